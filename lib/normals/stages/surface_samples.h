#pragma once
/// \file surface_samples.h
/// The samples of the band next to the surface as a point set on it, for the filters that
/// average over a neighbourhood of fixed size in the model's units (surface_filter.h): each sample
/// with |φ| <= tau, moved to its closest point on the zero level, x − φ·∇φ/|∇φ|, with its
/// normal. Grouped by block (slot order), within a block by its eight 4³ octants, each octant's
/// run padded to a multiple of 8 samples far away, so that kernels/pair_sum runs over whole runs;
/// each run and each block has the bounding box of its points; the blocks within reach of each
/// block are listed. Everything is in a fixed order, so sums over it do not depend on the threads.

#include <algorithm>
#include <array>
#include <cmath>
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
    /// With stride s > 1, only the samples whose grid coordinates are all multiples of s, with
    /// |φ| <= tau·s: about 1/s² as many points, as densely spread over the surface in units of s
    /// voxels as stride 1 in voxels.
    /// `origin`: the grid coordinates of the band's sample (0, 0, 0) in the frame the points are given in (a window
    /// of a larger grid: its lower corner in that grid, so that its points and their order are the larger grid's bit
    /// for bit); a multiple of the stride.
    void build(const Band& band, const Field3& normals, float tau, float reach, float margin, int stride = 1,
               std::array<int, 3> origin = {0, 0, 0});
    /// Whether band sample x, y, z of block b (φ = v) is one of the points (build's rule).
    bool taken(const Band& band, std::size_t b, int x, int y, int z, float v) const {
        if (!(std::abs(v) <= tau_)) return false;
        if (stride_ == 1) return true;
        const auto& bc = band.block_coord(b);
        return (origin_[0] + bc[0] * kBlockDim + x) % stride_ == 0 &&
               (origin_[1] + bc[1] * kBlockDim + y) % stride_ == 0 &&
               (origin_[2] + bc[2] * kBlockDim + z) % stride_ == 0;
    }

    std::size_t size() const { return index.size(); }
    /// build's origin: the points' coordinates less it are the band's own.
    const std::array<int, 3>& origin() const { return origin_; }
    static constexpr int kRuns = 8;  ///< runs per block: its 4³ octants

    /// The samples of block slot b: [begin(b), end(b)), its runs one after the other (padding
    /// included).
    std::size_t begin(std::int32_t b) const { return std::size_t(off_[std::size_t(b) * kRuns]); }
    std::size_t end(std::int32_t b) const { return std::size_t(off_[(std::size_t(b) + 1) * kRuns]); }
    /// The blocks within reach of active block b (itself included), in the order of their coordinates (z, then y,
    /// then x): the same order in a window as in the whole grid, whatever slots the blocks hold.
    const std::vector<std::int32_t>& near(std::int32_t b) const { return near_[std::size_t(b)]; }
    /// Squared distance from q to the bounding box of block b's points: a lower bound of
    /// |q − p_j|² over them (infinite for a block without samples).
    float box_distance2(std::int32_t b, const float q[3]) const {
        return box_d2(std::size_t(b) * (kRuns + 1) + kRuns, q);
    }
    /// Whether run k of block b has samples.
    bool run_empty(std::int32_t b, int k) const {
        const std::size_t r = std::size_t(b) * kRuns + std::size_t(k);
        return off_[r + 1] == off_[r];
    }
    /// The samples of run k of block b: [run_begin(b, k), run_end(b, k)).
    std::size_t run_begin(std::int32_t b, int k) const {
        return std::size_t(off_[std::size_t(b) * kRuns + std::size_t(k)]);
    }
    std::size_t run_end(std::int32_t b, int k) const {
        return std::size_t(off_[std::size_t(b) * kRuns + std::size_t(k) + 1]);
    }

    /// The runs (b2·kRuns + k2) of the blocks near b with points within `reach` of the box of
    /// run k of block b: every sample of that run finds its neighbours within reach among them.
    void candidates(std::int32_t b, int k, float reach, std::vector<std::int32_t>& out) const {
        out.clear();
        const std::size_t self = std::size_t(b) * (kRuns + 1) + std::size_t(k);
        const float r2 = reach * reach;
        for (std::int32_t b2 : near(b)) {
            if (box_box_d2(self, std::size_t(b2) * (kRuns + 1) + kRuns) > r2) continue;
            for (int k2 = 0; k2 < kRuns; ++k2)
                if (box_box_d2(self, std::size_t(b2) * (kRuns + 1) + std::size_t(k2)) <= r2)
                    out.push_back(b2 * kRuns + k2);
        }
    }

    /// Squared distance from q to the box of run r (b·kRuns + k).
    float run_distance2(std::int32_t r, const float q[3]) const {
        return box_d2(std::size_t(r / kRuns) * (kRuns + 1) + std::size_t(r % kRuns), q);
    }
    /// The samples of run r (b·kRuns + k).
    PairSpan span(std::int32_t r) const {
        return PairSpan{off_[std::size_t(r)], off_[std::size_t(r) + 1] - off_[std::size_t(r)]};
    }
    /// The points with range values rv and values v (arrays of size()).
    PairArrays arrays(const Samples (&rv)[3], const Samples (&v)[3]) const {
        return PairArrays{{p[0].data(), p[1].data(), p[2].data()},
                          {rv[0].data(), rv[1].data(), rv[2].data()},
                          {v[0].data(), v[1].data(), v[2].data()}};
    }
    /// The box of run r: lo, hi.
    const std::array<float, 3>& run_lo(std::int32_t r) const { return box_lo_[box_of(r)]; }
    const std::array<float, 3>& run_hi(std::int32_t r) const { return box_hi_[box_of(r)]; }

    Samples p[3];                    ///< closest points, voxel coordinates of the grid
    Samples n[3];                    ///< normals
    std::vector<std::size_t> index;  ///< the band sample of each, kPadding for padding

private:
    static std::size_t box_of(std::int32_t r) { return std::size_t(r / kRuns) * (kRuns + 1) + std::size_t(r % kRuns); }
    float box_d2(std::size_t box, const float q[3]) const {
        const float* lo = box_lo_[box].data();
        const float* hi = box_hi_[box].data();
        float d2 = 0.0f;
        for (int a = 0; a < 3; ++a) {
            const float d = q[a] < lo[a] ? lo[a] - q[a] : (q[a] > hi[a] ? q[a] - hi[a] : 0.0f);
            d2 += d * d;
        }
        return d2;
    }
    float box_box_d2(std::size_t a, std::size_t b) const {
        float d2 = 0.0f;
        for (std::size_t c = 0; c < 3; ++c) {
            const float d = std::max({box_lo_[a][c] - box_hi_[b][c], box_lo_[b][c] - box_hi_[a][c], 0.0f});
            d2 += d * d;
        }
        return d2;
    }

    float tau_ = 0;  // |φ| of the points at most
    int stride_ = 1;
    std::array<int, 3> origin_{0, 0, 0};
    std::vector<std::int64_t> off_;                      // run k of block b starts at off_[b·kRuns + k]
    std::vector<std::array<float, 3>> box_lo_, box_hi_;  // per block: its kRuns runs' boxes, then its own
    std::vector<std::vector<std::int32_t>> near_;
};

}  // namespace normalflow::engine
