#pragma once
/// \file refit_row.h
/// The refit step's kernel (Eq. 17, 53–54).

#include <cstdint>

#include "band/layout.h"

namespace normalflow::engine {

/// One refit step on `rows` consecutive rows of 8 samples (one call per plane: see face_row):
/// out = φ + dt |∇φ|_upwind (H_φ − hn) where m (the active samples), φ elsewhere. P points at the
/// first row's first sample in the padded local buffer (rows L apart; hn, m, out kBlockDim apart).
/// Branch-free, so that it vectorises.
/// Returns 1 if an active result is not finite.
int refit_row(const float* __restrict P, const float* __restrict hn, const std::uint8_t* __restrict m, float dt,
              int rows, float* __restrict out);

/// The refit's rate at the samples of `rows` rows: out = |∇φ|_upwind (H_φ − hn) where m, 0
/// elsewhere (the stages of the super-time-stepping refit). Layout as refit_row.
/// Returns 1 if an active result is not finite.
int refit_rate_row(const float* __restrict P, const float* __restrict hn, const std::uint8_t* __restrict m, int rows,
                   float* __restrict out);

}  // namespace normalflow::engine
