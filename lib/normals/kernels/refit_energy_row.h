#pragma once
/// \file refit_energy_row.h
/// The refit energy D of one row.

#include <cstdint>

#include "band/layout.h"

namespace normalflow::engine {

/// The refit energy D = Σ (|∇φ| − ∇φ·N) over the active samples of a row of 8 (central differences,
/// P at the row's first sample in the padded local buffer), summed in x order: the refit's steps
/// and refit_energy() give the same D for the same φ.
double refit_energy_row(const float* __restrict P, const std::uint8_t* __restrict m, const float* __restrict n0,
                        const float* __restrict n1, const float* __restrict n2);

}  // namespace normalflow::engine
