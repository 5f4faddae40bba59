#include "core/mesh_report.h"
#include "core/union_find.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include <tbb/parallel_sort.h>

#include "core/errors.h"

namespace normalflow {

namespace {

/// New index of every position after exact welding (first occurrence order); returns #unique.
std::size_t weld_map(const std::vector<Vec3f>& p, std::vector<std::uint32_t>& old_to_new) {
    const std::size_t n = p.size();
    // +0.0f turns -0 into +0, so the two compare and sort as one value.
    auto key = [&](std::uint32_t i) { return Vec3f{p[i].x + 0.0f, p[i].y + 0.0f, p[i].z + 0.0f}; };
    auto less = [&](std::uint32_t a, std::uint32_t b) {
        const Vec3f ka = key(a), kb = key(b);
        if (ka.x != kb.x) return ka.x < kb.x;
        if (ka.y != kb.y) return ka.y < kb.y;
        if (ka.z != kb.z) return ka.z < kb.z;
        return a < b;
    };
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    tbb::parallel_sort(order.begin(), order.end(), less);  // a strict order: the same on any thread count
    // rep[i] = smallest original index with the same position (the first in each sorted run).
    std::vector<std::uint32_t> rep(n);
    for (std::size_t k = 0; k < n; ++k) {
        const bool same = k > 0 && key(order[k]) == key(order[k - 1]);
        rep[order[k]] = same ? rep[order[k - 1]] : order[k];
    }
    old_to_new.assign(n, 0);
    std::uint32_t next = 0;
    for (std::size_t i = 0; i < n; ++i) old_to_new[i] = (rep[i] == i) ? next++ : old_to_new[rep[i]];
    return next;
}

/// Difference x - y in double, and whether it is exact (TwoSum error is zero).
inline double diff(double x, double y, bool& exact) {
    const double s = x - y;
    const double bb = s - x;
    const double err = (x - (s - bb)) + (-y - bb);
    if (err != 0.0) exact = false;
    return s;
}

/// a*b == c*d exactly (products split into value + fma error; equal iff both parts are equal).
inline bool products_equal(double a, double b, double c, double d) {
    const double p1 = a * b, p2 = c * d;
    return p1 == p2 && std::fma(a, b, -p1) == std::fma(c, d, -p2);
}

}  // namespace

bool exactly_collinear(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
    bool exact = true;
    const double ux = diff(b.x, a.x, exact), uy = diff(b.y, a.y, exact), uz = diff(b.z, a.z, exact);
    const double vx = diff(c.x, a.x, exact), vy = diff(c.y, a.y, exact), vz = diff(c.z, a.z, exact);
    if (exact)
        return products_equal(uy, vz, uz, vy) && products_equal(uz, vx, ux, vz) && products_equal(ux, vy, uy, vx);
    using L = long double;
    const L lux = L(b.x) - L(a.x), luy = L(b.y) - L(a.y), luz = L(b.z) - L(a.z);
    const L lvx = L(c.x) - L(a.x), lvy = L(c.y) - L(a.y), lvz = L(c.z) - L(a.z);
    return luy * lvz == luz * lvy && luz * lvx == lux * lvz && lux * lvy == luy * lvx;
}

Mesh weld_exact(const Mesh& m, std::vector<std::uint32_t>* old_to_new) {
    check_mesh(m, "weld_exact");
    std::vector<std::uint32_t> map;
    const std::size_t n = weld_map(m.positions, map);
    Mesh out;
    out.positions.reserve(n);
    // New ids are assigned in order of first occurrence, so appending first occurrences fills them in order.
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        if (map[i] == out.positions.size()) out.positions.push_back(m.positions[i]);
    out.triangles.reserve(m.triangles.size());
    for (const Tri& t : m.triangles) out.triangles.push_back({map[t[0]], map[t[1]], map[t[2]]});
    if (old_to_new) *old_to_new = std::move(map);
    return out;
}

MeshReport mesh_report(const Mesh& m) {
    check_mesh(m, "mesh_report");
    MeshReport r;
    r.input_vertices = m.positions.size();
    r.faces = m.triangles.size();
    r.bbox = bounding_box(m);

    std::vector<std::uint32_t> map;
    const std::size_t nv = weld_map(m.positions, map);
    r.vertices = nv;
    const std::size_t nf = m.triangles.size();
    std::vector<Tri> w(nf);
    for (std::size_t f = 0; f < nf; ++f)
        w[f] = {map[m.triangles[f][0]], map[m.triangles[f][1]], map[m.triangles[f][2]]};

    // Referenced vertices, degenerate faces, area and volume.
    std::vector<char> referenced(nv, 0), collapsed(nf, 0);
    const Vec3d o = r.bbox.empty() ? Vec3d{} : r.bbox.center();
    double area = 0.0, vol6 = 0.0;
    for (std::size_t f = 0; f < nf; ++f) {
        const Tri& t = w[f];
        for (auto v : t) referenced[v] = 1;
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
            collapsed[f] = 1;
            ++r.collapsed_faces;
        } else {
            const Tri& ti = m.triangles[f];
            if (exactly_collinear(m.positions[ti[0]], m.positions[ti[1]], m.positions[ti[2]])) ++r.degenerate_faces;
        }
        const Tri& ti = m.triangles[f];
        const Vec3d a = Vec3d(m.positions[ti[0]]) - o, b = Vec3d(m.positions[ti[1]]) - o,
                    c = Vec3d(m.positions[ti[2]]) - o;
        const Vec3d n = cross(b - a, c - a);
        area += 0.5 * norm(n);
        vol6 += dot(a, cross(b, c));
    }
    r.degenerate_faces += r.collapsed_faces;
    r.area = area;
    r.volume = vol6 / 6.0;
    r.referenced_vertices = static_cast<std::size_t>(std::count(referenced.begin(), referenced.end(), 1));

