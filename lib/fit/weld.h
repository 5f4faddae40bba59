#pragma once
/// \file weld.h
/// Internal to lib/fit: coincident positions as one vertex, and the vertices on an open boundary.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <unordered_map>
#include <vector>

#include "core/mesh.h"

namespace normalflow::detail {

struct PositionHash {
    std::size_t operator()(const Vec3f& p) const {
        std::uint32_t b[3];
        static_assert(sizeof(b) == sizeof(float) * 3);
        const float f[3] = {p.x == 0.0f ? 0.0f : p.x, p.y == 0.0f ? 0.0f : p.y, p.z == 0.0f ? 0.0f : p.z};
        std::memcpy(b, f, sizeof(b));
        std::size_t h = b[0];
        h = h * 0x9E3779B97F4A7C15ull ^ b[1];
        h = h * 0x9E3779B97F4A7C15ull ^ b[2];
        return h;
    }
};
struct PositionEqual {
    bool operator()(const Vec3f& a, const Vec3f& b) const { return a.x == b.x && a.y == b.y && a.z == b.z; }
};

/// group[i] = the welded vertex of position i (coincident positions share one, numbered in order of
/// first occurrence); returns the number of groups.
inline std::size_t weld(const Mesh& m, std::vector<std::uint32_t>& group) {
    std::unordered_map<Vec3f, std::uint32_t, PositionHash, PositionEqual> first;
    first.reserve(m.positions.size());
    group.resize(m.positions.size());
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        group[i] = first.emplace(m.positions[i], std::uint32_t(first.size())).first->second;
    return first.size();
}

/// The welded triangles' edges as sorted pairs with their face counts: true for each welded vertex
/// on an edge of exactly one face.
inline std::vector<char> boundary_vertices(const Mesh& m, const std::vector<std::uint32_t>& group, std::size_t n) {
    std::vector<std::uint64_t> edges;
    edges.reserve(m.triangles.size() * 3);
    for (const Tri& t : m.triangles)
        for (int e = 0; e < 3; ++e) {
            std::uint32_t a = group[t[std::size_t(e)]], b = group[t[std::size_t((e + 1) % 3)]];
            if (a == b) continue;  // a degenerate edge
            if (a > b) std::swap(a, b);
            edges.push_back(std::uint64_t(a) << 32 | b);
        }
    std::sort(edges.begin(), edges.end());
    std::vector<char> on(n, 0);
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i == 1) {
            on[std::size_t(edges[i] >> 32)] = 1;
            on[std::size_t(edges[i] & 0xffffffffu)] = 1;
        }
        i = j;
    }
    return on;
}

}  // namespace normalflow::detail
