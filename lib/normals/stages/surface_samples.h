#pragma once
/// \file surface_samples.h
/// The samples of the band next to the surface as a point set on it, for the filters that
/// average over a neighbourhood of fixed size in the model's units (bilateral.cpp): each sample
/// with |φ| <= tau, moved to its closest point on the zero level, x − φ·∇φ/|∇φ|, with its
/// normal. Grouped by block (slot order), each block's run padded to a multiple of 8 samples far
/// away, so that kernels/pair_sum runs over whole runs; the blocks within reach of each block are
/// listed. Everything is in a fixed order, so sums over it do not depend on the threads.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "band/band.h"
#include "band/layout.h"
#include "normals/kernels/pair_sum.h"

namespace normalflow::engine {

class SurfaceSamples {
public:
    static constexpr std::size_t kPadding = std::numeric_limits<std::size_t>::max();

    /// The samples of the active mask with |φ| <= tau, their closest points and the normals in
    /// `normals` (unit, made from φ); for every active block, the blocks whose samples may lie
    /// within `reach` voxels of a point within `margin` voxels of the block.
    void build(const Band& band, const Field3& normals, float tau, float reach, float margin);

    std::size_t size() const { return index.size(); }
    /// The samples of block slot b: [begin(b), end(b)), a multiple of 8 (padding included).
    std::size_t begin(std::int32_t b) const { return std::size_t(off_[std::size_t(b)]); }
    std::size_t end(std::int32_t b) const { return std::size_t(off_[std::size_t(b) + 1]); }
    /// The blocks within reach of active block b (itself included), ascending.
    const std::vector<std::int32_t>& near(std::int32_t b) const { return near_[std::size_t(b)]; }
    /// Squared distance from q to the points of block b's samples (its box widened by tau): a
    /// lower bound of |q − p_j|² over them.
    float box_distance2(std::int32_t b, const float q[3]) const;

    /// The run of block b with range values r and values v (arrays of size()).
    PairRun run(std::int32_t b, const Samples (&r)[3], const Samples (&v)[3]) const {
        const std::size_t o = begin(b);
        return PairRun{{p[0].data() + o, p[1].data() + o, p[2].data() + o},
                       {r[0].data() + o, r[1].data() + o, r[2].data() + o},
                       {v[0].data() + o, v[1].data() + o, v[2].data() + o},
                       int(end(b) - o)};
    }

    Samples p[3];                    ///< closest points, voxel coordinates of the grid
    Samples n[3];                    ///< normals
    std::vector<std::size_t> index;  ///< the band sample of each, kPadding for padding

private:
    const Band* band_ = nullptr;
    float tau_ = 0;
    std::vector<std::int64_t> off_;
    std::vector<std::vector<std::int32_t>> near_;
};

}  // namespace normalflow::engine
