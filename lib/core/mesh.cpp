#include "core/mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/errors.h"
#include "core/union_find.h"

namespace normalflow {

void check_mesh(const Mesh& m, std::string_view who) {
    const std::size_t n = m.positions.size();
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
        for (const std::uint32_t v : m.triangles[f])
            if (v >= n)
                throw InvalidInput(std::string(who) + ": triangle " + std::to_string(f) + " has vertex index " +
                                   std::to_string(v) + ", expected < " + std::to_string(n));
    for (std::size_t i = 0; i < n; ++i)
        if (!is_finite(m.positions[i]))
            throw InvalidInput(std::string(who) + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
    auto sized = [&](std::size_t k, const char* what) {
        if (k != 0 && k != n)
            throw InvalidInput(std::string(who) + ": " + std::to_string(k) + " " + what + " for " + std::to_string(n) +
                               " vertices");
    };
    sized(m.normals.size(), "normals");
    sized(m.colors.size(), "colours");
    sized(m.texcoords.size(), "texture coordinates");
    for (std::size_t i = 0; i < m.normals.size(); ++i)
        if (!is_finite(m.normals[i]))
            throw InvalidInput(std::string(who) + ": normal " + std::to_string(i) + " is not finite");
    for (std::size_t i = 0; i < m.texcoords.size(); ++i)
        if (!std::isfinite(m.texcoords[i][0]) || !std::isfinite(m.texcoords[i][1]))
            throw InvalidInput(std::string(who) + ": texture coordinate " + std::to_string(i) + " is not finite");
}

void remove_unreferenced_vertices(Mesh& m) {
    constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
    const std::size_t nv = m.positions.size();
    std::vector<std::uint32_t> remap(nv, kUnused);
    for (const Tri& t : m.triangles)
        for (const std::uint32_t v : t) remap[v] = 0;
    std::uint32_t next = 0;
    for (std::uint32_t& r : remap)
        if (r != kUnused) r = next++;
    auto compact = [&](auto& attr) {
        if (attr.empty()) return;
        for (std::size_t v = 0; v < nv; ++v)
            if (remap[v] != kUnused) attr[remap[v]] = attr[v];
        attr.resize(next);
    };
    compact(m.positions);
    compact(m.normals);
    compact(m.colors);
    compact(m.texcoords);
    for (Tri& t : m.triangles)
        for (std::uint32_t& v : t) v = remap[v];
}

void compute_vertex_normals(Mesh& m) {
    std::vector<Vec3d> sum(m.positions.size(), Vec3d{});
    for (const Tri& t : m.triangles) {
        const Vec3d n = face_area_vector(m, t);
        const double len = norm(n);
        if (!(len > 0)) continue;
        for (int k = 0; k < 3; ++k) {
            const Vec3d p(m.positions[t[k]]);
            const Vec3d e1 = Vec3d(m.positions[t[(k + 1) % 3]]) - p, e2 = Vec3d(m.positions[t[(k + 2) % 3]]) - p;
            const double angle = std::atan2(norm(cross(e1, e2)), dot(e1, e2));
            sum[t[k]] = sum[t[k]] + n * (angle / len);
        }
    }
    m.normals.assign(m.positions.size(), Vec3f{});
    for (std::size_t v = 0; v < sum.size(); ++v) {
        const double len = norm(sum[v]);
        if (len > 0 && std::isfinite(len)) m.normals[v] = Vec3f(sum[v] / len);
    }
}

std::vector<std::uint64_t> single_face_edges(const std::vector<Tri>& tris) {
    std::vector<std::uint64_t> e;
    e.reserve(3 * tris.size());
    for (const Tri& t : tris)
        for (int k = 0; k < 3; ++k)
            if (t[std::size_t(k)] != t[std::size_t((k + 1) % 3)])
                e.push_back(edge_key(t[std::size_t(k)], t[std::size_t((k + 1) % 3)]));
    std::sort(e.begin(), e.end());
    std::vector<std::uint64_t> once;
    for (std::size_t i = 0; i < e.size();) {
        std::size_t j = i;
        while (j < e.size() && e[j] == e[i]) ++j;
        if (j - i == 1) once.push_back(e[i]);
        i = j;
    }
    return once;
}

std::vector<std::array<Vec3d, 3>> hole_caps(const Mesh& m) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary;
    for (const std::uint64_t e : single_face_edges(m.triangles))
        boundary.emplace_back(std::uint32_t(e >> 32), std::uint32_t(e));
    std::vector<std::array<Vec3d, 3>> caps;
    if (boundary.empty()) return caps;
    detail::UnionFind<std::uint32_t> runs(m.positions.size());
    for (const auto& [u, v] : boundary) runs.unite(u, v);
    // by the run's root: the sum of its edges' ends, and their number
    std::vector<Vec3d> sum(m.positions.size(), Vec3d(0, 0, 0));
    std::vector<double> count(m.positions.size(), 0.0);
    for (const auto& [u, v] : boundary) {
        const std::uint32_t r = runs.find(u);
        sum[r] += Vec3d(m.positions[u]) + Vec3d(m.positions[v]);
        count[r] += 2;
    }
    caps.reserve(boundary.size());
    for (const auto& [u, v] : boundary) {
        const std::uint32_t r = runs.find(u);
        caps.push_back({sum[r] / count[r], Vec3d(m.positions[u]), Vec3d(m.positions[v])});
    }
    return caps;
}

std::vector<std::uint32_t> face_components(const Mesh& m, const std::vector<char>* only, std::size_t* count) {
    const auto in = [&](std::size_t f) { return !only || (*only)[f] != 0; };
    detail::UnionFind<std::uint32_t> uf(m.positions.size());
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
        if (in(f)) {
            uf.unite(m.triangles[f][0], m.triangles[f][1]);
            uf.unite(m.triangles[f][0], m.triangles[f][2]);
        }
    std::vector<std::uint32_t> id(m.positions.size(), kNoComponent), component(m.triangles.size(), kNoComponent);
    std::uint32_t n = 0;
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
        if (!in(f)) continue;
        std::uint32_t& c = id[uf.find(m.triangles[f][0])];
        if (c == kNoComponent) c = n++;
        component[f] = c;
    }
    if (count) *count = n;
    return component;
}

ComponentsRemoved remove_extra_components(Mesh& m, std::size_t allowed, double max_area_fraction) {
    ComponentsRemoved r;
    r.allowed = allowed;
    const std::vector<std::uint32_t> face_component = face_components(m, nullptr, &r.components);
    std::vector<double> area(r.components, 0.0);
    double total = 0;
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
        const double a = 0.5 * norm(face_area_vector(m, m.triangles[f]));
        area[face_component[f]] += a;
        total += a;
    }
    if (area.size() <= allowed) return r;
    std::vector<std::uint32_t> order(area.size());
    for (std::uint32_t c = 0; c < order.size(); ++c) order[c] = c;
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return area[a] < area[b]; });
    std::vector<char> drop(area.size(), 0);
    for (std::size_t k = 0; k + allowed < order.size(); ++k) {
        const std::uint32_t c = order[k];
        if (!(area[c] < max_area_fraction * total)) break;
        drop[c] = 1;
        ++r.removed;
        r.largest_area_fraction = total > 0 ? area[c] / total : 0;
    }
    if (r.removed == 0) return r;
    std::size_t kept = 0;
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
        if (!drop[face_component[f]]) m.triangles[kept++] = m.triangles[f];
    r.faces = m.triangles.size() - kept;
    m.triangles.resize(kept);
    remove_unreferenced_vertices(m);
    return r;
}

}  // namespace normalflow
