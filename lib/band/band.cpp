#include "band/band.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "band/gather.h"
#include "band/iterate.h"

namespace normalflow::engine {

Band::Band(const Volume& v) : grid_(v.grid) {
    block_dims_ = v.block_dims;
    table_ = v.block_table;
    coords_ = v.block_coords;
    const float inv_h = float(1.0 / v.grid.voxel_size);
    phi_.resize(v.values.size());
    for_samples(v.values.size(),
                [&](std::size_t i) { phi_[i] = std::clamp(v.values[i] * inv_h, -kHalfWidth, kHalfWidth); });
}

std::vector<std::int32_t> Band::all_blocks() const {
    std::vector<std::int32_t> all(nblocks());
    for (std::size_t b = 0; b < all.size(); ++b) all[b] = std::int32_t(b);
    return all;
}

bool Band::has_surface() const {
    for (std::size_t b = 0; b < coords_.size(); ++b) {
        const float* p = phi_.data() + b * kBlockVoxels;
        bool neg = false, pos = false;
        for (int i = 0; i < kBlockVoxels; ++i) (p[i] < 0.0f ? neg : pos) = true;
        if (neg && pos) return true;
    }
    // a surface can also lie between a block and an unallocated neighbour of the other sign
    for (std::size_t b = 0; b < coords_.size(); ++b) {
        const float s = phi_[b * kBlockVoxels];
        for (int a = 0; a < 3; ++a)
            for (int d = -1; d <= 1; d += 2) {
                auto c = coords_[b];
                c[a] += d;
                if (c[a] < 0 || c[a] >= block_dims_[a]) continue;
                const std::int32_t t = table_[tindex(c[0], c[1], c[2])];
                if ((t == kBlockInside && s >= 0.0f) || (t == kBlockOutside && s < 0.0f)) return true;
            }
    }
    return false;
}

void Band::write_back(Volume& v) const {
    const float h = float(v.grid.voxel_size);
    v.half_width = kHalfWidth;
    v.background = float(kHalfWidth * v.grid.voxel_size);
    v.block_table = table_;
    v.block_coords = coords_;
    v.values.resize(phi_.size());
    for_samples(phi_.size(), [&](std::size_t i) { v.values[i] = phi_[i] * h; });
}

void Band::write_field(const Samples& s, float missing, Volume& out) const {
    out.grid = grid_;
    out.half_width = kHalfWidth;
    out.background = missing;
    out.block_dims = block_dims_;
    out.block_table = table_;
    for (std::int32_t& t : out.block_table)
        if (t < 0) t = kBlockOutside;  // every tile reads `missing`
    out.block_coords = coords_;
    out.values.resize(s.size());
    for_samples(s.size(), [&](std::size_t i) { out.values[i] = mask_[i] ? s[i] : missing; });
}

void Band::make_neighbourhood(std::size_t b, Neighbourhood& n) const {
    const auto& bc = coords_[b];
    for (int a = 0; a < 3; ++a) {
        n.ext[a] = std::min(kBlockDim, grid_.dims[a] - bc[a] * kBlockDim);
        for (int l = -1; l <= kBlockDim; ++l) {
            const int g = std::clamp(bc[a] * kBlockDim + l, 0, grid_.dims[a] - 1);
            n.nb[a][l + 1] = std::uint8_t((g >> kBlockLog2) - bc[a] + 1);
            n.li[a][l + 1] = std::uint8_t(g & (kBlockDim - 1));
        }
    }
    n.contiguous_x = true;
    for (int l = 0; l < kBlockDim; ++l)
        if (n.nb[0][l + 1] != 1 || n.li[0][l + 1] != l) n.contiguous_x = false;
    for (int dz = 0; dz < 3; ++dz)
        for (int dy = 0; dy < 3; ++dy)
            for (int dx = 0; dx < 3; ++dx) {
                const int c[3] = {bc[0] + dx - 1, bc[1] + dy - 1, bc[2] + dz - 1};
                std::int32_t s = kBlockOutside;
                if (c[0] >= 0 && c[1] >= 0 && c[2] >= 0 && c[0] < block_dims_[0] && c[1] < block_dims_[1] &&
                    c[2] < block_dims_[2])
                    s = table_[tindex(c[0], c[1], c[2])];
                n.slot[(dz * 3 + dy) * 3 + dx] = s;
            }
}

void Band::update_band() {
    const std::size_t nb = nblocks();
    std::vector<std::uint8_t> surf(nb, 0);
    const std::vector<std::int32_t> all = all_blocks();
    for_blocks(all, 1, [&](std::size_t, std::int32_t b, Scratch& s) {
        Neighbourhood n;
        make_neighbourhood(std::size_t(b), n);  // the blocks are about to change: no cached nbh_
        float* P = s.at(0);
        gather_phi(n, phi_, P);
        bool found = false;
        for (int z = 0; z < n.ext[2] && !found; ++z)
            for (int y = 0; y < n.ext[1] && !found; ++y)
                for (int x = 0; x < n.ext[0]; ++x) {
                    const int q = lidx(x, y, z);
                    const bool in = P[q] < 0.0f;
                    if (std::abs(P[q]) < 1.0f || (P[q + 1] < 0.0f) != in || (P[q - 1] < 0.0f) != in ||
                        (P[q + L] < 0.0f) != in || (P[q - L] < 0.0f) != in || (P[q + L2] < 0.0f) != in ||
                        (P[q - L2] < 0.0f) != in) {
                        found = true;
                        break;
                    }
                }
        surf[std::size_t(b)] = found;
    });
    std::vector<std::uint8_t> req(table_.size(), 0);
    for (std::size_t b = 0; b < nb; ++b) {
        if (!surf[b]) continue;
        const auto& c = coords_[b];
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
                    if (x < 0 || y < 0 || z < 0 || x >= block_dims_[0] || y >= block_dims_[1] || z >= block_dims_[2])
                        continue;
                    req[tindex(x, y, z)] = 1;
                }
    }
    std::vector<std::array<int, 3>> coords;
    std::vector<std::int32_t> table(table_.size());
    std::size_t count = 0;
    for (std::size_t t = 0; t < table_.size(); ++t) count += req[t];
    coords.reserve(count);
    std::vector<std::int32_t> source;  // per new slot: the old slot, or the tile it was
    source.reserve(count);
    // The new φ goes into work_.phi_next's buffer (free between stages, its pages already touched
    // after the first main iteration), which then becomes phi_.
    Samples& phi = work_.phi_next;
    fit_samples(phi, count * kBlockVoxels);
    for (int z = 0; z < block_dims_[2]; ++z)
        for (int y = 0; y < block_dims_[1]; ++y)
            for (int x = 0; x < block_dims_[0]; ++x) {
                const std::size_t t = tindex(x, y, z);
                const std::int32_t old = table_[t];
                if (req[t]) {
                    const std::int32_t slot = std::int32_t(coords.size());
                    coords.push_back({x, y, z});
                    source.push_back(old);
                    table[t] = slot;
                } else if (old >= 0) {
                    table[t] = phi_[std::size_t(old) * kBlockVoxels] < 0.0f ? kBlockInside : kBlockOutside;
                } else {
                    table[t] = old;
                }
            }
    // the blocks' values, in parallel (their first writes to a fresh buffer fault)
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, source.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t slot = r.begin(); slot != r.end(); ++slot) {
                float* dst = phi.data() + slot * kBlockVoxels;
                const std::int32_t old = source[slot];
                if (old >= 0)
                    std::memcpy(dst, phi_.data() + std::size_t(old) * kBlockVoxels, sizeof(float) * kBlockVoxels);
                else
                    std::fill(dst, dst + kBlockVoxels, old == kBlockInside ? -kHalfWidth : kHalfWidth);
            }
        });
    table_ = std::move(table);
    coords_ = std::move(coords);
    std::swap(phi_, work_.phi_next);
    // The per-sample work arrays: every stage writes what it reads after the blocks moved, so
    // their contents need not survive (their slots changed anyway). A growing array is
    // reallocated with headroom rather than copied: as the band moves it grows by a few blocks
    // at a time, and resizing these twelve arrays of the whole band (copy, zero fill, page
    // faults) took 0.2–0.3 s per call on bunny at resolution 256, serial. Untouched headroom
    // costs address space, not memory.
    const std::size_t n = phi_.size();
    fit_samples(work_.phi_next, n);
    for (int c = 0; c < 3; ++c) {
        fit_samples(work_.normals[c], n);
        fit_samples(work_.normals_next[c], n);
        fit_samples(work_.normals_aux[c], n);
    }
    fit_samples(work_.hn, n);
    fit_samples(mask_, n);
    nbh_.resize(nblocks());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) make_neighbourhood(b, nbh_[b]);
    });
}

