// masked_block_sum (lib/normals/kernels/masked_block_sum.h) against a scalar loop with the same
// eight column sums and the same final tree, and the row-mask helpers (row_mask.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "kernel_test_data.h"
#include "normals/kernels/masked_block_sum.h"
#include "normals/kernels/row_mask.h"

namespace normalflow::engine {
namespace {

TEST(MaskedBlockSum, SameAsScalarColumnSums) {
    for (unsigned seed = 1; seed <= 30; ++seed) {
        std::mt19937 rng(seed);
        std::vector<float> E = test::uniform(rng, L3, 0.0f, 2.0f);
        const std::vector<std::uint8_t> m = test::random_mask(rng, 0.5);
        // masked-out samples may hold anything (stale values): they must not count
        for (int i = 0; i < kBlockVoxels; ++i)
            if (!m[i]) E[lidx(i % kBlockDim, (i / kBlockDim) % kBlockDim, i / (kBlockDim * kBlockDim))] = 1e30f;
        float acc[kBlockDim] = {};
        double plain = 0.0;
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x)
                    if (m[bidx(x, y, z)]) {
                        acc[x] += E[lidx(x, y, z)];
                        plain += E[lidx(x, y, z)];
                    }
        const double want = double(((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7])));
        const double got = masked_block_sum(E.data(), m.data());
        ASSERT_EQ(std::memcmp(&got, &want, sizeof got), 0) << "seed " << seed << ": " << got << " vs " << want;
        EXPECT_NEAR(got, plain, 1e-5 * plain);
    }
}

TEST(RowMask, WidenAnyAndSpan) {
    std::uint8_t m[kBlockDim] = {0, 0, 3, 0, 0, 1, 0, 0};
    std::int32_t w[kBlockDim];
    widen_mask(m, w);
    for (int x = 0; x < kBlockDim; ++x) EXPECT_EQ(w[x], m[x]);
    EXPECT_TRUE(any_in_row(m));
    const std::uint8_t none[kBlockDim] = {};
    EXPECT_FALSE(any_in_row(none));
    for (int x = 0; x < kBlockDim; ++x) {
        std::uint8_t one[kBlockDim] = {};
        one[x] = 1;
        EXPECT_TRUE(any_in_row(one)) << x;
    }
    const auto [y0, y1] = row_span(0, [&](int y) { return y == 2 || y == 5; });
    EXPECT_EQ(y0, 2);
    EXPECT_EQ(y1, 5);
    const auto [e0, e1] = row_span(-1, [](int) { return false; });
    EXPECT_LT(e1, e0);
    const auto [f0, f1] = row_span(-1, [](int y) { return y == -1; });
    EXPECT_EQ(f0, -1);
    EXPECT_EQ(f1, -1);
}

}  // namespace
}  // namespace normalflow::engine
