// refit_row and refit_energy_row (lib/normals/kernels) against scalar loops.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "kernel_test_data.h"
#include "normals/kernels/refit_energy_row.h"
#include "normals/kernels/refit_row.h"

namespace normalflow::engine {
namespace {

/// The scalar refit step at padded index q: φ + dt |∇φ|_upwind (H_φ − hn).
float refit_sample(const float* P, int q, float hn, float dt) {
    float H = 0.0f, gp2 = 0.0f, gm2 = 0.0f;
    for (int a = 0; a < 3; ++a) {
        const int sa = kStride[a], sb = kStride[(a + 1) % 3], sc = kStride[(a + 2) % 3];
        const float p = P[q];
        const float dp = P[q + sa] - p;
        const float dm = p - P[q - sa];
        const float bp = 0.25f * ((P[q + sb] - P[q - sb]) + (P[q + sa + sb] - P[q + sa - sb]));
        const float cp = 0.25f * ((P[q + sc] - P[q - sc]) + (P[q + sa + sc] - P[q + sa - sc]));
        const float bm = 0.25f * ((P[q + sb] - P[q - sb]) + (P[q - sa + sb] - P[q - sa - sb]));
        const float cm = 0.25f * ((P[q + sc] - P[q - sc]) + (P[q - sa + sc] - P[q - sa - sc]));
        const float np = std::sqrt(dp * dp + bp * bp + cp * cp);
        const float nm = std::sqrt(dm * dm + bm * bm + cm * cm);
        H += dp / std::max(np, 1e-6f) - dm / std::max(nm, 1e-6f);
        gp2 += std::max(dm, 0.0f) * std::max(dm, 0.0f) + std::min(dp, 0.0f) * std::min(dp, 0.0f);
        gm2 += std::min(dm, 0.0f) * std::min(dm, 0.0f) + std::max(dp, 0.0f) * std::max(dp, 0.0f);
    }
    const float rhs = H - hn;
    const float grad = std::sqrt(rhs < 0.0f ? gp2 : gm2);
    return P[q] + dt * grad * rhs;
}

TEST(RefitRow, SameAsScalarLoop) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
        std::mt19937 rng(seed);
        const std::vector<float> P = test::padded_phi(rng, seed % 2 ? 0.3f : 1.5f);
        const std::vector<float> hn = test::uniform(rng, kBlockVoxels, -0.5f, 0.5f);
        const std::vector<std::uint8_t> m = test::random_mask(rng, 0.6);
        std::vector<float> got(kBlockVoxels, -9.0f), want(kBlockVoxels);
        int nonfinite = 0;
        for (int z = 0; z < kBlockDim; ++z)  // a plane per call, as the engine
            nonfinite |= refit_row(P.data() + lidx(0, 0, z), hn.data() + bidx(0, 0, z), m.data() + bidx(0, 0, z), 0.1f,
                                   kBlockDim, got.data() + bidx(0, 0, z));
        EXPECT_EQ(nonfinite, 0);
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x) {
                    const int q = lidx(x, y, z), i = bidx(x, y, z);
                    want[i] = m[i] ? refit_sample(P.data(), q, hn[i], 0.1f) : P[q];
                }
        ASSERT_EQ(std::memcmp(got.data(), want.data(), sizeof(float) * kBlockVoxels), 0) << "seed " << seed;
    }
}

TEST(RefitRateRow, IsTheStepOverDtAndZeroOffTheMask) {
    // The super steps' rate: the explicit step's increment per unit time, at the active samples.
    for (unsigned seed = 1; seed <= 20; ++seed) {
        std::mt19937 rng(seed);
        const std::vector<float> P = test::padded_phi(rng, seed % 2 ? 0.3f : 1.5f);
        const std::vector<float> hn = test::uniform(rng, kBlockVoxels, -0.5f, 0.5f);
        const std::vector<std::uint8_t> m = test::random_mask(rng, 0.6);
        std::vector<float> got(kBlockVoxels, -9.0f);
        int nonfinite = 0;
        for (int z = 0; z < kBlockDim; ++z)
            nonfinite |= refit_rate_row(P.data() + lidx(0, 0, z), hn.data() + bidx(0, 0, z), m.data() + bidx(0, 0, z),
                                        kBlockDim, got.data() + bidx(0, 0, z));
        EXPECT_EQ(nonfinite, 0);
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x) {
                    const int q = lidx(x, y, z), i = bidx(x, y, z);
                    if (!m[i]) {
                        ASSERT_EQ(got[i], 0.0f);
                        continue;
                    }
                    const float rate = (refit_sample(P.data(), q, hn[i], 1.0f) - P[q]);
                    ASSERT_NEAR(got[i], rate, 1e-5f * (1.0f + std::abs(P[q]))) << "seed " << seed;
                }
    }
}

TEST(RefitRow, ReportsNonFiniteAtActiveSamples) {
    std::mt19937 rng(5);
    const std::vector<float> P = test::padded_phi(rng, 0.3f);
    std::vector<float> hn(kBlockVoxels, 0.0f), out(kBlockVoxels);
    std::vector<std::uint8_t> m(kBlockVoxels, 0);
    m[bidx(3, 0, 0)] = 1;
    EXPECT_EQ(refit_row(P.data() + lidx(0, 0, 0), hn.data(), m.data(), 0.1f, 1, out.data()), 0);
    hn[bidx(3, 0, 0)] = std::numeric_limits<float>::infinity();
    EXPECT_EQ(refit_row(P.data() + lidx(0, 0, 0), hn.data(), m.data(), 0.1f, 1, out.data()), 1);
    m[bidx(3, 0, 0)] = 0;
    EXPECT_EQ(refit_row(P.data() + lidx(0, 0, 0), hn.data(), m.data(), 0.1f, 1, out.data()), 0);
}

TEST(RefitEnergyRow, SameAsScalarLoop) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
        std::mt19937 rng(seed);
        const std::vector<float> P = test::padded_phi(rng, 0.5f);
        std::vector<float> n[3];
        for (auto& c : n) c = test::uniform(rng, kBlockVoxels, -1.0f, 1.0f);
        const std::vector<std::uint8_t> m = test::random_mask(rng, 0.5);
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y) {
                const int q0 = lidx(0, y, z), i0 = bidx(0, y, z);
                double want = 0.0;
                for (int x = 0; x < kBlockDim; ++x) {
                    const int q = q0 + x;
                    const float gx = 0.5f * (P[q + 1] - P[q - 1]);
                    const float gy = 0.5f * (P[q + L] - P[q - L]);
                    const float gz = 0.5f * (P[q + L2] - P[q - L2]);
                    const float gnorm = std::sqrt(gx * gx + gy * gy + gz * gz);
                    const float gdot = gx * n[0][i0 + x] + gy * n[1][i0 + x] + gz * n[2][i0 + x];
                    if (m[i0 + x]) want += double(gnorm) - double(gdot);
                }
                const double got = refit_energy_row(P.data() + q0, m.data() + i0, n[0].data() + i0, n[1].data() + i0,
                                                    n[2].data() + i0);
                ASSERT_EQ(std::memcmp(&got, &want, sizeof got), 0) << "seed " << seed << " row " << y << "," << z;
            }
    }
}

}  // namespace
}  // namespace normalflow::engine
