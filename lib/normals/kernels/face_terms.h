#pragma once
/// \file face_terms.h
/// The terms of one face of the normal loop, scalar: the reference face_row follows and the
/// scalar paths (the curvature noise scale) use.

#include <algorithm>

namespace normalflow::engine {

/// Face terms at the staggered point q + ½e_a (Appendix B, Eq. 43–47, 50): flux column m and κ².
inline void face_terms(const float* P, const float* const N[3], int q, int sa, int sb, int sc, float m[3], float& k2) {
    const int q1 = q + sa;
    const float dphi = P[q1] - P[q];
    const float gb = 0.25f * ((P[q + sb] - P[q - sb]) + (P[q1 + sb] - P[q1 - sb]));
    const float gc = 0.25f * ((P[q + sc] - P[q - sc]) + (P[q1 + sc] - P[q1 - sc]));
    const float g2 = dphi * dphi + gb * gb + gc * gc;
    const float inv = 1.0f / std::max(g2, 1e-12f);
    float dn2 = 0.0f, c2 = 0.0f;
    for (int c = 0; c < 3; ++c) {
        const float* Nc = N[c];
        const float a = Nc[q1] - Nc[q];
        const float b = 0.25f * ((Nc[q + sb] - Nc[q - sb]) + (Nc[q1 + sb] - Nc[q1 - sb]));
        const float d = 0.25f * ((Nc[q + sc] - Nc[q - sc]) + (Nc[q1 + sc] - Nc[q1 - sc]));
        const float C = (a * dphi + b * gb + d * gc) * inv;
        m[c] = a - dphi * C;
        dn2 += a * a + b * b + d * d;
        c2 += C * C;
    }
    k2 = std::max(dn2 - c2 * g2, 0.0f);
}

}  // namespace normalflow::engine
