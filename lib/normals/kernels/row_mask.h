#pragma once
/// \file row_mask.h
/// Helpers of the row kernels over a block's active mask (one byte per sample, rows of 8).

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <utility>

#include "band/layout.h"

namespace normalflow::engine {

/// The mask of a row as 32-bit lanes: with 8-bit lanes GCC 12 vectorises a row of 8 at 128 bits
/// only, even for AVX2; with 32-bit ones at 256.
inline void widen_mask(const std::uint8_t* __restrict m, std::int32_t* __restrict out) {
    for (int x = 0; x < kBlockDim; ++x) out[x] = m[x];
}

/// Whether a row of 8 mask bytes has any set.
inline bool any_in_row(const std::uint8_t* m) {
    std::uint64_t w;
    std::memcpy(&w, m, sizeof w);
    return w != 0;
}

/// The first and the last y in [lo, kBlockDim) for which has(y) holds, as {y0, y1}; y1 < y0 when
/// none does. The kernels take the rows y0 … y1 of a plane in one call.
template <class Has>
std::pair<int, int> row_span(int lo, Has&& has) {
    int y0 = kBlockDim, y1 = lo - 1;
    for (int y = lo; y < kBlockDim; ++y)
        if (has(y)) {
            y0 = std::min(y0, y);
            y1 = y;
        }
    return {y0, y1};
}

}  // namespace normalflow::engine
