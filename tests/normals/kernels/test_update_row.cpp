// update_row (lib/normals/kernels/update_row.h) against a scalar loop.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "kernel_test_data.h"
#include "normals/kernels/update_row.h"

namespace normalflow::engine {
namespace {

struct Inputs {
    std::vector<float> F[3][3];  // F[a][c]: flux component c through the faces x+½e_a (padded)
    std::vector<float> N[3];     // padded
    std::vector<std::uint8_t> m;
};

Inputs make(unsigned seed) {
    std::mt19937 rng(seed);
    Inputs in;
    for (auto& fa : in.F)
        for (auto& f : fa) f = test::uniform(rng, L3, -0.5f, 0.5f);
    for (auto& n : in.N) n = test::uniform(rng, L3, -1.0f, 1.0f);
    in.m = test::random_mask(rng, 0.6);
    return in;
}

/// The scalar update of one sample: N ← normalize(N + dt (I − NNᵀ) ∇·F) where active, else N.
void reference(const Inputs& in, float dt, std::vector<float> (&d)[3], int& nonfinite) {
    nonfinite = 0;
    for (int z = 0; z < kBlockDim; ++z)
        for (int y = 0; y < kBlockDim; ++y)
            for (int x = 0; x < kBlockDim; ++x) {
                const int q = lidx(x, y, z), i = bidx(x, y, z);
                float v[3];
                for (int c = 0; c < 3; ++c)
                    v[c] = (in.F[0][c][q] - in.F[0][c][q - 1]) + (in.F[1][c][q] - in.F[1][c][q - L]) +
                           (in.F[2][c][q] - in.F[2][c][q - L2]);
                const float nx = in.N[0][q], ny = in.N[1][q], nz = in.N[2][q];
                const float pn = v[0] * nx + v[1] * ny + v[2] * nz;
                const float u[3] = {nx + dt * (v[0] - pn * nx), ny + dt * (v[1] - pn * ny), nz + dt * (v[2] - pn * nz)};
                const float len = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
                if (!in.m[i]) {
                    d[0][i] = nx, d[1][i] = ny, d[2][i] = nz;
                    continue;
                }
                if (!(len <= std::numeric_limits<float>::max())) nonfinite = 1;
                const float div = len > 1e-6f ? len : 1.0f;
                for (int c = 0; c < 3; ++c) d[c][i] = u[c] / div;
            }
}

int run_kernel(const Inputs& in, float dt, std::vector<float> (&d)[3]) {
    int nonfinite = 0;
    for (int z = 0; z < kBlockDim; ++z) {  // a plane per call, as the engine
        const int q0 = lidx(0, 0, z), i0 = bidx(0, 0, z);
        nonfinite |=
            update_row(in.F[0][0].data() + q0, in.F[0][1].data() + q0, in.F[0][2].data() + q0, in.F[1][0].data() + q0,
                       in.F[1][1].data() + q0, in.F[1][2].data() + q0, in.F[2][0].data() + q0, in.F[2][1].data() + q0,
                       in.F[2][2].data() + q0, in.N[0].data() + q0, in.N[1].data() + q0, in.N[2].data() + q0,
                       in.m.data() + i0, dt, kBlockDim, d[0].data() + i0, d[1].data() + i0, d[2].data() + i0);
    }
    return nonfinite;
}

TEST(UpdateRow, SameAsScalarLoop) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
        const Inputs in = make(seed);
        std::vector<float> got[3], want[3];
        for (int c = 0; c < 3; ++c) got[c].assign(kBlockVoxels, -9.0f), want[c].assign(kBlockVoxels, -9.0f);
        int nf_want = 0;
        reference(in, 0.1f, want, nf_want);
        EXPECT_EQ(run_kernel(in, 0.1f, got), nf_want);
        for (int c = 0; c < 3; ++c)
            ASSERT_EQ(std::memcmp(got[c].data(), want[c].data(), sizeof(float) * kBlockVoxels), 0)
                << "seed " << seed << " component " << c;
    }
}

TEST(UpdateRow, ReportsNonFiniteOnlyAtActiveSamples) {
    Inputs in = make(99);
    std::vector<float> d[3];
    for (auto& v : d) v.assign(kBlockVoxels, 0.0f);
    int active = -1, inactive = -1;
    for (int i = 0; i < kBlockVoxels; ++i) (in.m[i] ? active : inactive) = i;
    ASSERT_GE(active, 0);
    ASSERT_GE(inactive, 0);
    auto at = [](int i) { return lidx(i % kBlockDim, (i / kBlockDim) % kBlockDim, i / (kBlockDim * kBlockDim)); };
    in.N[0][at(inactive)] = std::numeric_limits<float>::infinity();
    EXPECT_EQ(run_kernel(in, 0.1f, d), 0);
    in.N[1][at(active)] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(run_kernel(in, 0.1f, d), 1);
}

}  // namespace
}  // namespace normalflow::engine
