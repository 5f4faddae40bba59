#pragma once
/// \file volume.h
/// The one volume type of normalflow: a sparse, block-structured signed distance volume that
/// stores only the narrow band around the surface, so memory grows with the surface area,
/// not the bounding volume.
///
/// Layout: the grid is cut into 8×8×8 blocks. A dense table (one int32 per block, 2 bytes per
/// 256 voxels) says for each block either where its 512 values are stored, or that the block
/// lies entirely outside (+background) or inside (−background) the surface. Values inside a
/// block are stored x fastest, then y, then z. Sign convention: negative inside, positive
/// outside (as OpenVDB); values in world units.

#include <array>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "core/vec.h"

namespace normalflow {

/// Where a grid's own frame lies in the world of the file it came from: world = translation +
/// rotation · p, with p a position in the grid's frame (Grid::world) and rotation orthonormal (its
/// columns the world directions of the grid's x, y, z axes; a reflection when its determinant is −1,
/// as in many medical volumes). The identity for every volume made from a mesh. The engine works in
/// the grid's frame; the file boundary (io/) maps results to the world with it.
struct Placement {
    std::array<Vec3d, 3> rotation{Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};  ///< columns
    Vec3d translation;

    bool is_identity() const {
        return translation == Vec3d{} && rotation[0] == Vec3d{1, 0, 0} && rotation[1] == Vec3d{0, 1, 0} &&
               rotation[2] == Vec3d{0, 0, 1};
    }
    /// The world direction of a direction d of the grid's frame.
    Vec3d direction(const Vec3d& d) const { return rotation[0] * d.x + rotation[1] * d.y + rotation[2] * d.z; }
    /// The world position of a position p of the grid's frame.
    Vec3d point(const Vec3d& p) const { return translation + direction(p); }
    /// The grid-frame position of a world position w (the rotation's transpose).
    Vec3d inverse_point(const Vec3d& w) const {
        const Vec3d d = w - translation;
        return {dot(rotation[0], d), dot(rotation[1], d), dot(rotation[2], d)};
    }
    /// Whether the rotation is a reflection (determinant < 0): a mesh mapped by it turns its faces over.
    bool reflects() const { return dot(rotation[0], cross(rotation[1], rotation[2])) < 0; }
};

/// A regular grid of samples: sample (i, j, k) sits at origin + voxel_size * (i, j, k).
struct Grid {
    Vec3d origin;                      ///< world position of sample (0, 0, 0), in the grid's frame
    double voxel_size = 1.0;           ///< h, world units, > 0
    std::array<int, 3> dims{0, 0, 0};  ///< number of samples along x, y, z
    /// The grid's frame in the world of its file (identity unless a volume file said otherwise).
    Placement placement;

    /// World position of (possibly fractional) index (i, j, k).
    Vec3d world(const Vec3d& ijk) const { return origin + ijk * voxel_size; }
    /// Continuous index of a world position.
    Vec3d index(const Vec3d& w) const { return (w - origin) / voxel_size; }
    bool contains(int i, int j, int k) const {
        return i >= 0 && j >= 0 && k >= 0 && i < dims[0] && j < dims[1] && k < dims[2];
    }
    std::size_t sample_count() const { return std::size_t(dims[0]) * std::size_t(dims[1]) * std::size_t(dims[2]); }
};

inline constexpr int kBlockLog2 = 3;
inline constexpr int kBlockDim = 1 << kBlockLog2;                       // 8
inline constexpr int kBlockVoxels = kBlockDim * kBlockDim * kBlockDim;  // 512
inline constexpr std::int32_t kBlockOutside = -1;                       ///< unallocated block, value +background
inline constexpr std::int32_t kBlockInside = -2;                        ///< unallocated block, value -background

/// Sparse narrow-band signed distance volume (see file comment).
/// Invariant: every sample with |phi| < half_width * voxel_size lies in an allocated block.
struct Volume {
    Grid grid;
    float background = 3.0f;                 ///< world units, > 0: |phi| of every sample outside allocated blocks
    float half_width = 3.0f;                 ///< band half-width in voxels
    std::array<int, 3> block_dims{0, 0, 0};  ///< ceil(grid.dims / 8)
    std::vector<std::int32_t> block_table;   ///< per block: index into block_coords, or kBlockOutside/kBlockInside
    std::vector<std::array<int, 3>> block_coords;  ///< block coordinates (in blocks) of each allocated block
    std::vector<float> values;                     ///< block_coords.size() * 512 samples

    Volume() = default;
    /// An empty volume (every block outside) over grid g; half_width in voxels.
    Volume(const Grid& g, float half_width_voxels) { reset(g, half_width_voxels); }

