#include "normals/kernels/refit_energy_row.h"

#include <cmath>

#include "normals/kernels/row_kernel.h"
#include "normals/kernels/row_mask.h"

namespace normalflow::engine {

NF_ROW_KERNEL double refit_energy_row(const float* __restrict P, const std::uint8_t* __restrict m,
                                      const float* __restrict n0, const float* __restrict n1,
                                      const float* __restrict n2) {
    float gnorm[kBlockDim], gdot[kBlockDim];
    for (int x = 0; x < kBlockDim; ++x) {  // vectorised
        const float gx = 0.5f * (P[x + 1] - P[x - 1]);
        const float gy = 0.5f * (P[x + L] - P[x - L]);
        const float gz = 0.5f * (P[x + L2] - P[x - L2]);
        gnorm[x] = std::sqrt(gx * gx + gy * gy + gz * gz);
        gdot[x] = gx * n0[x] + gy * n1[x] + gz * n2[x];
    }
    double e = 0.0;
    for (int x = 0; x < kBlockDim; ++x)
        if (m[x]) e += double(gnorm[x]) - double(gdot[x]);
    return e;
}

}  // namespace normalflow::engine
