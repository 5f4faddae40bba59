#pragma once
/// \file masked_block_sum.h
/// The energy sum of the normal loop over one block.

#include <cstdint>

#include "band/layout.h"

namespace normalflow::engine {

/// Σ m·E over the 8³ samples of a block (E in the padded layout, m in the block's): eight lanes,
/// each summing its column over the rows in order, then a fixed tree; so the same on every thread
/// and vector width. A mask, not a product: E holds stale values where m is 0. Written with vector
/// types because GCC 12 leaves the eight column sums scalar, with a branch per sample.
double masked_block_sum(const float* __restrict E, const std::uint8_t* __restrict m);

}  // namespace normalflow::engine
