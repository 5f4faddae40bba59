#include "sdf/scan_convert.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/errors.h"
#include "sdf/triangle_bvh.h"
#include "sdf/winding_number.h"

namespace normalflow {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kUncertain = 0.1;  // |w − 1/2| below this is reported as uncertain
constexpr int kRepresentatives = 4;
constexpr double kOnSurface = 1e-3;  // samples nearer than this (in voxels) are on the surface

struct BlockStats {
    std::uint32_t band = 0, uncertain = 0, evaluations = 0;
    bool keep = false, inside = false;
};

struct Context {
    const Grid& grid;
    const ClosestTriangleQuery& q;
    const WindingNumber* wn;  // null in shell mode
    double h, reach, shell_off, bg;
};

int find_root(std::int16_t* parent, int x) {
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

// Distances, band test and signs of the 512 samples of block b; out receives the values.
BlockStats process_block(const Context& c, const std::array<int, 3>& b, float* out) {
    BlockStats st;
    const Grid& g = c.grid;
    const double halfdiag = 3.5 * std::sqrt(3.0) * c.h;
    const Vec3d center = g.world(Vec3d(b[0] * 8 + 3.5, b[1] * 8 + 3.5, b[2] * 8 + 3.5));
    const ClosestHit hc = c.q.closest_within(center, (c.reach + halfdiag) * (c.reach + halfdiag));
    if (!hc.found()) return st;

    double d[kBlockVoxels];
    bool in_grid[kBlockVoxels];
    std::uint32_t hint = hc.triangle;
    const double reach2 = c.reach * c.reach;
    // Distance is 1-Lipschitz: d(p) >= d(centre) − |p − centre|. Samples where that bound reaches the
    // band cannot be in it; skipping their query gives the same answer (not found) at no cost. The
    // margin keeps the skip on the safe side of rounding.
    const double dc = std::sqrt(hc.squared_distance);
    const double skip_beyond = c.reach * (1.0 + 1e-9) + 1e-9 * c.h;
    for (int lk = 0; lk < kBlockDim; ++lk)
        for (int lj = 0; lj < kBlockDim; ++lj)
            for (int li = 0; li < kBlockDim; ++li) {
                const int n = Volume::local_index(li, lj, lk);
                const int i = b[0] * 8 + li, j = b[1] * 8 + lj, k = b[2] * 8 + lk;
                in_grid[n] = g.contains(i, j, k);
                d[n] = kInf;
                if (!in_grid[n]) continue;
                const Vec3d p = g.world(Vec3d(i, j, k));
                if (dc - norm(p - center) > skip_beyond) continue;
                const ClosestHit hit = c.q.closest_within(p, reach2, hint);
                if (hit.found()) {
                    d[n] = std::sqrt(hit.squared_distance);
                    hint = hit.triangle;
                }
            }

    const double band = c.bg;
    if (!c.wn) {  // shell: phi = d − T/2
        for (int n = 0; n < kBlockVoxels; ++n) {
            const double phi = in_grid[n] ? d[n] - c.shell_off : kInf;
            if (std::abs(phi) < band) ++st.band;
            out[n] = float(std::clamp(phi, -band, band));
        }
        st.keep = st.band > 0;
        return st;
    }
    for (int n = 0; n < kBlockVoxels; ++n)
        if (in_grid[n] && d[n] < band) ++st.band;
    if (st.band == 0) return st;
    st.keep = true;

    // Sets of samples that must share a sign: 6-neighbours p, q with max(d(p), d(q)) > h.
    std::int16_t parent[kBlockVoxels];
    for (int n = 0; n < kBlockVoxels; ++n) parent[n] = std::int16_t(n);
    const double link = c.h * (1.0 + 1e-9);
    auto unite = [&](int p, int r) {
        if (!in_grid[p] || !in_grid[r] || !(std::max(d[p], d[r]) > link)) return;
        const int a = find_root(parent, p), bb = find_root(parent, r);
        if (a != bb) parent[std::max(a, bb)] = std::int16_t(std::min(a, bb));
    };
    for (int lk = 0; lk < kBlockDim; ++lk)
        for (int lj = 0; lj < kBlockDim; ++lj)
            for (int li = 0; li < kBlockDim; ++li) {
                const int n = Volume::local_index(li, lj, lk);
                if (li + 1 < kBlockDim) unite(n, n + 1);
                if (lj + 1 < kBlockDim) unite(n, n + kBlockDim);
                if (lk + 1 < kBlockDim) unite(n, n + kBlockDim * kBlockDim);
            }
    // Group members by root (counting sort keeps the index order).
    std::int16_t root[kBlockVoxels];
    int count[kBlockVoxels + 1] = {};
    for (int n = 0; n < kBlockVoxels; ++n) {
        root[n] = std::int16_t(find_root(parent, n));
        if (in_grid[n]) ++count[root[n] + 1];
    }
    for (int n = 0; n < kBlockVoxels; ++n) count[n + 1] += count[n];
    std::int16_t members[kBlockVoxels];
    int fill[kBlockVoxels];
    std::copy(count, count + kBlockVoxels, fill);
    for (int n = 0; n < kBlockVoxels; ++n)
        if (in_grid[n]) members[fill[root[n]]++] = std::int16_t(n);

    double sign[kBlockVoxels];
    auto pos = [&](int n) {
        return g.world(Vec3d(b[0] * 8 + (n & 7), b[1] * 8 + ((n >> 3) & 7), b[2] * 8 + (n >> 6)));
    };
    auto evaluate = [&](int n) {
        const double w = (*c.wn)(pos(n));
        ++st.evaluations;
        // A sample on the surface itself (d <= 1e-3 h: a grid point on a face, edge or vertex) sees
        // w ≈ 1/2 on any mesh; its sign changes phi by at most 2e-3 h, so it is not reported.
        if (d[n] < band && d[n] > kOnSurface * c.h && std::abs(w - 0.5) < kUncertain) ++st.uncertain;
        return w;
    };
    for (int r = 0; r < kBlockVoxels; ++r) {
        const int first = count[r], last = count[r + 1];
        if (first == last) continue;
        // Up to 4 spread representatives: the farthest sample from the surface, then farthest-point sampling.
        int reps[kRepresentatives];
        int nrep = 0;
        int best = members[first];
        for (int m = first; m < last; ++m)
            if (d[members[m]] > d[best]) best = members[m];
        reps[nrep++] = best;
        int mind[kBlockVoxels];
        for (int m = first; m < last; ++m) mind[m - first] = 1 << 30;
        while (nrep < kRepresentatives) {
            const int prev = reps[nrep - 1];
            int arg = -1, far = 0;
            for (int m = first; m < last; ++m) {
                const int n = members[m];
                const int dx = (n & 7) - (prev & 7), dy = ((n >> 3) & 7) - ((prev >> 3) & 7),
                          dz = (n >> 6) - (prev >> 6);
                mind[m - first] = std::min(mind[m - first], dx * dx + dy * dy + dz * dz);
                if (mind[m - first] > far) {
                    far = mind[m - first];
                    arg = n;
                }
            }
            if (arg < 0) break;
            reps[nrep++] = arg;
        }
        bool firm = true;
        int votes_in = 0;
        double wrep[kRepresentatives];
        for (int k = 0; k < nrep; ++k) {
            wrep[k] = evaluate(reps[k]);
            if (std::abs(wrep[k] - 0.5) < kUncertain) firm = false;
            votes_in += wrep[k] > 0.5;
        }
        if (firm && (votes_in == 0 || votes_in == nrep)) {
            for (int m = first; m < last; ++m) sign[members[m]] = votes_in ? -1.0 : 1.0;
        } else {
            for (int m = first; m < last; ++m) {
                const int n = members[m];
                int k = 0;
                while (k < nrep && reps[k] != n) ++k;
                const double w = k < nrep ? wrep[k] : evaluate(n);
                sign[n] = w > 0.5 ? -1.0 : 1.0;
            }
        }
    }
    for (int n = 0; n < kBlockVoxels; ++n) {
        if (!in_grid[n]) {
            out[n] = float(band);
            continue;
        }
        out[n] = float(sign[n] * std::min(d[n], band));
        st.inside |= sign[n] < 0;
    }
    return st;
}

}  // namespace

namespace {

void check_scan_options(const ScanConvertOptions& opt) {
    if (!(opt.half_width >= 1.0f) || !std::isfinite(opt.half_width))
        throw InvalidInput("scan_convert: half_width is " + std::to_string(opt.half_width) + " voxels, expected >= 1");
    if (!(opt.shell_thickness >= 0) || !std::isfinite(opt.shell_thickness))
        throw InvalidInput("scan_convert: shell_thickness is " + std::to_string(opt.shell_thickness) +
                           ", expected >= 0");
    if (!(opt.voxel_size >= 0) || !std::isfinite(opt.voxel_size))
        throw InvalidInput("scan_convert: voxel_size is " + std::to_string(opt.voxel_size) + ", expected >= 0");
    if (opt.voxel_size == 0 && opt.resolution < 1)
        throw InvalidInput("scan_convert: resolution is " + std::to_string(opt.resolution) + ", expected >= 1");
    if (opt.threads < 0)
        throw InvalidInput("scan_convert: threads is " + std::to_string(opt.threads) + ", expected >= 0");
}

// The scan of the blocks [w.lo, w.hi) of `grid` into a volume over that window (whole = the whole grid: the tile
// scan starts outside at its border and a volume with nothing inside is refused). Sample positions come from `grid`
// itself, so a window's values are bit for bit those of the whole grid's scan.
Volume scan_window(const Mesh& m, const ClosestTriangleQuery& q, const WindingNumber* wn, const Grid& grid,
                   const BlockWindow& w, bool whole, const ScanConvertOptions& opt, ScanConvertReport& rep,
                   Progress* progress) {
    const double h = grid.voxel_size;
    const double hw = opt.half_width;
    const double shell_off = opt.shell_thickness * 0.5;
    const Grid sub = window_grid(grid, w);
    Volume vol(sub, opt.half_width);
    const double bg = vol.background;
    const double reach = hw * h + shell_off;
    rep.grid = sub;
    tbb::task_arena arena(opt.threads > 0 ? opt.threads : tbb::task_arena::automatic);
    const auto& bd = vol.block_dims;
    // Global block (bi, bj, bk) of the grid is the window's (bi − lo, ...).
    auto global_block = [&](int bi, int bj, int bk) {
        return std::array<int, 3>{bi + w.lo[0], bj + w.lo[1], bk + w.lo[2]};
    };

    // 1. Candidate blocks: those a triangle's box dilated by the band touches, near its plane. marks(r) flags the
    // blocks of the grid's box r, x fastest.
    const auto t_dist0 = Clock::now();
    const double halfdiag = 3.5 * std::sqrt(3.0) * h;
    const auto marks = [&](const BlockWindow& r) {
        const std::array<int, 3> rd{r.hi[0] - r.lo[0], r.hi[1] - r.lo[1], r.hi[2] - r.lo[2]};
        std::vector<std::uint8_t> out(
            static_cast<std::size_t>(rd[0]) * static_cast<std::size_t>(rd[1]) * static_cast<std::size_t>(rd[2]),
            std::uint8_t{0});
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.triangles.size(), 1024), [&](const auto& range) {
                for (std::size_t f = range.begin(); f != range.end(); ++f) {
                    const Tri& t = m.triangles[f];
                    const Vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
                    const Vec3d lo = grid.index(cwise_min(a, cwise_min(b, c)) - Vec3d(reach, reach, reach));
                    const Vec3d hi = grid.index(cwise_max(a, cwise_max(b, c)) + Vec3d(reach, reach, reach));
                    int blo[3], bhi[3];
                    bool outside = false;
                    for (int ax = 0; ax < 3; ++ax) {
                        blo[ax] = std::clamp(int(std::floor(lo[ax])), 0, grid.dims[ax] - 1) >> kBlockLog2;
                        bhi[ax] = std::clamp(int(std::ceil(hi[ax])), 0, grid.dims[ax] - 1) >> kBlockLog2;
                        blo[ax] = std::max(blo[ax], r.lo[ax]);
                        bhi[ax] = std::min(bhi[ax], r.hi[ax] - 1);
                        outside |= blo[ax] > bhi[ax];
                    }
                    if (outside) continue;
                    const Vec3d nrm = normalized(cross(b - a, c - a));
                    const bool plane = squared_norm(nrm) > 0.5;
                    for (int bk = blo[2]; bk <= bhi[2]; ++bk)
                        for (int bj = blo[1]; bj <= bhi[1]; ++bj)
                            for (int bi = blo[0]; bi <= bhi[0]; ++bi) {
                                if (plane) {
                                    const Vec3d cen = grid.world(Vec3d(bi * 8 + 3.5, bj * 8 + 3.5, bk * 8 + 3.5));
                                    if (std::abs(dot(cen - a, nrm)) > reach + halfdiag) continue;
                                }
                                const std::size_t at =
                                    (std::size_t(bk - r.lo[2]) * std::size_t(rd[1]) + std::size_t(bj - r.lo[1])) *
                                        std::size_t(rd[0]) +
                                    std::size_t(bi - r.lo[0]);
                                std::atomic_ref<std::uint8_t>(out[at]).store(1, std::memory_order_relaxed);
                            }
                }
            });
        });
        return out;
    };
    std::vector<std::uint8_t> cand = marks(BlockWindow{w.lo, {w.lo[0] + bd[0], w.lo[1] + bd[1], w.lo[2] + bd[2]}});
    std::vector<std::array<int, 3>> cands;
    for (int bk = 0; bk < bd[2]; ++bk)
        for (int bj = 0; bj < bd[1]; ++bj)
            for (int bi = 0; bi < bd[0]; ++bi)
                if (cand[vol.table_index(bi, bj, bk)]) cands.push_back(global_block(bi, bj, bk));
    cand = {};
    rep.candidate_blocks = cands.size();

    // 2. Distances and signs per candidate block, in chunks (bounded scratch memory).
    const Context ctx{grid, q, wn, h, reach, shell_off, bg};
    constexpr std::size_t kChunk = 512;  // also the cancel granularity: ~0.1 s of work per chunk
    std::vector<float> scratch;
    std::vector<BlockStats> stats;
    bool any_inside = false;
    for (std::size_t c0 = 0; c0 < cands.size(); c0 += kChunk) {
        const std::size_t c1 = std::min(cands.size(), c0 + kChunk);
        scratch.resize((c1 - c0) * kBlockVoxels);
        stats.assign(c1 - c0, BlockStats{});
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(c0, c1, 4), [&](const auto& range) {
                for (std::size_t i = range.begin(); i != range.end(); ++i)
                    stats[i - c0] = process_block(ctx, cands[i], scratch.data() + (i - c0) * kBlockVoxels);
            });
        });
        for (std::size_t i = c0; i < c1; ++i) {
            const BlockStats& s = stats[i - c0];
            rep.uncertain_sign += s.uncertain;
            rep.winding_evaluations += s.evaluations;
            if (!s.keep) continue;
            any_inside |= s.inside;
            rep.band_voxels += s.band;
            const auto& b = cands[i];
            const std::int32_t slot = vol.allocate_block(b[0] - w.lo[0], b[1] - w.lo[1], b[2] - w.lo[2]);
            std::copy_n(scratch.data() + (i - c0) * kBlockVoxels, kBlockVoxels, vol.block_values(slot));
        }
        detail::tick(progress, double(c1) / double(cands.size()), "scan_convert");
    }
    scratch = {};
    rep.seconds_distance += seconds_since(t_dist0);
    if (whole && wn && !any_inside)
        throw InvalidInput(
            "scan_convert: the mesh encloses no volume (winding number > 1/2 nowhere near it: an "
            "open sheet, or oriented inside-out); use --shell T (shell_thickness) to treat it as a "
            "thin shell");

    // 3. Tile signs of unallocated blocks: scan each block row along x, starting outside (the whole grid's border
    // is outside). A window's row starts as the whole grid's row runs there: with the sign the last block the whole
    // scan keeps before the window leaves (found from the window's side outwards), outside where it keeps none. Near
    // the holes of an open mesh that sign is not the winding number's, and rows that started from it allocated
    // other conflict blocks than the whole scan: iron.ply at 256 in windows of 64 (halo 32) disagreed on 130 tiles
    // and 852 blocks, and the bricks' surface on the shared scan stood 0.14 voxel from the whole run's.
    const auto t_tile0 = Clock::now();
    // the sign of the largest |φ| on a kept block's last in-grid x-layer (global block bi of a row)
    const auto leaves = [&](const float* vals, int bi, int bj, int bk) {
        const int li = std::min(kBlockDim - 1, grid.dims[0] - 1 - bi * kBlockDim);
        float best = 0;
        for (int lk = 0; lk < kBlockDim; ++lk)
            for (int lj = 0; lj < kBlockDim; ++lj) {
                if (!grid.contains(bi * 8 + li, bj * 8 + lj, bk * 8 + lk)) continue;
                const float v = vals[Volume::local_index(li, lj, lk)];
                if (std::abs(v) > std::abs(best)) best = v;
            }
        return best < 0 ? kBlockInside : kBlockOutside;
    };
    std::vector<std::int32_t> row_start(std::size_t(bd[1]) * std::size_t(bd[2]), kBlockOutside);
    if (!whole && w.lo[0] > 0) {
        const BlockWindow before{{0, w.lo[1], w.lo[2]}, {w.lo[0], w.lo[1] + bd[1], w.lo[2] + bd[2]}};
        const std::vector<std::uint8_t> left = marks(before);
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<int>(0, bd[1] * bd[2], 4), [&](const auto& range) {
                std::vector<float> values(kBlockVoxels);
                for (int row = range.begin(); row != range.end(); ++row) {
                    const int bj = row % bd[1], bk = row / bd[1];
                    if (vol.block_table[vol.table_index(0, bj, bk)] >= 0) continue;  // the row starts from its own
                    for (int bi = w.lo[0] - 1; bi >= 0; --bi) {
                        if (!left[(std::size_t(row)) * std::size_t(w.lo[0]) + std::size_t(bi)]) continue;
                        const BlockStats st = process_block(ctx, {bi, bj + w.lo[1], bk + w.lo[2]}, values.data());
                        if (!st.keep) continue;
                        row_start[std::size_t(row)] = leaves(values.data(), bi, bj + w.lo[1], bk + w.lo[2]);
                        break;
                    }
                }
            });
        });
    }
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, bd[1] * bd[2], 16), [&](const auto& range) {
            for (int row = range.begin(); row != range.end(); ++row) {
                const int bj = row % bd[1], bk = row / bd[1];
                std::int32_t tile = row_start[std::size_t(row)];
                for (int bi = 0; bi < bd[0]; ++bi) {
                    std::int32_t& slot = vol.block_table[vol.table_index(bi, bj, bk)];
                    if (slot < 0) {
                        slot = tile;
                        continue;
                    }
                    const auto g = global_block(bi, bj, bk);
                    tile = leaves(vol.block_values(slot), g[0], g[1], g[2]);
                }
            }
        });
    });
    row_start = {};
    // 4. Tile conflicts. extract_surface visits only cubes with a corner in an allocated block, so two
    // unallocated blocks that share a cube (26-neighbours) must have the same tile sign, and no inside
    // tile may touch the grid border. On a closed mesh this always holds; near the holes of an open
    // mesh the row scan can disagree between rows, or an inside region can run out to the border.
    // Allocate every inside tile that touches an outside tile (filled with -background): the level
    // set then closes between them. Marked in parallel, allocated in block order (deterministic). A window's
    // side inside the grid is no border: what lies beyond it is another window's to check.
    std::vector<std::uint8_t> conflict(vol.block_table.size(), 0);
    const auto& gbd = [&] {
        std::array<int, 3> d{};
        for (int a = 0; a < 3; ++a) d[a] = (grid.dims[a] + kBlockDim - 1) / kBlockDim;
        return d;
    }();
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, bd[1] * bd[2], 16), [&](const auto& range) {
            for (int row = range.begin(); row != range.end(); ++row) {
                const int bj = row % bd[1], bk = row / bd[1];
                for (int bi = 0; bi < bd[0]; ++bi) {
                    if (vol.block_table[vol.table_index(bi, bj, bk)] != kBlockInside) continue;
                    bool hit = false;
                    for (int dk = -1; dk <= 1 && !hit; ++dk)
                        for (int dj = -1; dj <= 1 && !hit; ++dj)
                            for (int di = -1; di <= 1 && !hit; ++di) {
                                const int ni = bi + di, nj = bj + dj, nk = bk + dk;
                                if (ni < 0 || nj < 0 || nk < 0 || ni >= bd[0] || nj >= bd[1] || nk >= bd[2]) {
                                    // Beyond the grid counts as outside (extract_surface reads +background there).
                                    const auto g = global_block(ni, nj, nk);
                                    hit = g[0] < 0 || g[1] < 0 || g[2] < 0 || g[0] >= gbd[0] || g[1] >= gbd[1] ||
                                          g[2] >= gbd[2];
                                } else {
                                    hit = vol.block_table[vol.table_index(ni, nj, nk)] == kBlockOutside;
                                }
                            }
                    conflict[vol.table_index(bi, bj, bk)] = hit;
                }
            }
        });
    });
    for (int bk = 0; bk < bd[2]; ++bk)
        for (int bj = 0; bj < bd[1]; ++bj)
            for (int bi = 0; bi < bd[0]; ++bi)
                if (conflict[vol.table_index(bi, bj, bk)]) {
                    vol.allocate_block(bi, bj, bk);
                    ++rep.tile_conflict_blocks;
                }
    conflict = {};
    rep.seconds_sign += seconds_since(t_tile0);

    rep.blocks = vol.block_count();
    rep.memory_bytes = vol.memory_bytes();
    if (rep.uncertain_sign > 0 || rep.tile_conflict_blocks > 0) {
        std::string detail;
        if (rep.uncertain_sign > 0)
            detail = "inside and outside uncertain at " + std::to_string(rep.uncertain_sign) + " samples near them";
        if (rep.tile_conflict_blocks > 0)
            detail += (detail.empty() ? "" : "; ") + std::to_string(rep.tile_conflict_blocks) +
                      " blocks away from the surface taken as inside";
        rep.open_mesh_warning =
            "scan_convert: the mesh is open (holes or boundaries): the volume is closed across them (" + detail + ")";
        rep.warnings.push_back(rep.open_mesh_warning);
    }
    return vol;
}

}  // namespace

