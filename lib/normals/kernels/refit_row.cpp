#include "normals/kernels/refit_row.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "normals/kernels/row_kernel.h"
#include "normals/kernels/row_mask.h"

namespace normalflow::engine {

namespace {

/// The refit terms of one axis at the samples of a row: H_φ's staggered part (Eq. 54), the
/// upwind squared gradients for F > 0 / F < 0.
template <int sa, int sb, int sc>
inline void refit_axis(const float* __restrict P, int x, float& H, float& gp2, float& gm2) {
    const float p = P[x];
    const float dp = P[x + sa] - p;
    const float dm = p - P[x - sa];
    const float bp = 0.25f * ((P[x + sb] - P[x - sb]) + (P[x + sa + sb] - P[x + sa - sb]));
    const float cp = 0.25f * ((P[x + sc] - P[x - sc]) + (P[x + sa + sc] - P[x + sa - sc]));
    const float bm = 0.25f * ((P[x + sb] - P[x - sb]) + (P[x - sa + sb] - P[x - sa - sb]));
    const float cm = 0.25f * ((P[x + sc] - P[x - sc]) + (P[x - sa + sc] - P[x - sa - sc]));
    const float np = std::sqrt(dp * dp + bp * bp + cp * cp);
    const float nm = std::sqrt(dm * dm + bm * bm + cm * cm);
    H += dp / std::max(np, 1e-6f) - dm / std::max(nm, 1e-6f);
    const float dmp = std::max(dm, 0.0f), dmn = std::min(dm, 0.0f);
    const float dpp = std::max(dp, 0.0f), dpn = std::min(dp, 0.0f);
    gp2 += dmp * dmp + dpn * dpn;
    gm2 += dmn * dmn + dpp * dpp;
}

/// The refit over `rows` rows: out = φ + dt·|∇φ|(H_φ − hn) (Rate false) or |∇φ|(H_φ − hn) (Rate
/// true) at the active samples; φ, or 0, elsewhere. Returns 1 if an active result is not finite.
template <bool Rate>
inline int refit_rows(const float* __restrict P, const float* __restrict hn, const std::uint8_t* __restrict m, float dt,
                      int rows, float* __restrict out) {
    int nonfinite = 0;
    for (int r = 0; r < rows; ++r, P += L, hn += kBlockDim, m += kBlockDim, out += kBlockDim) {
        std::int32_t mi[kBlockDim];
        widen_mask(m, mi);
        for (int x = 0; x < kBlockDim; ++x) {
            float H = 0.0f, gp2 = 0.0f, gm2 = 0.0f;
            refit_axis<kStride[0], kStride[1], kStride[2]>(P, x, H, gp2, gm2);
            refit_axis<kStride[1], kStride[2], kStride[0]>(P, x, H, gp2, gm2);
            refit_axis<kStride[2], kStride[0], kStride[1]>(P, x, H, gp2, gm2);
            const float rhs = H - hn[x];  // φ_t = |∇φ| rhs, speed F = −rhs
            const float grad = std::sqrt(rhs < 0.0f ? gp2 : gm2);
            const float v = Rate ? grad * rhs : P[x] + dt * grad * rhs;
            const bool act = mi[x] != 0;
            nonfinite |= int(act & !(std::abs(v) <= std::numeric_limits<float>::max()));
            out[x] = act ? v : (Rate ? 0.0f : P[x]);
        }
    }
    return nonfinite;
}

}  // namespace

NF_ROW_KERNEL int refit_row(const float* __restrict P, const float* __restrict hn, const std::uint8_t* __restrict m,
                            float dt, int rows, float* __restrict out) {
    return refit_rows<false>(P, hn, m, dt, rows, out);
}

NF_ROW_KERNEL int refit_rate_row(const float* __restrict P, const float* __restrict hn,
                                 const std::uint8_t* __restrict m, int rows, float* __restrict out) {
    return refit_rows<true>(P, hn, m, 0.0f, rows, out);
}

}  // namespace normalflow::engine
