#include "remesh/trim_to_footprint.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "core/union_find.h"

namespace normalflow {
namespace {

bool contains(const std::vector<std::uint64_t>& sorted, std::uint64_t k) {
    return std::binary_search(sorted.begin(), sorted.end(), k);
}

/// The faces f with keep[f] == which, grouped by vertex connectivity (through faces of the same
/// group), each with its size; in order of their first face.
std::vector<std::pair<std::vector<std::size_t>, std::size_t>> face_groups(const Mesh& m, const std::vector<char>& keep,
                                                                          char which) {
    std::vector<char> in(keep.size());
    for (std::size_t f = 0; f < keep.size(); ++f) in[f] = keep[f] == which;
    std::size_t n = 0;
    const std::vector<std::uint32_t> component = face_components(m, &in, &n);
    std::vector<std::pair<std::vector<std::size_t>, std::size_t>> out(n);
    for (std::size_t f = 0; f < component.size(); ++f)
        if (component[f] != kNoComponent) {
            out[component[f]].first.push_back(f);
            ++out[component[f]].second;
        }
    return out;
}

}  // namespace

TrimReport trim_to_footprint(Mesh& m, const Mesh& input, const ClosestTriangleQuery& q, double tolerance,
                             double max_distance) {
    check_mesh(m, "trim_to_footprint");
    check_mesh(input, "trim_to_footprint");
    if (!(tolerance > 0) || !std::isfinite(tolerance) || !(max_distance >= tolerance) || !std::isfinite(max_distance))
        throw InvalidInput("trim_to_footprint: tolerance " + std::to_string(tolerance) + " and max_distance " +
                           std::to_string(max_distance) + ", expected 0 < tolerance <= max_distance");
    TrimReport rep;
    // The input's open boundary, on welded vertices: per triangle, which edges (k, k+1) lie on it.
    std::vector<std::uint32_t> group;
    const Mesh w = weld_exact(input, &group);
    const std::vector<std::uint64_t> rim = single_face_edges(w.triangles);
    if (rim.empty()) return rep;
    std::vector<std::uint8_t> rim_edges(input.triangles.size(), 0);  // bit k: edge (k, k+1)
    std::vector<char> rim_vertex(w.positions.size(), 0);
    for (std::size_t f = 0; f < input.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = w.triangles[f][std::size_t(k)], b = w.triangles[f][std::size_t((k + 1) % 3)];
            if (a != b && contains(rim, edge_key(a, b))) {
                rim_edges[f] |= std::uint8_t(1 << k);
                rim_vertex[a] = rim_vertex[b] = 1;
            }
        }
    // The input's boundary loops: rim vertices joined along rim edges.
    detail::UnionFind<std::uint32_t> loops(w.positions.size());
    for (const std::uint64_t e : rim) loops.unite(std::uint32_t(e >> 32), std::uint32_t(e & 0xffffffffu));
    // Vertices of m beyond the rim, and for those that project onto it, the loop they project onto.
    constexpr std::uint32_t kNoLoop = UINT32_MAX;
    const double tol2 = tolerance * tolerance;
    std::vector<char> beyond(m.positions.size(), 0);
    std::vector<std::uint32_t> loop_of(m.positions.size(), kNoLoop);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.positions.size(), 512), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const ClosestHit h = q.closest(Vec3d(m.positions[i]));
            if (!h.found() || h.squared_distance <= tol2) continue;
            if (h.squared_distance > max_distance * max_distance) {
                beyond[i] = 1;
                continue;
            }
            const std::size_t f = h.triangle;
            const Tri& t = input.triangles[f];
            // barycentric coordinates of the closest point; a coordinate ~0 puts it on the opposite edge
            double bary[3];
            if (!barycentric_coordinates(h.point, Vec3d(input.positions[t[0]]), Vec3d(input.positions[t[1]]),
                                         Vec3d(input.positions[t[2]]), bary))
                continue;
            constexpr double eps = 1e-6;
            std::uint32_t on = kNoLoop;  // a welded rim vertex of the edge or corner the point lies on
            for (int k = 0; k < 3 && on == kNoLoop; ++k) {
                const std::uint32_t corner = group[t[std::size_t(k)]];
                // edge (k, k+1) is opposite corner k+2
                if ((rim_edges[f] >> k & 1) && bary[(k + 2) % 3] < eps) on = corner;
                // a rim vertex: the other two coordinates ~0
                if (bary[(k + 1) % 3] < eps && bary[(k + 2) % 3] < eps && rim_vertex[corner]) on = corner;
            }
            if (on != kNoLoop) {
                beyond[i] = 1;
                loop_of[i] = on;
            }
        }
    });
    std::vector<char> keep(m.triangles.size(), 1);
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
        for (const std::uint32_t v : m.triangles[f])
            if (beyond[v]) keep[f] = 0;
    // Each removed patch opens the input loops its vertices project onto. Where one loop has several
    // patches, the largest is its opening and the others are holes the surface near the rim punched
    // (a stretch a little off the input): they come back. A patch of far vertices only is cap.
    const auto patches = face_groups(m, keep, 0);
    std::vector<std::vector<std::uint32_t>> patch_loops(patches.size());
    std::vector<std::pair<std::uint32_t, std::size_t>> largest;  // per loop root: (root, patch), sorted by root
    for (std::size_t p = 0; p < patches.size(); ++p) {
        for (const std::size_t f : patches[p].first)
            for (const std::uint32_t v : m.triangles[f])
                if (loop_of[v] != kNoLoop) patch_loops[p].push_back(loops.find(loop_of[v]));
        std::sort(patch_loops[p].begin(), patch_loops[p].end());
        patch_loops[p].erase(std::unique(patch_loops[p].begin(), patch_loops[p].end()), patch_loops[p].end());
        for (const std::uint32_t l : patch_loops[p]) largest.emplace_back(l, p);
    }
    std::sort(largest.begin(), largest.end(), [&](const auto& a, const auto& b) {
        return a.first < b.first ||
               (a.first == b.first && (patches[a.second].second > patches[b.second].second ||
                                       (patches[a.second].second == patches[b.second].second && a.second < b.second)));
    });
    std::vector<char> opening(patches.size(), 0);
    for (std::size_t i = 0; i < largest.size(); ++i)
        if (i == 0 || largest[i].first != largest[i - 1].first) opening[largest[i].second] = 1;
    // A small patch far from the input that touches no loop is where the smoothing moved the surface
    // (a filled pit), not cap: it comes back too.
    for (std::size_t p = 0; p < patches.size(); ++p)
        if (patch_loops[p].empty() ? patches[p].second < m.triangles.size() / 100 : !opening[p])
            for (const std::size_t f : patches[p].first) keep[f] = 1;
    // Spikes: faces with two or three boundary edges, peeled until none is left (a few rounds).
    for (int round = 0; round < 8; ++round) {
        std::vector<Tri> alive;
        std::vector<std::size_t> index;
        for (std::size_t f = 0; f < m.triangles.size(); ++f)
            if (keep[f]) {
                alive.push_back(m.triangles[f]);
                index.push_back(f);
            }
        const std::vector<std::uint64_t> open = single_face_edges(alive);
        std::size_t peeled = 0;
        for (std::size_t i = 0; i < alive.size(); ++i) {
            int on = 0;
            for (int k = 0; k < 3; ++k)
                on += contains(open, edge_key(alive[i][std::size_t(k)], alive[i][std::size_t((k + 1) % 3)]));
            if (on >= 2) {
                keep[index[i]] = 0;
                ++peeled;
            }
        }
        if (peeled == 0) break;
    }
    // Small pieces the cut separated from the rest.
    std::size_t kept = 0;
    for (const char k : keep) kept += k != 0;
    for (const auto& [component, size] : face_groups(m, keep, 1))
        if (size < kept / 100) {
            ++rep.components_removed;
            for (const std::size_t f : component) keep[f] = 0;
        }
    // Compact: kept faces, referenced vertices, attributes with them.
    std::vector<std::uint32_t> remap(m.positions.size(), UINT32_MAX);
    Mesh out;
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
        if (!keep[f]) {
            ++rep.faces_removed;
            continue;
        }
        Tri t;
        for (std::size_t c = 0; c < 3; ++c) {
            std::uint32_t& r = remap[m.triangles[f][c]];
            if (r == UINT32_MAX) {
                const std::uint32_t v = m.triangles[f][c];
                r = std::uint32_t(out.positions.size());
                out.positions.push_back(m.positions[v]);
                if (m.has_normals()) out.normals.push_back(m.normals[v]);
                if (m.has_colors()) out.colors.push_back(m.colors[v]);
                if (m.has_texcoords()) out.texcoords.push_back(m.texcoords[v]);
            }
            t[c] = r;
        }
        out.triangles.push_back(t);
    }
    m = std::move(out);
    return rep;
}

}  // namespace normalflow
