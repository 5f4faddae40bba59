#include "normals/kernels/face_row.h"

#include <algorithm>
#include <cmath>

#include "normals/kernels/exp_nonpositive.h"
#include "normals/kernels/row_kernel.h"

namespace normalflow::engine {

template <FaceWeight kWeight, int kAxis>
NF_ROW_KERNEL void face_row(const float* __restrict P, const float* __restrict N, const float* __restrict G, int q0,
                            int n, int rows, float band, float inv2mu2, float* __restrict F, float* __restrict E) {
    constexpr int sa = kStride[kAxis], sb = kStride[(kAxis + 1) % 3], sc = kStride[(kAxis + 2) % 3];
    const float* N0 = N;
    const float* N1 = N + L3;
    const float* N2 = N + 2 * L3;
    float* F0 = F;
    float* F1 = F + L3;
    float* F2 = F + 2 * L3;
    const float two_mu2 = 1.0f / inv2mu2;  // E of Live as a product: a division per face costs more
    for (int r = 0; r < rows; ++r) {
        for (int j = 0; j < n; ++j) {
            const int q = q0 + r * L + j;
            const int q1 = q + sa;
            const float dphi = P[q1] - P[q];
            const float gb = 0.25f * ((P[q + sb] - P[q - sb]) + (P[q1 + sb] - P[q1 - sb]));
            const float gc = 0.25f * ((P[q + sc] - P[q - sc]) + (P[q1 + sc] - P[q1 - sc]));
            const float g2 = dphi * dphi + gb * gb + gc * gc;
            const float inv = 1.0f / std::max(g2, 1e-12f);
            const float a0 = N0[q1] - N0[q];
            const float b0 = 0.25f * ((N0[q + sb] - N0[q - sb]) + (N0[q1 + sb] - N0[q1 - sb]));
            const float d0 = 0.25f * ((N0[q + sc] - N0[q - sc]) + (N0[q1 + sc] - N0[q1 - sc]));
            const float C0 = (a0 * dphi + b0 * gb + d0 * gc) * inv;
            const float a1 = N1[q1] - N1[q];
            const float b1 = 0.25f * ((N1[q + sb] - N1[q - sb]) + (N1[q1 + sb] - N1[q1 - sb]));
            const float d1 = 0.25f * ((N1[q + sc] - N1[q - sc]) + (N1[q1 + sc] - N1[q1 - sc]));
            const float C1 = (a1 * dphi + b1 * gb + d1 * gc) * inv;
            const float a2 = N2[q1] - N2[q];
            const float b2 = 0.25f * ((N2[q + sb] - N2[q - sb]) + (N2[q1 + sb] - N2[q1 - sb]));
            const float d2 = 0.25f * ((N2[q + sc] - N2[q - sc]) + (N2[q1 + sc] - N2[q1 - sc]));
            const float C2 = (a2 * dphi + b2 * gb + d2 * gc) * inv;
            const float dn2 =
                ((a0 * a0 + b0 * b0 + d0 * d0) + (a1 * a1 + b1 * b1 + d1 * d1)) + (a2 * a2 + b2 * b2 + d2 * d2);
            const float c2 = (C0 * C0 + C1 * C1) + C2 * C2;
            const float k2 = std::max(dn2 - c2 * g2, 0.0f);
            // a mask, not a branch (no short-circuit): the loop stays vectorisable
            const float keep = float(!(int(std::abs(P[q]) > band) & int(std::abs(P[q1]) > band)));
            float g = keep, e = k2;
            if constexpr (kWeight == FaceWeight::Frozen) {
                g = G[q] * keep;
                e = G[q] * k2;
            } else if constexpr (kWeight == FaceWeight::Live) {
                const float c = exp_nonpositive(-k2 * inv2mu2);
                g = c * keep;
                e = (1.0f - c) * two_mu2;
            }
            F0[q] = g * (a0 - dphi * C0);
            F1[q] = g * (a1 - dphi * C1);
            F2[q] = g * (a2 - dphi * C2);
            E[q] = e;
        }
    }
}

template void face_row<FaceWeight::One, 0>(const float* __restrict, const float* __restrict, const float* __restrict,
                                           int, int, int, float, float, float* __restrict, float* __restrict);
template void face_row<FaceWeight::One, 1>(const float* __restrict, const float* __restrict, const float* __restrict,
                                           int, int, int, float, float, float* __restrict, float* __restrict);
template void face_row<FaceWeight::One, 2>(const float* __restrict, const float* __restrict, const float* __restrict,
                                           int, int, int, float, float, float* __restrict, float* __restrict);
template void face_row<FaceWeight::Frozen, 0>(const float* __restrict, const float* __restrict, const float* __restrict,
                                              int, int, int, float, float, float* __restrict, float* __restrict);
template void face_row<FaceWeight::Frozen, 1>(const float* __restrict, const float* __restrict, const float* __restrict,
                                              int, int, int, float, float, float* __restrict, float* __restrict);
template void face_row<FaceWeight::Frozen, 2>(const float* __restrict, const float* __restrict, const float* __restrict,
                                              int, int, int, float, float, float* __restrict, float* __restrict);
template void face_row<FaceWeight::Live, 0>(const float* __restrict, const float* __restrict, const float* __restrict,
                                            int, int, int, float, float, float* __restrict, float* __restrict);
template void face_row<FaceWeight::Live, 1>(const float* __restrict, const float* __restrict, const float* __restrict,
                                            int, int, int, float, float, float* __restrict, float* __restrict);
template void face_row<FaceWeight::Live, 2>(const float* __restrict, const float* __restrict, const float* __restrict,
                                            int, int, int, float, float, float* __restrict, float* __restrict);

}  // namespace normalflow::engine