void Band::build_active(float active_band) {
    const float band = active_band;
    std::vector<std::uint32_t> count(nblocks());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            const auto& c = coords_[b];
            int lo[3], ext[3];  // the block's samples that may be active: lo <= local < ext
            for (int a = 0; a < 3; ++a) {
                ext[a] = std::min(kBlockDim, grid_.dims[a] - fixed_hi_[a] - c[a] * kBlockDim);
                lo[a] = std::max(0, fixed_lo_[a] - c[a] * kBlockDim);
            }
            std::uint32_t cnt = 0;
            const std::size_t base = b * kBlockVoxels;
            for (int z = 0; z < kBlockDim; ++z)
                for (int y = 0; y < kBlockDim; ++y)
                    for (int x = 0; x < kBlockDim; ++x) {
                        const std::size_t i = base + std::size_t(bidx(x, y, z));
                        const bool a = x >= lo[0] && y >= lo[1] && z >= lo[2] && x < ext[0] && y < ext[1] &&
                                       z < ext[2] && std::abs(phi_[i]) <= band;
                        mask_[i] = a;
                        cnt += a;
                    }
            count[b] = cnt;
        }
    });
    active_.clear();
    active_voxels_ = 0;
    for (std::size_t b = 0; b < nblocks(); ++b) {
        if (count[b]) active_.push_back(std::int32_t(b));
        active_voxels_ += count[b];
    }
}

}  // namespace normalflow::engine