    // Duplicate faces: sort the sorted corner triples of non-collapsed faces; later copies count.
    {
        struct Key {
            Tri s;
            std::uint32_t f;
        };
        std::vector<Key> keys;
        keys.reserve(nf);
        for (std::size_t f = 0; f < nf; ++f) {
            if (collapsed[f]) continue;
            Tri s = w[f];
            std::sort(s.begin(), s.end());
            keys.push_back({s, static_cast<std::uint32_t>(f)});
        }
        tbb::parallel_sort(keys.begin(), keys.end(),
                           [](const Key& a, const Key& b) { return a.s < b.s || (a.s == b.s && a.f < b.f); });
        for (std::size_t k = 1; k < keys.size(); ++k)
            if (keys[k].s == keys[k - 1].s) ++r.duplicate_faces;
    }

    // Edges: one record per directed face edge a->b (a != b), key = (min << 32 | max), sorted.
    struct HalfEdge {
        std::uint64_t key;
        std::uint32_t face;
        std::uint8_t corner;    // the edge goes from corner to corner+1
        std::uint8_t reversed;  // 1 if a > b
    };
    std::vector<HalfEdge> he;
    he.reserve(3 * nf);
    for (std::size_t f = 0; f < nf; ++f)
        for (std::uint8_t k = 0; k < 3; ++k) {
            const std::uint32_t a = w[f][k], b = w[f][(k + 1) % 3];
            if (a == b) continue;
            const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
            he.push_back({key, static_cast<std::uint32_t>(f), k, static_cast<std::uint8_t>(a > b)});
        }
    tbb::parallel_sort(he.begin(), he.end(), [](const HalfEdge& x, const HalfEdge& y) {
        return x.key < y.key || (x.key == y.key && x.face < y.face) ||
               (x.key == y.key && x.face == y.face && x.corner < y.corner);
    });