    void reset(const Grid& g, float half_width_voxels) {
        grid = g;
        half_width = half_width_voxels;
        background = float(half_width_voxels * g.voxel_size);
        for (int a = 0; a < 3; ++a) block_dims[a] = (g.dims[a] + kBlockDim - 1) / kBlockDim;
        block_table.assign(std::size_t(block_dims[0]) * block_dims[1] * block_dims[2], kBlockOutside);
        block_coords.clear();
        values.clear();
    }

    std::size_t block_count() const { return block_coords.size(); }
    std::size_t table_index(int bi, int bj, int bk) const {
        return (std::size_t(bk) * block_dims[1] + std::size_t(bj)) * block_dims[0] + std::size_t(bi);
    }
    static constexpr int local_index(int li, int lj, int lk) { return (lk * kBlockDim + lj) * kBlockDim + li; }
    /// Block slot of sample (i, j, k) (which must be inside the grid): >= 0 or kBlockOutside/Inside.
    std::int32_t block_of(int i, int j, int k) const {
        return block_table[table_index(i >> kBlockLog2, j >> kBlockLog2, k >> kBlockLog2)];
    }

    /// Value at sample (i, j, k); +background outside the grid.
    float value(int i, int j, int k) const {
        if (!grid.contains(i, j, k)) return background;
        const std::int32_t b = block_of(i, j, k);
        if (b >= 0)
            return values[std::size_t(b) * kBlockVoxels +
                          local_index(i & (kBlockDim - 1), j & (kBlockDim - 1), k & (kBlockDim - 1))];
        return b == kBlockInside ? -background : background;
    }

    /// Allocates block (bi, bj, bk) if needed (filled with its tile value); returns its slot.
    std::int32_t allocate_block(int bi, int bj, int bk) {
        std::int32_t& slot = block_table[table_index(bi, bj, bk)];
        if (slot >= 0) return slot;
        const float fill = slot == kBlockInside ? -background : background;
        slot = std::int32_t(block_coords.size());
        block_coords.push_back({bi, bj, bk});
        values.resize(values.size() + kBlockVoxels, fill);
        return slot;
    }

    /// Sets sample (i, j, k) (inside the grid), allocating its block if needed.
    void set(int i, int j, int k, float v) {
        assert(grid.contains(i, j, k) && "Volume::set: index outside the grid");
        const std::int32_t b = allocate_block(i >> kBlockLog2, j >> kBlockLog2, k >> kBlockLog2);
        values[std::size_t(b) * kBlockVoxels +
               local_index(i & (kBlockDim - 1), j & (kBlockDim - 1), k & (kBlockDim - 1))] = v;
    }

    /// Pointer to the 512 values of allocated block slot b.
    float* block_values(std::int32_t b) { return values.data() + std::size_t(b) * kBlockVoxels; }
    const float* block_values(std::int32_t b) const { return values.data() + std::size_t(b) * kBlockVoxels; }

    /// Checks the layout invariants every stage relies on: voxel_size finite and > 0, origin finite,
    /// dims >= 1, background and half_width finite and > 0, block_dims = ceil(dims / 8), one table
    /// entry per block, 512 values per allocated block, every allocated block's coordinates inside
    /// block_dims and its table entry pointing back at it, every table entry a block index or
    /// kBlockOutside/kBlockInside with exactly block_count() entries allocated, and every sample finite.
    /// (The narrow-band invariant, |phi| < half_width · h only in allocated blocks, is not checked.)
    /// \param who  message prefix naming the caller, e.g. "extract_surface" or "read_nrrd: a.nrrd"
    /// \throw InvalidInput "who: volume block_table has 11 entries, expected 12" and the like;
    ///        NumericalError "who: volume sample 7 of block 1 is NaN or infinite".
    /// Cost: one pass over the table, the blocks and the values; single-threaded.
    void check(std::string_view who) const;

    /// Bytes held by this volume (table + blocks).
    std::size_t memory_bytes() const {
        return block_table.size() * sizeof(std::int32_t) + block_coords.size() * sizeof(block_coords[0]) +
               values.size() * sizeof(float);
    }
};

/// A normal map on a volume's grid: one Volume per component of the unit normal N, holding N where it
/// is defined and kNoNormal elsewhere (their background). smooth_volume hands out the last normal map
/// it filtered; fit_mesh_to_volume can turn faces to it.
using NormalMap = std::array<Volume, 3>;
inline constexpr float kNoNormal = 2.0f;

}  // namespace normalflow
