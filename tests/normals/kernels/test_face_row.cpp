// face_row (lib/normals/kernels/face_row.h) against face_terms, face by face, for every FaceWeight
// and axis: the same values bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "kernel_test_data.h"
#include "normals/kernels/exp_nonpositive.h"
#include "normals/kernels/face_row.h"
#include "normals/kernels/face_terms.h"

namespace normalflow::engine {
namespace {

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void check(FaceWeight w, int axis, unsigned seed) {
    std::mt19937 rng(seed);
    const float band = 3.0f, inv2mu2 = 50.0f;
    const std::vector<float> P = test::padded_phi(rng, 0.6f);
    std::vector<float> N = test::uniform(rng, 3 * L3, -1.0f, 1.0f);
    const std::vector<float> G = test::uniform(rng, L3, 0.0f, 1.0f);
    std::vector<float> F(3 * L3, -7.0f), E(L3, -7.0f);
    const float* Nc[3] = {N.data(), N.data() + L3, N.data() + 2 * L3};
    int lo[3] = {0, 0, 0};
    lo[axis] = -1;
    const int n = kBlockDim - lo[0];
    // one call per z plane, all its rows (rows > 1), as the engine calls the y and z faces
    for (int z = lo[2]; z < kBlockDim; ++z) {
        const int rows = kBlockDim - lo[1];
        const float* g = w == FaceWeight::Frozen ? G.data() : nullptr;
        switch (w) {
            case FaceWeight::One:
                face_rows<FaceWeight::One>(axis, P.data(), N.data(), g, lidx(lo[0], lo[1], z), n, rows, band, inv2mu2,
                                           F.data(), E.data());
                break;
            case FaceWeight::Frozen:
                face_rows<FaceWeight::Frozen>(axis, P.data(), N.data(), g, lidx(lo[0], lo[1], z), n, rows, band,
                                              inv2mu2, F.data(), E.data());
                break;
            case FaceWeight::Live:
                face_rows<FaceWeight::Live>(axis, P.data(), N.data(), g, lidx(lo[0], lo[1], z), n, rows, band, inv2mu2,
                                            F.data(), E.data());
                break;
        }
    }
    const int sa = kStride[axis], sb = kStride[(axis + 1) % 3], sc = kStride[(axis + 2) % 3];
    int outside = 0, inside = 0;
    for (int z = lo[2]; z < kBlockDim; ++z)
        for (int y = lo[1]; y < kBlockDim; ++y)
            for (int x = lo[0]; x < kBlockDim; ++x) {
                const int q = lidx(x, y, z);
                float m[3], k2;
                face_terms(P.data(), Nc, q, sa, sb, sc, m, k2);
                const bool keep = !(std::abs(P[q]) > band && std::abs(P[q + sa]) > band);
                (keep ? inside : outside)++;
                float g = keep ? 1.0f : 0.0f, e = k2;
                if (w == FaceWeight::Frozen) {
                    g = G[q] * g;
                    e = G[q] * k2;
                } else if (w == FaceWeight::Live) {
                    const float c = exp_nonpositive(-k2 * inv2mu2);
                    g = c * g;
                    e = (1.0f - c) * (1.0f / inv2mu2);
                }
                for (int c = 0; c < 3; ++c)
                    ASSERT_TRUE(same_bits(F[c * L3 + q], g * m[c])) << "F" << c << " at (" << x << "," << y << "," << z
                                                                    << "): " << F[c * L3 + q] << " vs " << g * m[c];
                ASSERT_TRUE(same_bits(E[q], e))
                    << "E at (" << x << "," << y << "," << z << "): " << E[q] << " vs " << e;
            }
    EXPECT_GT(inside, 20);  // both kinds of faces were tested
    EXPECT_GT(outside, 20);
}

class FaceRow : public ::testing::TestWithParam<std::tuple<FaceWeight, int>> {};

TEST_P(FaceRow, SameAsFaceTermsPerFace) {
    const auto [w, axis] = GetParam();
    for (unsigned seed = 1; seed <= 5; ++seed) check(w, axis, seed * 7919u + unsigned(axis));
}

INSTANTIATE_TEST_SUITE_P(AllWeightsAndAxes, FaceRow,
                         ::testing::Combine(::testing::Values(FaceWeight::One, FaceWeight::Frozen, FaceWeight::Live),
                                            ::testing::Values(0, 1, 2)));

}  // namespace
}  // namespace normalflow::engine
