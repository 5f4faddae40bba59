#pragma once
// Test meshes for tests/sdf: icosphere, box, torus, square sheet; analytic distances.

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

#include "core/mesh.h"
#include "core/volume.h"
#include "sdf/closest_triangle.h"

namespace normalflow::test {

// Icosphere of radius r about c, `levels` loop subdivisions of an icosahedron (20 * 4^levels faces), outward.
inline Mesh icosphere(double r, int levels, Vec3d c = {}) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3d> p = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    std::vector<Tri> f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                          {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                          {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    for (auto& q : p) q = normalized(q);
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
        auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            p.push_back(normalized(p[a] + p[b]));
            return mid[key] = std::uint32_t(p.size() - 1);
        };
        std::vector<Tri> g;
        for (const Tri& tr : f) {
            const std::uint32_t a = midpoint(tr[0], tr[1]), b = midpoint(tr[1], tr[2]), d = midpoint(tr[2], tr[0]);
            g.push_back({tr[0], a, d});
            g.push_back({tr[1], b, a});
            g.push_back({tr[2], d, b});
            g.push_back({a, b, d});
        }
        f = std::move(g);
    }
    Mesh m;
    for (const auto& q : p) m.positions.push_back(Vec3f(c + q * r));
    m.triangles = f;
    return m;
}

// Largest distance between an icosphere mesh and its sphere (the chord error): r − min distance to a face.
inline double sphere_chord_error(const Mesh& m, double r, Vec3d c = {}) {
    double dmin = r;
    for (const Tri& t : m.triangles) {
        const Vec3d q =
            closest_point_on_triangle(c, Vec3d(m.positions[t[0]]), Vec3d(m.positions[t[1]]), Vec3d(m.positions[t[2]]));
        dmin = std::min(dmin, norm(q - c));
    }
    return r - dmin;
}

// Axis-aligned box [lo, hi], 12 outward triangles.
inline Mesh box_mesh(Vec3d lo, Vec3d hi) {
    Mesh m;
    for (int k = 0; k < 8; ++k)
        m.positions.push_back(Vec3f(Vec3d(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z)));
    m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                   {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    return m;
}

inline double box_sdf(Vec3d p, Vec3d lo, Vec3d hi) {
    const Vec3d c = (lo + hi) * 0.5, e = (hi - lo) * 0.5;
    Vec3d q;
    for (int a = 0; a < 3; ++a) q[a] = std::abs(p[a] - c[a]) - e[a];
    const Vec3d qp = cwise_max(q, Vec3d{});
    return norm(qp) + std::min(std::max({q.x, q.y, q.z}), 0.0);
}

// Torus about the z axis: major radius R, minor radius r, nu × nv quads, outward.
inline Mesh torus_mesh(double R, double r, int nu, int nv) {
    Mesh m;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double u = 2 * std::numbers::pi * i / nu, v = 2 * std::numbers::pi * j / nv;
            m.positions.push_back(Vec3f(
                Vec3d((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v))));
        }
    auto id = [&](int i, int j) { return std::uint32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return m;
}

inline double torus_sdf(Vec3d p, double R, double r) { return std::hypot(std::hypot(p.x, p.y) - R, p.z) - r; }

// A flat square sheet [−s, s]² at z = 0, n × n quads.
inline Mesh sheet(double s, int n) {
    Mesh m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) m.positions.push_back(Vec3f(Vec3d(-s + 2 * s * i / n, -s + 2 * s * j / n, 0)));
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::uint32_t a = std::uint32_t(j * (n + 1) + i);
            m.triangles.push_back({a, a + 1, a + std::uint32_t(n) + 2});
            m.triangles.push_back({a, a + std::uint32_t(n) + 2, a + std::uint32_t(n) + 1});
        }
    return m;
}

inline Mesh concat(const Mesh& a, const Mesh& b) {
    Mesh m = a;
    const auto off = std::uint32_t(a.positions.size());
    m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
    for (Tri t : b.triangles) m.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
    return m;
}

inline Mesh flipped(Mesh m) {
    for (Tri& t : m.triangles) std::swap(t[1], t[2]);
    return m;
}

// Calls f(i, j, k, value) for every in-grid sample of every allocated block.
template <class F>
void for_each_block_sample(const Volume& v, F&& f) {
    for (std::size_t s = 0; s < v.block_count(); ++s) {
        const auto& b = v.block_coords[s];
        const float* vals = v.block_values(std::int32_t(s));
        for (int lk = 0; lk < kBlockDim; ++lk)
            for (int lj = 0; lj < kBlockDim; ++lj)
                for (int li = 0; li < kBlockDim; ++li) {
                    const int i = b[0] * 8 + li, j = b[1] * 8 + lj, k = b[2] * 8 + lk;
                    if (v.grid.contains(i, j, k)) f(i, j, k, vals[Volume::local_index(li, lj, lk)]);
                }
    }
}

}  // namespace normalflow::test
