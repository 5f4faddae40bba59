#pragma once
/// \file face_row.h
/// The face kernel of the normal loop (Appendix B's staggered fluxes).

#include "band/layout.h"

namespace normalflow::engine {

/// How a normal step weighs the flux of a face: 1 (isotropic), a conductance g held for the whole
/// normal loop, or the paper's g = exp(−κ²/(2µ²)) of the current normals.
enum class FaceWeight { One, Frozen, Live };

/// face_terms over `rows` rows of faces q0 + r·L … q0 + r·L + n−1 (each contiguous in x; rows of 8,
/// or one run across a plane for the x faces), branch-free so that the compiler vectorises it. Rows
/// are passed several at a time because one row of 8 is one vector iteration whose dependency
/// chain (the division, the exp) would otherwise stall on its own. The same operations in the
/// same order as face_terms, so the results are bit-identical. F = g·m, or 0 where both samples of the face lie outside the band (the faces the
/// engine skips); g = 1, G[q] or exp(−κ²·inv2mu2) by kWeight. E = the face's energy density: κ²,
/// G[q]·κ² or (1 − g)·2µ² (the penalty G(κ²) of Eq. 20, as a product where penalty() divides: the
/// reported G may differ in the last bit, the normals do not).
/// N holds the three components L3 apart, F likewise (the kernels' scratch layout), and the axis
/// is a template argument: every load and store is then a fixed offset from one of five pointers,
/// which leaves the registers to the arithmetic (with run-time strides and a pointer per component,
/// a third of the loop's instructions were address arithmetic and stack reloads).
template <FaceWeight kWeight, int kAxis>
void face_row(const float* __restrict P, const float* __restrict N, const float* __restrict G, int q0, int n, int rows,
              float band, float inv2mu2, float* __restrict F, float* __restrict E);

// Defined in face_row.cpp, which instantiates it for every weight and axis (each built for AVX2
// and the baseline, see row_kernel.h).

/// face_row for the faces x+½e_axis.
template <FaceWeight kWeight>
inline void face_rows(int axis, const float* P, const float* N, const float* G, int q0, int n, int rows, float band,
                      float inv2mu2, float* F, float* E) {
    switch (axis) {
        case 0: face_row<kWeight, 0>(P, N, G, q0, n, rows, band, inv2mu2, F, E); break;
        case 1: face_row<kWeight, 1>(P, N, G, q0, n, rows, band, inv2mu2, F, E); break;
        default: face_row<kWeight, 2>(P, N, G, q0, n, rows, band, inv2mu2, F, E); break;
    }
}

}  // namespace normalflow::engine
