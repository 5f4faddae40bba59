#include "normals/kernels/eikonal_block.h"

#include <algorithm>
#include <cmath>

#include "normals/kernels/row_kernel.h"
#include "normals/kernels/row_mask.h"

namespace normalflow::engine {

NF_ROW_KERNEL int eikonal_block(const float* __restrict U0, const std::uint8_t* __restrict m0, float limit,
                                float* __restrict out0) {
    int changed = 0;
    for (int r = 0; r < kBlockDim * kBlockDim; ++r) {
        const int q0 = lidx(0, r % kBlockDim, r / kBlockDim);
        const float* U = U0 + q0;
        float* out = out0 + q0;
        std::int32_t mi[kBlockDim];
        widen_mask(m0 + r * kBlockDim, mi);
        for (int x = 0; x < kBlockDim; ++x) {
            const float c = U[x];
            float a0 = std::min(U[x - 1], U[x + 1]);
            float a1 = std::min(U[x - L], U[x + L]);
            float a2 = std::min(U[x - L2], U[x + L2]);
            const float s01 = std::min(a0, a1), l01 = std::max(a0, a1);
            a0 = s01;
            a1 = std::min(l01, a2);
            a2 = std::max(l01, a2);
            const float s0 = std::min(a0, a1);
            a1 = std::max(a0, a1);
            a0 = s0;
            const float d1 = a0 + 1.0f;
            const float s2 = a0 + a1;
            const float dd = a0 - a1;
            const float d2 = 0.5f * (s2 + std::sqrt(std::max(2.0f - dd * dd, 0.0f)));
            const float s3 = a0 + a1 + a2;
            const float q2 = a0 * a0 + a1 * a1 + a2 * a2;
            const float d3 = (s3 + std::sqrt(std::max(s3 * s3 - 3.0f * (q2 - 1.0f), 0.0f))) / 3.0f;
            const float d = d1 > a1 ? (d2 > a2 ? d3 : d2) : d1;
            const float nu = std::min(c, d);
            const bool fixed = mi[x] != 0;
            changed |= int(!fixed & (c - nu > kReinitTolerance) & (nu < limit));
            out[x] = fixed ? c : nu;
        }
    }
    return changed;
}

}  // namespace normalflow::engine
