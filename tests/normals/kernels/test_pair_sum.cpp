// pair_sum (lib/normals/kernels) against a scalar loop with std::exp: the sums of the bilateral
// weights over spans of surface samples, padding and samples beyond the disc weighing nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "normals/kernels/pair_sum.h"

namespace normalflow::engine {
namespace {

TEST(PairSum, SameAsScalarLoopOverSeveralSpans) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> pos(-6.0f, 6.0f), unit(-1.0f, 1.0f);
    const int n = 8 * 40;
    std::vector<float> p[3], r[3], v[3];
    for (int c = 0; c < 3; ++c)
        for (int j = 0; j < n; ++j) {
            p[c].push_back(pos(rng));
            r[c].push_back(unit(rng));
            v[c].push_back(unit(rng));
        }
    for (int j = 8 * 7 + 5; j < 8 * 8; ++j)  // padding at the end of one span: far away
        for (int c = 0; c < 3; ++c) p[c][std::size_t(j)] = 1.0e9f;
    const PairArrays a{{p[0].data(), p[1].data(), p[2].data()},
                       {r[0].data(), r[1].data(), r[2].data()},
                       {v[0].data(), v[1].data(), v[2].data()}};
    const PairSpan spans[] = {{0, 64}, {96, 16}, {200, 120}};  // samples 64–95 and 112–199 left out
    const float q[3] = {0.5f, -0.25f, 1.0f}, rq[3] = {0.2f, 0.1f, -0.3f};
    const float ks = 0.06f, kr = 4.0f, r2 = 25.0f;
    float acc[32] = {};
    pair_sum(a, spans, 3, q, rq, ks, kr, r2, acc);
    double want[4] = {0, 0, 0, 0};
    int inside = 0;
    for (const PairSpan& s : spans)
        for (std::int64_t j = s.begin; j < s.begin + s.n; ++j) {
            const std::size_t J = std::size_t(j);
            double d2 = 0, c2 = 0;
            for (int c = 0; c < 3; ++c) {
                d2 += double(p[c][J] - q[c]) * double(p[c][J] - q[c]);
                c2 += double(r[c][J] - rq[c]) * double(r[c][J] - rq[c]);
            }
            if (d2 > r2) continue;
            ++inside;
            const double w = std::exp(-(ks * d2 + kr * c2));
            for (int c = 0; c < 3; ++c) want[c] += w * v[c][J];
            want[3] += w;
        }
    ASSERT_GT(inside, 20);  // the disc holds samples, and some lie beyond it
    for (int c = 0; c < 4; ++c) {
        double got = 0;
        for (int l = 0; l < 8; ++l) got += acc[8 * c + l];
        EXPECT_NEAR(got, want[c], 1e-5 * (1.0 + std::abs(want[3]))) << "component " << c;
    }
    // no spans: nothing added
    float none[32] = {};
    pair_sum(a, spans, 0, q, rq, ks, kr, r2, none);
    for (const float x : none) EXPECT_EQ(x, 0.0f);
}

}  // namespace
}  // namespace normalflow::engine