Grid window_grid(const Grid& g, const BlockWindow& w) {
    Grid sub = g;
    for (int a = 0; a < 3; ++a) {
        sub.origin[a] = g.origin[a] + double(w.lo[a] * kBlockDim) * g.voxel_size;
        sub.dims[a] = std::min(w.hi[a] * kBlockDim, g.dims[a]) - w.lo[a] * kBlockDim;
    }
    return sub;
}

Grid scan_grid(const Mesh& m, const ScanConvertOptions& opt) {
    if (m.empty()) throw InvalidInput("scan_convert: empty mesh (no triangles)");
    check_scan_options(opt);
    Box3d box;
    for (const Tri& t : m.triangles)
        for (int c = 0; c < 3; ++c) box.extend(Vec3d(m.positions[t[c]]));
    const Vec3d size = box.size();
    const double h = opt.voxel_size > 0 ? opt.voxel_size : box.longest_side() / opt.resolution;
    if (!(h > 0))
        throw InvalidInput("scan_convert: the mesh has zero extent; set voxel_size to choose the grid spacing");
    const double hw = opt.half_width;
    const double shell_off = opt.shell_thickness * 0.5;
    const int pad = int(std::ceil(hw + 2.0 + shell_off / h));
    Grid grid;
    grid.voxel_size = h;
    grid.origin = box.min - Vec3d(pad, pad, pad) * h;
    double blocks_total = 1;
    for (int a = 0; a < 3; ++a) {
        const double n = std::ceil(size[a] / h) + 1 + 2.0 * pad;
        if (n > 1 << 28)
            throw OutOfMemory("scan_convert: grid would have " + std::to_string(n) + " samples along an axis");
        grid.dims[a] = int(n);
        blocks_total *= std::ceil(n / kBlockDim);
    }
    if (blocks_total > double(1u << 31))
        throw OutOfMemory("scan_convert: the block table would have " + std::to_string(blocks_total) +
                          " entries (over 2^31); use a coarser resolution");
    return grid;
}

