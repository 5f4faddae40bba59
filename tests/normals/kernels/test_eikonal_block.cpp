// eikonal_block (lib/normals/kernels/eikonal_block.h) against a scalar Godunov update with the
// neighbours sorted by std::sort.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "kernel_test_data.h"
#include "normals/kernels/eikonal_block.h"

namespace normalflow::engine {
namespace {

/// One Jacobi pass at padded index q: min(U, the upwind solution of |∇u| = 1 from the smaller
/// neighbour per axis: a0 + 1, else the 2-D root, else the 3-D root).
float godunov(const float* U, int q) {
    float a[3] = {std::min(U[q - 1], U[q + 1]), std::min(U[q - L], U[q + L]), std::min(U[q - L2], U[q + L2])};
    std::sort(a, a + 3);
    float d = a[0] + 1.0f;
    if (d > a[1]) {
        const float dd = a[0] - a[1];
        d = 0.5f * ((a[0] + a[1]) + std::sqrt(std::max(2.0f - dd * dd, 0.0f)));
        if (d > a[2]) {
            const float s3 = a[0] + a[1] + a[2];
            const float q2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
            d = (s3 + std::sqrt(std::max(s3 * s3 - 3.0f * (q2 - 1.0f), 0.0f))) / 3.0f;
        }
    }
    return std::min(U[q], d);
}

TEST(EikonalBlock, SameAsScalarGodunovPass) {
    const float limit = 5.0f;
    for (unsigned seed = 1; seed <= 30; ++seed) {
        std::mt19937 rng(seed);
        // distances to a plane, some raised (not yet converged), some fixed
        std::vector<float> U = test::padded_phi(rng, 0.0f);
        std::uniform_real_distribution<float> raise(0.0f, 3.0f);
        std::bernoulli_distribution raised(0.5);
        for (auto& u : U) u = std::min(std::abs(u) + (raised(rng) ? raise(rng) : 0.0f), kHalfWidth);
        const std::vector<std::uint8_t> m = test::random_mask(rng, 0.15);
        std::vector<float> got(L3, -1.0f);
        const int changed = eikonal_block(U.data(), m.data(), limit, got.data());
        int want_changed = 0;
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x) {
                    const int q = lidx(x, y, z);
                    const bool fixed = m[bidx(x, y, z)] != 0;
                    const float want = fixed ? U[q] : godunov(U.data(), q);
                    if (!fixed && U[q] - want > kReinitTolerance && want < limit) want_changed = 1;
                    ASSERT_EQ(std::memcmp(&got[q], &want, sizeof want), 0)
                        << "seed " << seed << " at (" << x << "," << y << "," << z << "): " << got[q] << " vs " << want;
                }
        EXPECT_EQ(changed, want_changed) << "seed " << seed;
    }
}

TEST(EikonalBlock, SettledBlockReportsNoChange) {
    // exact distances to the plane x = −1.5: a pass changes nothing
    std::vector<float> U(L3);
    for (int z = -1; z <= kBlockDim; ++z)
        for (int y = -1; y <= kBlockDim; ++y)
            for (int x = -1; x <= kBlockDim; ++x) U[lidx(x, y, z)] = float(x) + 1.5f;
    std::vector<std::uint8_t> m(kBlockVoxels, 0);
    std::vector<float> out(L3);
    EXPECT_EQ(eikonal_block(U.data(), m.data(), kHalfWidth, out.data()), 0);
    for (int x = 0; x < kBlockDim; ++x) EXPECT_EQ(out[lidx(x, 3, 3)], float(x) + 1.5f);
}

}  // namespace
}  // namespace normalflow::engine
