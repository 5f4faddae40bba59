#pragma once
/// \file update_row.h
/// The update of the normal loop.

#include <cstdint>

#include "band/layout.h"

namespace normalflow::engine {

/// The update of `rows` consecutive rows of 8 samples of the normal loop (stride L in the padded
/// buffers, kBlockDim in m and d): N ← normalize(N + dt (I − NNᵀ) ∇·F) where m (the active samples),
/// N elsewhere. f<a><c>: flux component c through the faces x+½e_a of the row (the face below a
/// sample is at −1, −L, −L² from it); n<c>: the normals. Branch-free (selects) and with restrict
/// parameters so that it vectorises. Returns 1 if an active result is not finite.
int update_row(const float* __restrict fx0, const float* __restrict fx1, const float* __restrict fx2,
               const float* __restrict fy0, const float* __restrict fy1, const float* __restrict fy2,
               const float* __restrict fz0, const float* __restrict fz1, const float* __restrict fz2,
               const float* __restrict n0, const float* __restrict n1, const float* __restrict n2,
               const std::uint8_t* __restrict m, float dt, int rows, float* __restrict d0, float* __restrict d1,
               float* __restrict d2);

}  // namespace normalflow::engine
