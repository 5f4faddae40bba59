#include "extract/extract_surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "core/errors.h"

namespace normalflow {
namespace {

// The 6 Kuhn tetrahedra of the unit cube, as corner codes (bit 0: +x, bit 1: +y, bit 2: +z), each
// positively oriented: v0 = 0, then one axis at a time, v3 = 7 (odd axis orders swap v2 and v3).
constexpr std::array<std::array<int, 4>, 6> kTets = {{
    {0, 1, 3, 7},  // x, y, z (even)
    {0, 2, 7, 3},  // y, x, z (odd)
    {0, 2, 6, 7},  // y, z, x (even)
    {0, 4, 7, 6},  // z, y, x (odd)
    {0, 4, 5, 7},  // z, x, y (even)
    {0, 1, 7, 5},  // x, z, y (odd)
}};

// Even permutations with a given first element / first pair (see extract_surface.h for the rule).
constexpr std::array<std::array<int, 4>, 4> kAlone = {{{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}}};

using Key = std::uint64_t;

struct Keyer {
    std::uint64_t sx, sy;  // (dims + 2) along x, y
    // Key of the grid edge between cube corners cu and cw (one a subset of the other) of cube base c.
    Key operator()(const std::array<int, 3>& c, int cu, int cw) const {
        if ((cu & cw) != cu) std::swap(cu, cw);
        const std::uint64_t i = std::uint64_t(c[0] + 1 + (cu & 1)), j = std::uint64_t(c[1] + 1 + ((cu >> 1) & 1)),
                            k = std::uint64_t(c[2] + 1 + ((cu >> 2) & 1));
        return (((k * sy + j) * sx + i) << 3) | std::uint64_t(cu ^ cw);
    }
};

struct BlockOut {
    std::vector<std::array<Key, 3>> tris;
};

}  // namespace

Mesh extract_surface(const Volume& v, const ExtractOptions& opt, ExtractReport* report) {
    v.check("extract_surface");
    if (!std::isfinite(opt.iso) || !(std::abs(opt.iso) < v.background))
        throw InvalidInput("extract_surface: iso is " + std::to_string(opt.iso) + ", expected |iso| < background " +
                           std::to_string(v.background));
    const Grid& g = v.grid;
    const float iso = float(opt.iso);
    const Keyer keyer{std::uint64_t(g.dims[0]) + 2, std::uint64_t(g.dims[1]) + 2};
    const std::size_t allocated = v.block_count();
    // Inside tiles (unallocated, -background) next to an outside tile or to the grid's exterior: the level
    // set also passes between such blocks, where no allocated block sees it (an open input's closed volume
    // does this: its inside can reach the border). They are visited after the allocated blocks.
    std::vector<std::array<int, 3>> tiles;
    std::vector<char> is_tile_visited(v.block_table.size(), 0);
    for (int bk = 0; bk < v.block_dims[2]; ++bk)
        for (int bj = 0; bj < v.block_dims[1]; ++bj)
            for (int bi = 0; bi < v.block_dims[0]; ++bi) {
                const std::size_t t = v.table_index(bi, bj, bk);
                if (v.block_table[t] != kBlockInside) continue;
                bool borders = (bi + 1) * kBlockDim >= g.dims[0] || (bj + 1) * kBlockDim >= g.dims[1] ||
                               (bk + 1) * kBlockDim >= g.dims[2];
                for (int n = 0; n < 27 && !borders; ++n) {
                    const int ni = bi + n % 3 - 1, nj = bj + n / 3 % 3 - 1, nk = bk + n / 9 - 1;
                    borders = ni < 0 || nj < 0 || nk < 0 || ni >= v.block_dims[0] || nj >= v.block_dims[1] ||
                              nk >= v.block_dims[2] || v.block_table[v.table_index(ni, nj, nk)] == kBlockOutside;
                }
                if (borders) {
                    tiles.push_back({bi, bj, bk});
                    is_tile_visited[t] = 1;
                }
            }
    const std::size_t nb = allocated + tiles.size();
    std::vector<BlockOut> outs(nb);

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 8), [&](const auto& range) {
        // Values of samples [8b − 1, 8b + 8]³ of the block, minus iso.
        constexpr int C = kBlockDim + 2;
        float cache[C * C * C];
        for (std::size_t slot = range.begin(); slot != range.end(); ++slot) {
            const bool tile = slot >= allocated;
            const auto& b = tile ? tiles[slot - allocated] : v.block_coords[slot];
            const std::size_t self = v.table_index(b[0], b[1], b[2]);
            const int x0 = b[0] * kBlockDim - 1, y0 = b[1] * kBlockDim - 1, z0 = b[2] * kBlockDim - 1;
            for (int k = 0; k < C; ++k)
                for (int j = 0; j < C; ++j)
                    for (int i = 0; i < C; ++i) cache[(k * C + j) * C + i] = v.value(x0 + i, y0 + j, z0 + k) - iso;
            BlockOut& out = outs[slot];
            for (int lk = 0; lk < C - 1; ++lk)
                for (int lj = 0; lj < C - 1; ++lj)
                    for (int li = 0; li < C - 1; ++li) {
                        const std::array<int, 3> c{x0 + li, y0 + lj, z0 + lk};
                        if (c[0] >= g.dims[0] || c[1] >= g.dims[1] || c[2] >= g.dims[2]) continue;
                        float val[8];
                        int inside = 0;
                        for (int q = 0; q < 8; ++q) {
                            val[q] = cache[((lk + (q >> 2 & 1)) * C + lj + (q >> 1 & 1)) * C + li + (q & 1)];
                            inside |= (val[q] < 0 ? 1 : 0) << q;
                        }
                        if (inside == 0 || inside == 255) continue;
                        // Border cubes: visited by the first allocated block (in table order) holding a corner,
                        // or, when no allocated block holds one, by the first visited tile.
                        if (li == 0 || lj == 0 || lk == 0 || li == C - 2 || lj == C - 2 || lk == C - 2) {
                            std::size_t owner = self;
                            bool allocated_corner = false;
                            for (int q = 0; q < 8; ++q) {
                                const int ci = c[0] + (q & 1), cj = c[1] + (q >> 1 & 1), ck = c[2] + (q >> 2 & 1);
                                if (ci < 0 || cj < 0 || ck < 0) continue;
                                const int bi = ci >> kBlockLog2, bj = cj >> kBlockLog2, bk = ck >> kBlockLog2;
                                if (bi >= v.block_dims[0] || bj >= v.block_dims[1] || bk >= v.block_dims[2]) continue;
                                const std::size_t t = v.table_index(bi, bj, bk);
                                if (v.block_table[t] >= 0) {
                                    if (!allocated_corner || t < owner) owner = t;
                                    allocated_corner = true;
                                } else if (tile && !allocated_corner && is_tile_visited[t] && t < owner) {
                                    owner = t;
                                }
                            }
                            if (owner != self || (tile && allocated_corner)) continue;
                        }
                        for (const auto& tet : kTets) {
                            int mask = 0;
                            for (int a = 0; a < 4; ++a) mask |= ((inside >> tet[a]) & 1) << a;
                            const int n_in = __builtin_popcount(unsigned(mask));
                            if (n_in == 0 || n_in == 4) continue;
                            auto e = [&](int a, int b2) { return keyer(c, tet[a], tet[b2]); };
                            if (n_in == 1 || n_in == 3) {
                                int s = 0;  // the vertex alone on its side
                                const int alone_mask = n_in == 1 ? mask : (~mask & 15);
                                while (!((alone_mask >> s) & 1)) ++s;
                                const auto& p = kAlone[std::size_t(s)];
                                if (n_in == 1)
                                    out.tris.push_back({e(p[0], p[1]), e(p[0], p[2]), e(p[0], p[3])});
                                else
                                    out.tris.push_back({e(p[0], p[1]), e(p[0], p[3]), e(p[0], p[2])});
                            } else {
                                // Inside pair {a, b}, outside {c, d}, (a, b, c, d) an even permutation.
                                std::array<int, 4> p;
                                switch (mask) {
                                    case 0b0011: p = {0, 1, 2, 3}; break;
                                    case 0b0101: p = {0, 2, 3, 1}; break;
                                    case 0b1001: p = {0, 3, 1, 2}; break;
                                    case 0b0110: p = {1, 2, 0, 3}; break;
                                    case 0b1010: p = {1, 3, 2, 0}; break;
                                    default: p = {2, 3, 0, 1}; break;  // 0b1100
                                }
                                const Key ac = e(p[0], p[2]), ad = e(p[0], p[3]), bd = e(p[1], p[3]),
                                          bc = e(p[1], p[2]);
                                out.tris.push_back({ac, ad, bd});
                                out.tris.push_back({ac, bd, bc});
                            }
                        }
                    }
        }
    });

    // Weld: vertices are the sorted distinct edge keys.
    std::size_t nt = 0;
    std::vector<std::size_t> offset(nb + 1, 0);
    for (std::size_t s = 0; s < nb; ++s) offset[s + 1] = offset[s] + outs[s].tris.size();
    nt = offset[nb];
    std::vector<Key> keys(nt * 3);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 16), [&](const auto& range) {
        for (std::size_t s = range.begin(); s != range.end(); ++s)
            for (std::size_t t = 0; t < outs[s].tris.size(); ++t)
                for (int c = 0; c < 3; ++c)
                    keys[3 * (offset[s] + t) + std::size_t(c)] = outs[s].tris[t][std::size_t(c)];
    });
    std::vector<Key> unique_keys = keys;
    tbb::parallel_sort(unique_keys.begin(), unique_keys.end());
    unique_keys.erase(std::unique(unique_keys.begin(), unique_keys.end()), unique_keys.end());

    Mesh mesh;
    mesh.positions.resize(unique_keys.size());
    mesh.triangles.resize(nt);
    const std::uint64_t sx = keyer.sx, sy = keyer.sy;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, unique_keys.size(), 4096), [&](const auto& range) {
        for (std::size_t n = range.begin(); n != range.end(); ++n) {
            const Key key = unique_keys[n];
            const int dir = int(key & 7);
            std::uint64_t lin = key >> 3;
            const int i = int(lin % sx) - 1;
            lin /= sx;
            const int j = int(lin % sy) - 1;
            const int k = int(lin / sy) - 1;
            const int di = dir & 1, dj = dir >> 1 & 1, dk = dir >> 2 & 1;
            const double a = double(v.value(i, j, k)) - iso, b = double(v.value(i + di, j + dj, k + dk)) - iso;
            const double t = std::clamp(a / (a - b), 1e-3, 1.0 - 1e-3);
            mesh.positions[n] = Vec3f(g.world(Vec3d(i + t * di, j + t * dj, k + t * dk)));
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 4096), [&](const auto& range) {
        for (std::size_t t = range.begin(); t != range.end(); ++t)
            for (int c = 0; c < 3; ++c) {
                const Key key = keys[3 * t + std::size_t(c)];
                mesh.triangles[t][std::size_t(c)] =
                    std::uint32_t(std::lower_bound(unique_keys.begin(), unique_keys.end(), key) - unique_keys.begin());
            }
    });
    if (report) {
        report->vertices = mesh.positions.size();
        report->triangles = mesh.triangles.size();
        report->closed = true;
        report->manifold = true;
    }
    return mesh;
}

}  // namespace normalflow
