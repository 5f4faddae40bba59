#pragma once
// Test meshes for tests/metrics and tests/baselines: a subdivided cube and a rounded cube (plus the
// icosphere of tests/sdf).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <tuple>

#include "../sdf/sdf_test_meshes.h"
#include "core/mesh.h"

namespace normalflow::test {

// The cube [-1, 1]^3, each face an n × n grid of quads split into two triangles, shared vertices, outward.
inline Mesh subdivided_cube(int n) {
    Mesh m;
    std::map<std::tuple<int, int, int>, std::uint32_t> index;
    auto vertex = [&](int i, int j, int k) {
        const auto key = std::make_tuple(i, j, k);
        auto it = index.find(key);
        if (it != index.end()) return it->second;
        m.positions.push_back(Vec3f(Vec3d(-1 + 2.0 * i / n, -1 + 2.0 * j / n, -1 + 2.0 * k / n)));
        return index[key] = std::uint32_t(m.positions.size() - 1);
    };
    for (int a = 0; a < 3; ++a)
        for (int side = 0; side < 2; ++side) {
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            for (int u = 0; u < n; ++u)
                for (int v = 0; v < n; ++v) {
                    auto at = [&](int uu, int vv) {
                        int ijk[3];
                        ijk[a] = side * n;
                        ijk[b] = uu;
                        ijk[c] = vv;
                        return vertex(ijk[0], ijk[1], ijk[2]);
                    };
                    const std::uint32_t p0 = at(u, v), p1 = at(u + 1, v), p2 = at(u + 1, v + 1), p3 = at(u, v + 1);
                    if (side == 1) {
                        m.triangles.push_back({p0, p1, p2});
                        m.triangles.push_back({p0, p2, p3});
                    } else {
                        m.triangles.push_back({p0, p2, p1});
                        m.triangles.push_back({p0, p3, p2});
                    }
                }
        }
    return m;
}

// subdivided_cube(n) with its edges and corners rounded with radius R (0 < R < 1): each point p goes to
// q + R (p − q) / |p − q| with q = p clamped to the inner box [−(1−R), 1−R]^3 (faces stay flat).
inline Mesh rounded_cube(int n, double R) {
    Mesh m = subdivided_cube(n);
    for (Vec3f& pf : m.positions) {
        const Vec3d p(pf);
        Vec3d q;
        for (int a = 0; a < 3; ++a) q[a] = std::clamp(p[a], -(1 - R), 1 - R);
        pf = Vec3f(q + normalized(p - q) * R);
    }
    return m;
}

inline Mesh scaled(Mesh m, double s) {
    for (Vec3f& p : m.positions) p = Vec3f(Vec3d(p) * s);
    return m;
}

}  // namespace normalflow::test
