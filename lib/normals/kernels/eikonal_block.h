#pragma once
/// \file eikonal_block.h
/// The reinitialisation's Jacobi pass over one block.

#include <cstdint>

#include "band/layout.h"

namespace normalflow::engine {

/// One Jacobi pass of the unsigned distance over the 8³ samples of a block, row by row in one call
/// (a row is one vector iteration whose sorting network and roots would otherwise stall alone; see
/// face_row): where m is set the sample is fixed (out = U), elsewhere out = min(U, the Godunov
/// upwind solution of |∇u| = 1 from the smaller neighbour per axis, h = 1). U and out: the padded
/// local buffers, m in the block's layout.
/// Branch-free (a sorting network and selects) so that it vectorises; the same values as solving
/// with the sorted neighbours a0 <= a1 <= a2 in turn: a0 + 1, then the 2-D, then the 3-D root.
/// Returns 1 when a free sample decreased by more than kReinitTolerance to below limit (a value
/// depends only on smaller ones, so the samples below limit converge whatever happens above it).
int eikonal_block(const float* __restrict U0, const std::uint8_t* __restrict m0, float limit, float* __restrict out0);

}  // namespace normalflow::engine
