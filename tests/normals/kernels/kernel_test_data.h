#pragma once
// Random inputs in the engine's layouts (band/layout.h) for the row kernels' tests.
#include <cstdint>
#include <random>
#include <vector>

#include "band/layout.h"

namespace normalflow::engine::test {

/// n floats uniform in [lo, hi).
inline std::vector<float> uniform(std::mt19937& rng, std::size_t n, float lo, float hi) {
    std::uniform_real_distribution<float> d(lo, hi);
    std::vector<float> v(n);
    for (auto& x : v) x = d(rng);
    return v;
}

/// A block's mask (kBlockVoxels bytes) with about a fraction p of the samples set, whole empty
/// rows included.
inline std::vector<std::uint8_t> random_mask(std::mt19937& rng, double p) {
    std::bernoulli_distribution on(p), empty_row(0.25);
    std::vector<std::uint8_t> m(kBlockVoxels);
    for (int r = 0; r < kBlockDim * kBlockDim; ++r) {
        const bool empty = empty_row(rng);
        for (int x = 0; x < kBlockDim; ++x) m[r * kBlockDim + x] = !empty && on(rng);
    }
    return m;
}

/// A padded φ (L³) that is a signed distance to a plane plus noise: gradients near unit length,
/// magnitudes across [−6, 6].
inline std::vector<float> padded_phi(std::mt19937& rng, float noise) {
    std::uniform_real_distribution<float> d(-1.0f, 1.0f);
    const float nx = 0.48f, ny = 0.6f, nz = 0.64f;  // unit
    const float off = 4.0f * d(rng);
    std::vector<float> P(L3);
    for (int z = -1; z <= kBlockDim; ++z)
        for (int y = -1; y <= kBlockDim; ++y)
            for (int x = -1; x <= kBlockDim; ++x)
                P[lidx(x, y, z)] = nx * x + ny * y + nz * z - off - 4.0f + noise * d(rng);
    return P;
}

}  // namespace normalflow::engine::test