Volume scan_convert(const Mesh& m, const ClosestTriangleQuery& q, const ScanConvertOptions& opt,
                    ScanConvertReport* report, Progress* progress) {
    if (m.empty()) throw InvalidInput("scan_convert: empty mesh (no triangles)");
    check_mesh(m, "scan_convert");
    check_scan_options(opt);
    detail::begin(progress, "voxelize");
    const Grid grid = scan_grid(m, opt);
    ScanConvertReport rep;
    // Sign oracle (built up front; its time goes to seconds_sign).
    const auto t_sign0 = Clock::now();
    std::unique_ptr<WindingNumber> wn;
    tbb::task_arena arena(opt.threads > 0 ? opt.threads : tbb::task_arena::automatic);
    if (opt.shell_thickness == 0) arena.execute([&] { wn = std::make_unique<WindingNumber>(m); });
    rep.seconds_sign += seconds_since(t_sign0);
    BlockWindow all;
    for (int a = 0; a < 3; ++a) all.hi[a] = (grid.dims[a] + kBlockDim - 1) / kBlockDim;
    Volume vol = scan_window(m, q, wn.get(), grid, all, true, opt, rep, progress);
    if (report) *report = std::move(rep);
    return vol;
}

Volume scan_convert_window(const Mesh& m, const ClosestTriangleQuery& q, const WindingNumber* wn, const Grid& grid,
                           const BlockWindow& window, const ScanConvertOptions& opt, ScanConvertReport* report,
                           Progress* progress) {
    if (m.empty()) throw InvalidInput("scan_convert: empty mesh (no triangles)");
    check_scan_options(opt);
    if (!wn && opt.shell_thickness == 0)
        throw InvalidInput("scan_convert_window: a winding number is needed unless shell_thickness > 0");
    std::array<int, 3> gbd{};
    for (int a = 0; a < 3; ++a) {
        gbd[a] = (grid.dims[a] + kBlockDim - 1) / kBlockDim;
        if (window.lo[a] < 0 || window.hi[a] > gbd[a] || window.lo[a] >= window.hi[a])
            throw InvalidInput("scan_convert_window: the window's blocks along axis " + std::to_string(a) + " are [" +
                               std::to_string(window.lo[a]) + ", " + std::to_string(window.hi[a]) +
                               "), expected a non-empty range within [0, " + std::to_string(gbd[a]) + ")");
    }
    ScanConvertReport rep;
    Volume vol = scan_window(m, q, wn, grid, window, false, opt, rep, progress);
    if (report) *report = std::move(rep);
    return vol;
}

}  // namespace normalflow
