#pragma once
/// \file band.h
/// The engine's narrow band (after OpenVDB's LevelSetTracker): it owns φ in voxel units on the
/// allocated 8³ blocks, the block table and coordinates, the blocks' neighbourhoods, the active
/// mask and list, and the per-sample work buffers the stages borrow (WorkBuffers). It moves with
/// the surface (update_band) and keeps φ a signed distance (reinitialise); the stages of
/// lib/normals (the normal filters, the refit, mean curvature flow) read and write φ and the work
/// buffers through it, block by block (for_blocks).

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "band/layout.h"
#include "band/run_control.h"
#include "core/band_memory.h"
#include "core/volume.h"

namespace normalflow::engine {

/// The band's per-sample work buffers: each as long as φ, resized by Band::update_band, their
/// contents not kept across it (every stage writes what it reads after the band moved, and the
/// slots changed anyway). Which stage uses which, and when:
struct WorkBuffers {
    /// φ's twin, the output of every pass that makes a new φ: update_band (the moved φ, then
    /// swapped with φ), reinitialise (the unsigned distances, ping-pong with spare()), each step of
    /// the refit and of mean curvature flow (the next φ, then swapped with φ). In the refit, before
    /// its first step, target_curvature uses it as scratch (G per sample, second_order_term).
    Samples phi_next;
    /// The normal map N: made and filtered by the normal filter (filter_normals), read by the refit.
    Field3 normals;
    /// The normal steps' output (ping-pong with normals): normal filter only.
    Field3 normals_next;
    /// A third normal field, normal filter only: the anisotropic filter's pre-smoothed normals,
    /// high-boost's Nⁿ. Its first component is spare() outside the normal filter.
    Field3 normals_aux;
    /// H_N, the target curvature of the refit (0 in mean curvature flow).
    Samples hn;

    /// The spare φ-sized buffer, normals_aux[0], free outside the normal filter: reinitialise's
    /// ping-pong buffer; the refit's previous iterate (a step that raised D is undone from it).
    Samples& spare() { return normals_aux[0]; }
};

class Band {
public:
    /// φ = the volume's values in voxels, clamped to ±kHalfWidth; the volume's blocks. The
    /// neighbourhoods and work buffers are made by the first update_band.
    explicit Band(const Volume& v);

    /// Whether φ changes sign somewhere (inside a block or to an unallocated neighbour).
    bool has_surface() const;

    /// Blocks holding the surface (a sign change to a 6-neighbour, or |φ| < 1) plus their 26
    /// neighbours stay or become allocated; every other block becomes a tile of its sign.
    /// Resizes the work buffers and the mask (contents not kept).
    void update_band();

    /// φ ← signed distance in the band: interface samples keep φ/|∇φ| (bounded by the distance to
    /// the axis crossings of the zero level), the others get Jacobi sweeps of the Godunov update.
    /// The sweeps stop when the distances below limit have converged; those at or above it are
    /// then at least limit (the sweeps only lower an upper bound), not necessarily converged.
    /// Uses work().phi_next, work().spare() and the mask.
    void reinitialise(float limit, const RunControl& ctl);
    /// limit of the last reinitialise(): φ is a distance below it.
    float reinit_limit() const { return reinit_limit_; }

    /// The mask of the samples with |φ| <= active_band (inside the grid) and the list of the blocks
    /// that hold any (active()).
    void build_active(float active_band);
    /// Samples within lo[a] voxels of the grid's low side along axis a, or hi[a] of its high side, are never active:
    /// they keep their values (a Dirichlet border, for a window of a larger grid worked on alone).
    void set_fixed_border(const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
        fixed_lo_ = lo;
        fixed_hi_ = hi;
    }

    /// The volume from φ: world units, the band's blocks, half width kHalfWidth.
    void write_back(Volume& v) const;
    /// A per-sample field as a Volume on the band's grid and blocks: s at the active samples (the mask
    /// of build_active), `missing` at the other samples and in the tiles (background = missing).
    void write_field(const Samples& s, float missing, Volume& out) const;

    // ---- layout
    std::size_t nblocks() const { return coords_.size(); }
    /// Block coordinates (i, j, k: samples 8i … 8i + 7 along x, …) of allocated block b.
    const std::array<int, 3>& block_coord(std::size_t b) const { return coords_[b]; }
    /// The slot of the block at block coordinates (i, j, k): >= 0 when allocated, < 0 when
    /// unallocated or outside the grid.
    std::int32_t block_at(int i, int j, int k) const {
        if (i < 0 || j < 0 || k < 0 || i >= block_dims_[0] || j >= block_dims_[1] || k >= block_dims_[2]) return -1;
        return table_[tindex(i, j, k)];
    }
    const Grid& grid() const { return grid_; }
    /// The halo sources of allocated block b (valid after update_band until the next).
    const Neighbourhood& neighbourhood(std::size_t b) const { return nbh_[b]; }
    /// Every allocated block, 0 … nblocks() − 1.
    std::vector<std::int32_t> all_blocks() const;
    /// The blocks with active samples, ascending (build_active).
    const std::vector<std::int32_t>& active() const { return active_; }
    std::size_t active_voxels() const { return active_voxels_; }

    // ---- per-sample arrays
    Samples& phi() { return phi_; }
    const Samples& phi() const { return phi_; }
    /// 1 at the active samples (build_active); reinitialise overwrites it with its fixed samples.
    const std::uint8_t* mask() const { return mask_.data(); }
    WorkBuffers& work() { return work_; }

    /// parallel_for over a list of block slots; body(index in list, slot, scratch of
    /// scratch_fields padded buffers of L³ floats, per thread).
    template <class Body>
    void for_blocks(const std::vector<std::int32_t>& list, int scratch_fields, Body&& body) const {
        const std::size_t need = std::size_t(scratch_fields) * L3;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, list.size(), 4),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              std::vector<float>& buf = scratch_.local();
                              if (buf.size() < need) buf.resize(need);
                              Scratch s{buf.data()};
                              for (std::size_t i = r.begin(); i != r.end(); ++i) body(i, list[i], s);
                          });
    }

private:
    std::size_t tindex(int bi, int bj, int bk) const {
        return (std::size_t(bk) * block_dims_[1] + std::size_t(bj)) * block_dims_[0] + std::size_t(bi);
    }
    void make_neighbourhood(std::size_t b, Neighbourhood& n) const;

    Grid grid_;
    std::array<int, 3> fixed_lo_{0, 0, 0}, fixed_hi_{0, 0, 0};
    float reinit_limit_ = 0.0f;
    std::array<int, 3> block_dims_{};
    std::vector<std::int32_t> table_;
    std::vector<std::array<int, 3>> coords_;
    Samples phi_;
    WorkBuffers work_;
    std::vector<std::uint8_t, detail::NoInitAllocator<std::uint8_t>> mask_;
    std::vector<Neighbourhood> nbh_;  // per allocated block, rebuilt when the band moves
    mutable tbb::enumerable_thread_specific<std::vector<float>> scratch_;
    std::vector<std::int32_t> active_;
    std::size_t active_voxels_ = 0;
};

}  // namespace normalflow::engine
