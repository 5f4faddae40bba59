#include "fit/face_filter.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/errors.h"
#include "fit/weld.h"

namespace normalflow {

namespace {

template <class F>
void parallel(std::size_t n, F&& f) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
}

/// Compressed rows: row i is items[start[i] .. start[i + 1]).
struct Rows {
    std::vector<std::uint32_t> start, items;
    std::size_t size(std::size_t i) const { return start[i + 1] - start[i]; }
    const std::uint32_t* begin(std::size_t i) const { return items.data() + start[i]; }
    const std::uint32_t* end(std::size_t i) const { return items.data() + start[i + 1]; }
};

}  // namespace

FaceFilterReport filter_faces(Mesh& m, const FaceFilterOptions& o, const std::vector<Vec3d>* guidance,
                              const std::vector<char>* held, std::vector<Vec3d>* filtered_normals) {
    if (o.normal_steps < 0 || o.vertex_steps < 0 || o.rings < 1 || !(o.sigma_r > 0) || !(o.sigma_s > 0) ||
        !std::isfinite(o.sigma_r) || !std::isfinite(o.sigma_s) || !(o.own_patch_bias > 0 && o.own_patch_bias <= 1) ||
        !(o.stop_displacement >= 0) || !std::isfinite(o.stop_displacement))
        throw InvalidInput(
            "filter_faces: normal_steps and vertex_steps must be >= 0, rings >= 1, sigma_r and sigma_s finite and > 0, "
            "own_patch_bias in (0, 1], stop_displacement finite and >= 0");
    check_mesh(m, "filter_faces");
    const std::size_t nf = m.triangles.size();
    if (guidance && guidance->size() != nf)
        throw InvalidInput("filter_faces: " + std::to_string(guidance->size()) + " guidance normals for " +
                           std::to_string(nf) + " faces");
    if (held && held->size() != m.positions.size())
        throw InvalidInput("filter_faces: " + std::to_string(held->size()) + " held flags for " +
                           std::to_string(m.positions.size()) + " positions");
    FaceFilterReport rep;
    std::vector<std::uint32_t> group;
    const std::size_t n = detail::weld(m, group);
    std::vector<Vec3d> x(n);
    std::vector<char> fixed(n, 0);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        x[group[i]] = Vec3d(m.positions[i]);
        if (held && (*held)[i]) fixed[group[i]] = 1;
    }
    {
        const std::vector<char> on = detail::boundary_vertices(m, group, n);
        for (std::size_t i = 0; i < n; ++i) fixed[i] = fixed[i] || on[i];
    }
    // the welded faces that have three distinct vertices
    std::vector<std::array<std::uint32_t, 3>> tri(nf);
    std::vector<char> live(nf, 0);
    for (std::size_t f = 0; f < nf; ++f) {
        const Tri& t = m.triangles[f];
        tri[f] = {group[t[0]], group[t[1]], group[t[2]]};
        live[f] = tri[f][0] != tri[f][1] && tri[f][1] != tri[f][2] && tri[f][0] != tri[f][2];
        rep.faces += std::size_t(live[f]);
    }
    // vertex → faces
    Rows vf;
    vf.start.assign(n + 1, 0);
    for (std::size_t f = 0; f < nf; ++f)
        if (live[f])
            for (std::uint32_t a : tri[f]) ++vf.start[a + 1];
    for (std::size_t i = 0; i < n; ++i) vf.start[i + 1] += vf.start[i];
    vf.items.resize(vf.start[n]);
    {
        std::vector<std::uint32_t> fill(vf.start.begin(), vf.start.end() - 1);
        for (std::size_t f = 0; f < nf; ++f)
            if (live[f])
                for (std::uint32_t a : tri[f]) vf.items[fill[a]++] = std::uint32_t(f);
    }
    // face → the faces of its vertex ring (itself included), sorted; then `rings` rings of those
    const auto ring_of = [&](std::size_t f, std::vector<std::uint32_t>& out) {
        out.clear();
        for (std::uint32_t a : tri[f]) out.insert(out.end(), vf.begin(a), vf.end(a));
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    };
    const auto build_rows = [&](int rings) {
        std::vector<std::vector<std::uint32_t>> rows(nf);
        parallel(nf, [&](std::size_t f) {
            if (!live[f]) return;
            std::vector<std::uint32_t> cur, tmp, next;
            ring_of(f, cur);
            for (int r = 1; r < rings; ++r) {
                next = cur;
                for (std::uint32_t k : cur) {
                    ring_of(k, tmp);
                    next.insert(next.end(), tmp.begin(), tmp.end());
                }
                std::sort(next.begin(), next.end());
                next.erase(std::unique(next.begin(), next.end()), next.end());
                cur.swap(next);
            }
            rows[f] = std::move(cur);
        });
        Rows out;
        out.start.assign(nf + 1, 0);
        for (std::size_t f = 0; f < nf; ++f) out.start[f + 1] = out.start[f] + std::uint32_t(rows[f].size());
        out.items.resize(out.start[nf]);
        for (std::size_t f = 0; f < nf; ++f)
            std::copy(rows[f].begin(), rows[f].end(), out.items.begin() + out.start[f]);
        return out;
    };
    const Rows patch = build_rows(1);
    const Rows hood = o.rings == 1 ? patch : build_rows(o.rings);

    std::vector<Vec3d> normal(nf), centre(nf), guide(nf), filtered(nf);
    std::vector<double> area(nf, 0.0);
    const auto measure = [&] {
        parallel(nf, [&](std::size_t f) {
            if (!live[f]) return;
            const Vec3d &a = x[tri[f][0]], &b = x[tri[f][1]], &c = x[tri[f][2]];
            const Vec3d cr = cross(b - a, c - a);
            const double len = norm(cr);
            area[f] = 0.5 * len;
            normal[f] = len > 0 ? cr / len : Vec3d(0, 0, 0);
            centre[f] = (a + b + c) / 3.0;
        });
    };
    measure();
    // σ_s: the mean distance between the centroids of faces that share a vertex
    double spacing = 0.0;
    {
        std::vector<double> per(nf, 0.0);
        std::vector<std::uint32_t> count(nf, 0);
        parallel(nf, [&](std::size_t f) {
            if (!live[f]) return;
            for (const std::uint32_t* k = patch.begin(f); k != patch.end(f); ++k)
                if (*k != f) {
                    per[f] += norm(centre[*k] - centre[f]);
                    ++count[f];
                }
        });
        double sum = 0.0;
        std::size_t cnt = 0;
        for (std::size_t f = 0; f < nf; ++f) sum += per[f], cnt += count[f];
        spacing = cnt ? sum / double(cnt) : 0.0;
    }
    if (!(spacing > 0) || rep.faces == 0) return rep;
    const double inv_s = 1.0 / (2.0 * std::pow(o.sigma_s * spacing, 2));
    const double inv_r = 1.0 / (2.0 * o.sigma_r * o.sigma_r);

    std::vector<Vec3d> next(n), base(nf);
    std::vector<char> revert(n, 0);
    const std::vector<Vec3d> start = x;
    // the vertices' root-mean-square distance from where they began (a sum in a fixed order: thread-independent)
    const auto rms_displacement = [&] {
        double sum = 0.0;
        for (std::size_t i = 0; i < n; ++i) sum += dot(x[i] - start[i], x[i] - start[i]);
        return std::sqrt(sum / double(n));
    };
    for (int round = 0; round < o.normal_steps; ++round) {
        if (o.stop_displacement > 0 && rep.rms_displacement >= o.stop_displacement) break;
        ++rep.rounds;
        // the normals the guidance is built from: the given ones, else the current ones
        parallel(nf, [&](std::size_t f) {
            base[f] = normal[f];
            if (guidance && norm((*guidance)[f]) > 0.5) base[f] = (*guidance)[f];
        });
        if (o.patch_guidance) {
            parallel(nf, [&](std::size_t f) {
                if (!live[f]) return;
                // a patch's area-weighted mean base normal and its spread (the largest distance from it)
                const auto mean_and_spread = [&](std::uint32_t j, Vec3d& mean) {
                    mean = Vec3d(0, 0, 0);
                    for (const std::uint32_t* k = patch.begin(j); k != patch.end(j); ++k)
                        mean = mean + base[*k] * area[*k];
                    const double len = norm(mean);
                    if (!(len > 0)) return std::numeric_limits<double>::infinity();
                    mean = mean / len;
                    double spread = 0.0;
                    for (const std::uint32_t* k = patch.begin(j); k != patch.end(j); ++k)
                        if (area[*k] > 0) spread = std::max(spread, norm(base[*k] - mean));
                    return spread;
                };
                // the face's own patch first: another one wins only if clearly more consistent
                Vec3d chosen = base[f], mean;
                double best = std::numeric_limits<double>::infinity();
                if (const double own = mean_and_spread(std::uint32_t(f), mean); own < best) {
                    best = own * o.own_patch_bias;
                    chosen = mean;
                }
                for (const std::uint32_t* j = patch.begin(f); j != patch.end(f); ++j)
                    if (*j != f)
                        if (const double spread = mean_and_spread(*j, mean); spread < best) {
                            best = spread;
                            chosen = mean;
                        }
                guide[f] = chosen;
            });
        } else {
            guide = base;
        }
        // joint bilateral filter of the normals
        parallel(nf, [&](std::size_t f) {
            if (!live[f]) return;
            Vec3d sum(0, 0, 0);
            for (const std::uint32_t* k = hood.begin(f); k != hood.end(f); ++k) {
                const Vec3d d = centre[*k] - centre[f];
                const Vec3d g = guide[*k] - guide[f];
                sum = sum + normal[*k] * (area[*k] * std::exp(-dot(d, d) * inv_s - dot(g, g) * inv_r));
            }
            const double len = norm(sum);
            filtered[f] = len > 0 ? sum / len : normal[f];
        });
        // vertex update toward the filtered normals; no face turns over
        for (int s = 0; s < o.vertex_steps; ++s) {
            parallel(n, [&](std::size_t i) {
                next[i] = x[i];
                if (fixed[i] || vf.size(i) == 0) return;
                Vec3d sum(0, 0, 0);
                for (const std::uint32_t* k = vf.begin(i); k != vf.end(i); ++k) {
                    const auto& t = tri[*k];
                    const Vec3d c = (x[t[0]] + x[t[1]] + x[t[2]]) / 3.0;
                    sum = sum + filtered[*k] * dot(filtered[*k], c - x[i]);
                }
                next[i] = x[i] + sum / double(vf.size(i));
            });
            for (;;) {  // each pass undoes at least one move, so this ends
                std::fill(revert.begin(), revert.end(), 0);
                bool any = false;
                for (std::size_t f = 0; f < nf; ++f) {
                    if (!live[f]) continue;
                    const auto& t = tri[f];
                    // against the given guidance where there is one (the volume's side of the surface)
                    const Vec3d& ref = base[f];
                    const Vec3d cr = cross(next[t[1]] - next[t[0]], next[t[2]] - next[t[0]]);
                    const Vec3d was = cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]]);
                    // a face already turned is not this move's doing
                    const bool turns = (dot(was, ref) > 0 && dot(cr, ref) <= 0) ||
                                       (dot(was, filtered[f]) > 0 && dot(cr, filtered[f]) <= 0);
                    if (!turns) continue;
                    for (std::uint32_t a : t)
                        if (next[a] != x[a]) revert[a] = 1, any = true;
                }
                if (!any) break;
                for (std::size_t i = 0; i < n; ++i)
                    if (revert[i]) next[i] = x[i], ++rep.reverted_moves;
            }
            x.swap(next);
        }
        measure();
        rep.rms_displacement = rms_displacement();
    }
    for (std::size_t i = 0; i < m.positions.size(); ++i) m.positions[i] = Vec3f(x[group[i]]);
    if (filtered_normals) *filtered_normals = filtered;
    return rep;
}

}  // namespace normalflow