    // Fans around vertices: union-find over corners (3f + k) of non-collapsed faces. The corners at
    // vertex a of all faces on edge {a,b} are joined, and likewise at b.
    detail::UnionFind<std::uint32_t> corners(3 * nf);
    auto corner_of = [&](std::uint32_t f, std::uint32_t v) {
        for (std::uint32_t k = 0; k < 3; ++k)
            if (w[f][k] == v) return 3 * f + k;
        return 3 * f;  // unreachable for non-collapsed faces
    };
    detail::UnionFind<std::uint32_t> comps(nv);
    detail::UnionFind<std::uint32_t> loops(nv);  // over boundary edges only
    std::vector<char> on_boundary(nv, 0);
    for (std::size_t i = 0; i < he.size();) {
        std::size_t j = i;
        while (j < he.size() && he[j].key == he[i].key) ++j;
        const std::size_t count = j - i;
        ++r.edges;
        const auto a = static_cast<std::uint32_t>(he[i].key >> 32), b = static_cast<std::uint32_t>(he[i].key);
        comps.unite(a, b);
        if (count == 1) {
            ++r.boundary_edges;
            loops.unite(a, b);
            on_boundary[a] = on_boundary[b] = 1;
        }
        if (count > 2) ++r.non_manifold_edges;
        if (count == 2 && he[i].reversed == he[i + 1].reversed) ++r.inconsistent_edges;
        std::uint32_t first = UINT32_MAX;
        for (std::size_t k = i; k < j; ++k) {
            const std::uint32_t f = he[k].face;
            if (collapsed[f]) continue;
            if (first == UINT32_MAX) {
                first = f;
                continue;
            }
            corners.unite(corner_of(first, a), corner_of(f, a));
            corners.unite(corner_of(first, b), corner_of(f, b));
        }
        i = j;
    }

    // Non-manifold vertices: more than one corner root at the vertex.
    {
        std::vector<std::uint64_t> vr;  // (vertex << 32 | root)
        vr.reserve(3 * nf);
        for (std::size_t f = 0; f < nf; ++f) {
            if (collapsed[f]) continue;
            for (std::uint32_t k = 0; k < 3; ++k)
                vr.push_back((std::uint64_t(w[f][k]) << 32) | corners.find(static_cast<std::uint32_t>(3 * f + k)));
        }
        std::sort(vr.begin(), vr.end());
        vr.erase(std::unique(vr.begin(), vr.end()), vr.end());
        for (std::size_t i = 0; i < vr.size();) {
            std::size_t j = i;
            while (j < vr.size() && (vr[j] >> 32) == (vr[i] >> 32)) ++j;
            if (j - i > 1) ++r.non_manifold_vertices;
            i = j;
        }
    }

    // Components: vertex-connectivity over the faces' edges, counted on referenced vertices.
    for (std::size_t v = 0; v < nv; ++v)
        if (referenced[v] && comps.find(static_cast<std::uint32_t>(v)) == v) ++r.components;

    for (std::size_t v = 0; v < nv; ++v)
        if (on_boundary[v] && loops.find(static_cast<std::uint32_t>(v)) == v) ++r.boundary_loops;

    r.closed = nf > 0 && r.boundary_edges == 0;
    r.manifold = r.non_manifold_edges == 0 && r.non_manifold_vertices == 0;
    r.oriented = r.inconsistent_edges == 0;
    r.euler_characteristic =
        static_cast<long>(r.referenced_vertices) - static_cast<long>(r.edges) + static_cast<long>(nf);

    auto warn = [&](std::size_t n, const char* what) {
        if (n > 0) r.warnings.push_back(std::to_string(n) + " " + what);
    };
    warn(r.input_vertices - r.vertices, "duplicate positions (welded for this report)");
    warn(r.vertices - r.referenced_vertices, "unreferenced vertices");
    warn(r.boundary_edges, "boundary edges (mesh is open)");
    warn(r.non_manifold_edges, "non-manifold edges (more than two faces)");
    warn(r.non_manifold_vertices, "non-manifold vertices");
    warn(r.degenerate_faces, "degenerate faces (repeated vertex or zero area)");
    warn(r.duplicate_faces, "duplicate faces");
    warn(r.inconsistent_edges, "inconsistently oriented edges");
    if (r.components > 1) r.warnings.push_back(std::to_string(r.components) + " connected components");
    if (r.closed && r.oriented && r.volume < 0)
        r.warnings.push_back("closed mesh is oriented inward (negative volume)");
    return r;
}

}  // namespace normalflow
