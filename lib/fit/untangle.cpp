#include "fit/untangle.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/errors.h"
#include "extract/volume_sampler.h"
#include "fit/weld.h"

namespace normalflow {

UntangleReport untangle(Mesh& m, const Volume& v, double max_move, int max_passes) {
    if (max_passes < 0 || !(max_move >= 0) || !std::isfinite(max_move))
        throw InvalidInput("untangle: max_move must be finite and >= 0, max_passes >= 0");
    check_mesh(m, "untangle");
    v.check("untangle");
    UntangleReport rep;
    std::vector<std::uint32_t> group;
    const std::size_t n = detail::weld(m, group);
    std::vector<Vec3d> x(n);
    for (std::size_t i = 0; i < m.positions.size(); ++i) x[group[i]] = Vec3d(m.positions[i]);
    const std::vector<char> fixed = detail::boundary_vertices(m, group, n);
    const std::size_t nf = m.triangles.size();
    std::vector<std::array<std::uint32_t, 3>> tri;
    tri.reserve(nf);
    for (const Tri& t : m.triangles) {
        const std::array<std::uint32_t, 3> w{group[t[0]], group[t[1]], group[t[2]]};
        if (w[0] != w[1] && w[1] != w[2] && w[0] != w[2]) tri.push_back(w);
    }
    // each vertex's neighbours (sorted, distinct)
    std::vector<std::uint32_t> start(n + 1, 0), items;
    {
        std::vector<std::uint64_t> edges;
        edges.reserve(tri.size() * 6);
        for (const auto& t : tri)
            for (int e = 0; e < 3; ++e) {
                const std::uint64_t a = t[std::size_t(e)], b = t[std::size_t((e + 1) % 3)];
                edges.push_back(a << 32 | b);
                edges.push_back(b << 32 | a);
            }
        std::sort(edges.begin(), edges.end());
        edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
        for (const std::uint64_t e : edges) ++start[std::size_t(e >> 32) + 1];
        for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
        items.reserve(edges.size());
        for (const std::uint64_t e : edges) items.push_back(std::uint32_t(e));
    }
    const std::vector<Vec3d> start_x = x;
    const detail::VolumeSampler S(v);
    const auto folded = [&](std::vector<char>& out) {
        out.assign(tri.size(), 0);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tri.size(), 1024),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t f = r.begin(); f != r.end(); ++f)
                                  out[f] = S.turned_against(x[tri[f][0]], x[tri[f][1]], x[tri[f][2]]);
                          });
        return std::size_t(std::count(out.begin(), out.end(), char(1)));
    };
    std::vector<char> against, region(n);
    std::vector<Vec3d> next;
    rep.folded_before = rep.folded_after = folded(against);
    std::size_t least = rep.folded_after;
    std::vector<Vec3d> best = x;
    int since_least = 0, rings = 0;
    for (; rep.passes < max_passes && least > 0 && max_move > 0; ++rep.passes) {
        if (since_least >= kUntanglePatience) {  // stuck: the neighbours move too, then theirs
            if (rings == kUntangleRings) break;
            ++rings;
            since_least = 0;
        }
        // the vertices of the folded faces, and `rings` rings of their neighbours
        std::fill(region.begin(), region.end(), 0);
        for (std::size_t f = 0; f < tri.size(); ++f)
            if (against[f])
                for (const std::uint32_t a : tri[f]) region[a] = 1;
        for (int ring = 0; ring < rings; ++ring) {
            std::vector<char> grown = region;
            for (std::size_t i = 0; i < n; ++i)
                if (region[i])
                    for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) grown[items[k]] = 1;
            region.swap(grown);
        }
        next = x;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                if (!region[i] || fixed[i] || start[i] == start[i + 1] || S.outside_band(x[i])) continue;
                Vec3d c(0, 0, 0);
                for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) c = c + x[items[k]];
                c = c / double(start[i + 1] - start[i]);
                Vec3d g;
                S.phi(x[i], &g);
                const double len = norm(g);
                if (!(len > 0)) continue;
                g = g / len;
                const Vec3d d = c - x[i];
                next[i] = x[i] + d - g * dot(d, g);
                // no farther than max_move from where it began
                const Vec3d from = next[i] - start_x[i];
                if (const double far = norm(from); far > max_move) next[i] = start_x[i] + from * (max_move / far);
            }
        });
        x.swap(next);
        rep.folded_after = folded(against);
        if (rep.folded_after < least) {
            least = rep.folded_after;
            best = x;
            since_least = 0;
        } else {
            ++since_least;
        }
    }
    rep.folded_after = least;  // the pass with the fewest folds
    x.swap(best);
    if (least >= rep.folded_before) {  // no better: as it was
        rep.undone = rep.passes > 0;
    }
    for (std::size_t i = 0; i < n; ++i) rep.moved += Vec3f(x[i]) != Vec3f(start_x[i]);
    for (std::size_t i = 0; i < m.positions.size(); ++i) m.positions[i] = Vec3f(x[group[i]]);
    return rep;
}

}  // namespace normalflow
