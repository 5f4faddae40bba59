#include "metrics/noise.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "extract/surface_attributes.h"

namespace normalflow {

namespace detail {

NormalRng::NormalRng(std::uint64_t seed) : engine_(seed) {}

double NormalRng::uniform() { return double(engine_() >> 11) * 0x1.0p-53; }

double NormalRng::normal() {
    if (has_spare_) {
        has_spare_ = false;
        return spare_;
    }
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();  // log(0) guard
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double a = 2.0 * std::numbers::pi * u2;
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
}

std::uint64_t NormalRng::below(std::uint64_t n) {
    // Rejection: accept x < limit, the largest multiple of n representable, then x % n is unbiased.
    const std::uint64_t limit = (~std::uint64_t(0) / n) * n;
    std::uint64_t x = engine_();
    while (x >= limit) x = engine_();
    return x % n;
}

}  // namespace detail

namespace {

std::vector<std::pair<std::uint32_t, std::uint32_t>> unique_edges(const Mesh& w) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> e;
    e.reserve(3 * w.triangles.size());
    for (const Tri& t : w.triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t[k], b = t[(k + 1) % 3];
            if (a != b) e.emplace_back(std::min(a, b), std::max(a, b));
        }
    std::sort(e.begin(), e.end());
    e.erase(std::unique(e.begin(), e.end()), e.end());
    return e;
}

double mean_length(const Mesh& w, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& e) {
    if (e.empty()) return 0.0;
    double s = 0;
    for (const auto& [a, b] : e) s += norm(Vec3d(w.positions[a]) - Vec3d(w.positions[b]));
    return s / double(e.size());
}

Vec3d random_unit(detail::NormalRng& rng) {
    for (;;) {
        const Vec3d d{rng.normal(), rng.normal(), rng.normal()};
        const double n = norm(d);
        if (n > 1e-12) return d / n;
    }
}

}  // namespace

double mean_edge_length(const Mesh& m) {
    const Mesh w = weld_exact(m);
    return mean_length(w, unique_edges(w));
}

std::vector<Vec3d> steady_vertex_normals(const std::vector<Vec3d>& area_normal,
                                         const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges) {
    std::vector<Vec3d> n(area_normal.size()), sum(area_normal.size());
    const auto unit = [](const Vec3d& v) {
        const double len = norm(v);
        return len > 0 ? v / len : Vec3d(0, 0, 0);
    };
    for (std::size_t v = 0; v < n.size(); ++v) n[v] = unit(area_normal[v]);
    for (int pass = 0; pass < 2; ++pass) {
        sum = n;
        for (const auto& [a, b] : edges) sum[a] += n[b], sum[b] += n[a];
        for (std::size_t v = 0; v < n.size(); ++v) n[v] = unit(sum[v]);
    }
    return n;
}

