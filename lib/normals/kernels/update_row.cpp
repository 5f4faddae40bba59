#include "normals/kernels/update_row.h"

#include <cmath>
#include <limits>

#include "normals/kernels/row_kernel.h"
#include "normals/kernels/row_mask.h"

namespace normalflow::engine {

NF_ROW_KERNEL int update_row(const float* __restrict fx0, const float* __restrict fx1, const float* __restrict fx2,
                             const float* __restrict fy0, const float* __restrict fy1, const float* __restrict fy2,
                             const float* __restrict fz0, const float* __restrict fz1, const float* __restrict fz2,
                             const float* __restrict n0, const float* __restrict n1, const float* __restrict n2,
                             const std::uint8_t* __restrict m, float dt, int rows, float* __restrict d0,
                             float* __restrict d1, float* __restrict d2) {
    int nonfinite = 0;
    for (int r = 0; r < rows; ++r, fx0 += L, fx1 += L, fx2 += L, fy0 += L, fy1 += L, fy2 += L, fz0 += L, fz1 += L,
             fz2 += L, n0 += L, n1 += L, n2 += L, m += kBlockDim, d0 += kBlockDim, d1 += kBlockDim, d2 += kBlockDim) {
        std::int32_t mi[kBlockDim];
        widen_mask(m, mi);
        for (int x = 0; x < kBlockDim; ++x) {
            const float v0 = (fx0[x] - fx0[x - 1]) + (fy0[x] - fy0[x - L]) + (fz0[x] - fz0[x - L2]);
            const float v1 = (fx1[x] - fx1[x - 1]) + (fy1[x] - fy1[x - L]) + (fz1[x] - fz1[x - L2]);
            const float v2 = (fx2[x] - fx2[x - 1]) + (fy2[x] - fy2[x - L]) + (fz2[x] - fz2[x - L2]);
            const float nx = n0[x], ny = n1[x], nz = n2[x];
            const float pn = v0 * nx + v1 * ny + v2 * nz;
            const float ux = nx + dt * (v0 - pn * nx);
            const float uy = ny + dt * (v1 - pn * ny);
            const float uz = nz + dt * (v2 - pn * nz);
            const float len = std::sqrt(ux * ux + uy * uy + uz * uz);
            const bool act = mi[x] != 0;
            nonfinite |= int(act & !(len <= std::numeric_limits<float>::max()));
            const float div = len > 1e-6f ? len : 1.0f;
            d0[x] = act ? ux / div : nx;
            d1[x] = act ? uy / div : ny;
            d2[x] = act ? uz / div : nz;
        }
    }
    return nonfinite;
}

}  // namespace normalflow::engine