std::vector<Vec3d> steady_vertex_normals(const Mesh& m) {
    const std::size_t n = m.positions.size();
    std::vector<Vec3d> area(n, Vec3d(0, 0, 0));
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
    edges.reserve(3 * m.triangles.size());
    for (const Tri& t : m.triangles) {
        if (t[0] >= n || t[1] >= n || t[2] >= n)
            throw InvalidInput("steady_vertex_normals: a triangle's index is out of range");
        const Vec3d a = face_area_vector(m, t);
        for (std::size_t k = 0; k < 3; ++k) {
            area[t[k]] += a;
            const std::uint32_t p = t[k], q = t[(k + 1) % 3];
            if (p != q) edges.emplace_back(std::min(p, q), std::max(p, q));
        }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    return steady_vertex_normals(area, edges);
}

NoiseEstimate estimate_noise(const Mesh& m, NoiseNormals along) {
    const Mesh w = weld_exact(m);
    NoiseEstimate r;
    const std::size_t nv = w.positions.size();
    // every edge once per face, sorted: an edge of one face is on an open boundary
    std::vector<std::pair<std::uint32_t, std::uint32_t>> all;
    all.reserve(3 * w.triangles.size());
    std::vector<Vec3d> normal(nv);
    for (const Tri& t : w.triangles) {
        const Vec3d n = face_area_vector(w, t);
        for (int k = 0; k < 3; ++k) {
            normal[t[std::size_t(k)]] += n;
            const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
            if (a != b) all.emplace_back(std::min(a, b), std::max(a, b));
        }
    }
    std::sort(all.begin(), all.end());
    std::vector<char> boundary(nv, 0);
    std::vector<std::uint32_t> start(nv + 1, 0);  // the neighbours of v: nb[start[v] .. start[v + 1])
    std::vector<std::pair<std::uint32_t, std::uint32_t>> unique;
    double length = 0.0;
    for (std::size_t i = 0; i < all.size();) {
        std::size_t j = i;
        while (j < all.size() && all[j] == all[i]) ++j;
        const auto [a, b] = all[i];
        if (j - i == 1) boundary[a] = boundary[b] = 1;
        unique.push_back(all[i]);
        ++start[a + 1], ++start[b + 1];
        length += norm(Vec3d(w.positions[a]) - Vec3d(w.positions[b]));
        i = j;
    }
    r.mean_edge_length = unique.empty() ? 0.0 : length / double(unique.size());
    for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<std::uint32_t> nb(start[nv]);
    {
        std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
        for (const auto& [a, b] : unique) nb[fill[a]++] = b, nb[fill[b]++] = a;
    }
    const auto k = [&](std::size_t v) { return double(start[v + 1] - start[v]); };
    // δ_v: the umbrella offset along the vertex's normal, where v is interior with 3 or more neighbours
    if (along == NoiseNormals::Steady)
        normal = steady_vertex_normals(normal, unique);
    else
        for (Vec3d& n : normal)
            if (const double len = norm(n); len > 0) n = n / len;
    std::vector<double> offset(nv, 0.0);
    std::vector<char> measured(nv, 0);
    for (std::size_t v = 0; v < nv; ++v) {
        if (boundary[v] || k(v) < 3 || !(norm(normal[v]) > 0)) continue;
        Vec3d c(0, 0, 0);
        for (std::uint32_t i = start[v]; i < start[v + 1]; ++i) c += Vec3d(w.positions[nb[i]]);
        offset[v] = dot(Vec3d(w.positions[v]) - c / k(v), normal[v]);
        measured[v] = 1;
    }
    // Δ_v = δ_v − mean of the neighbours' δ, where v and its neighbours are measured; its response to unit white
    // noise is the sum of the squared coefficients of (I − A)² in row v (A: the neighbour mean), exact
    double energy = 0.0, response = 0.0;
    std::vector<std::pair<std::uint32_t, double>> row;
    for (std::size_t v = 0; v < nv; ++v) {
        if (!measured[v]) continue;
        bool all_measured = true;
        double mean = 0.0;
        for (std::uint32_t i = start[v]; i < start[v + 1]; ++i) {
            all_measured = all_measured && measured[nb[i]];
            mean += offset[nb[i]];
        }
        if (!all_measured) continue;
        const double d = offset[v] - mean / k(v);
        row.assign(1, {std::uint32_t(v), 1.0});
        for (std::uint32_t i = start[v]; i < start[v + 1]; ++i) {
            const std::uint32_t j = nb[i];
            row.emplace_back(j, -2.0 / k(v));
            for (std::uint32_t l = start[j]; l < start[j + 1]; ++l) row.emplace_back(nb[l], 1.0 / (k(v) * k(j)));
        }
        std::sort(row.begin(), row.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
        double squares = 0.0;
        for (std::size_t i = 0; i < row.size();) {
            double c = 0.0;
            std::size_t j = i;
            for (; j < row.size() && row[j].first == row[i].first; ++j) c += row[j].second;
            squares += c * c;
            i = j;
        }
        energy += d * d;
        response += squares;
        ++r.vertices;
    }
    r.sigma = response > 0 ? std::sqrt(energy / response) : 0.0;
    return r;
}

NoiseReport add_noise(Mesh& m, const NoiseOptions& opt) {
    if (m.triangles.empty()) throw InvalidInput("add_noise: mesh has no triangles");
    if (!(opt.sigma >= 0) || !std::isfinite(opt.sigma))
        throw InvalidInput("add_noise: sigma " + std::to_string(opt.sigma) + ", expected a finite value >= 0");
    if (!(opt.impulsive_fraction >= 0 && opt.impulsive_fraction <= 1))
        throw InvalidInput("add_noise: impulsive_fraction " + std::to_string(opt.impulsive_fraction) +
                           " out of range, expected [0, 1]");
    std::vector<std::uint32_t> old_to_new;
    Mesh w;
    try {
        w = weld_exact(m, &old_to_new);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string("add_noise: ") + e.what());
    }
    NoiseReport r;
    r.mean_edge_length = mean_length(w, unique_edges(w));
    r.sigma_world = opt.sigma * r.mean_edge_length;

    const std::size_t nv = w.positions.size();
    std::vector<Vec3d> normal(nv);
    std::vector<char> referenced(nv, 0);
    for (const Tri& t : w.triangles) {
        const Vec3d n = face_area_vector(w, t);
        for (std::uint32_t v : t) {
            normal[v] += n;
            referenced[v] = 1;
        }
    }
    std::vector<std::uint32_t> verts;
    for (std::uint32_t v = 0; v < nv; ++v)
        if (referenced[v]) verts.push_back(v);
    r.vertices = verts.size();

    detail::NormalRng rng(opt.seed);
    std::vector<std::uint32_t> chosen;
    if (opt.kind == NoiseKind::Impulsive) {
        const auto k = std::size_t(std::llround(opt.impulsive_fraction * double(verts.size())));
        std::vector<std::uint32_t> pool = verts;  // partial Fisher–Yates: the first k of a shuffle
        for (std::size_t i = 0; i < k; ++i) std::swap(pool[i], pool[i + rng.below(pool.size() - i)]);
        chosen.assign(pool.begin(), pool.begin() + std::ptrdiff_t(k));
        std::sort(chosen.begin(), chosen.end());  // displacements drawn in index order
    } else {
        chosen = verts;
    }

    std::vector<Vec3d> disp(nv);
    double s2 = 0;
    for (std::uint32_t v : chosen) {
        Vec3d dir;
        if (opt.direction == NoiseDirection::Normal && squared_norm(normal[v]) > 0) {
            dir = normalized(normal[v]);
        } else {
            dir = random_unit(rng);
        }
        const double len = rng.normal() * r.sigma_world;
        disp[v] = dir * len;
        s2 += len * len;
    }
    r.displaced = chosen.size();
    r.rms_displacement = chosen.empty() ? 0.0 : std::sqrt(s2 / double(chosen.size()));
    for (std::size_t k = 0; k < m.positions.size(); ++k) {
        const std::uint32_t v = old_to_new[k];
        if (referenced[v]) m.positions[k] = Vec3f(Vec3d(w.positions[v]) + disp[v]);
    }
    if (m.has_normals()) set_face_normals(m);  // the normals of the noisy surface, not of the clean one
    return r;
}

}  // namespace normalflow
