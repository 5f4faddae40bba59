#include "remesh/sharpen.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/errors.h"
#include "extract/volume_sampler.h"
#include "remesh/quadric.h"

namespace normalflow {

namespace {

/// A move is refused when one of the vertex's faces would turn from where it started by more than this (cosine:
/// 120°; a bevel's faces turn far as they fold into the crease, and at 90° a box's corners were not reached),
/// or its area (×2) fall below kMinArea × max_move²: vertices that converge on a corner or along a crease line
/// must not meet (the mesh would have coincident vertices and faces without area).
constexpr double kMinNormalCosine = -0.5;
constexpr double kMinArea = 1e-6;

Vec3d face_normal(const Vec3d& a, const Vec3d& b, const Vec3d& c) { return cross(b - a, c - a); }

}  // namespace

SurfaceProbe mesh_probe(const Mesh& reference, const ClosestTriangleQuery& q) {
    return [&reference, &q](const Vec3d& p, Vec3d& point, Vec3d& n) {
        const ClosestHit hit = q.closest(p);
        if (!hit.found()) return false;
        point = hit.point;
        n = face_area_vector(reference, reference.triangles[hit.triangle]);
        return norm(n) > 0;
    };
}

SurfaceProbe volume_probe(const Volume& v, const NormalMap* map) {
    return [&v, map](const Vec3d& p, Vec3d& point, Vec3d& n) {
        const detail::VolumeSampler sampler(v);
        Vec3d x = p, g;
        for (int step = 0; step < 8; ++step) {
            if (sampler.outside_band(x)) return false;
            const double phi = sampler.phi(x, &g);
            const double g2 = dot(g, g);
            if (!(g2 > 1e-12)) return false;
            x = x - g * (phi / g2);
            if (std::abs(phi) < 1e-6 * v.grid.voxel_size) break;
        }
        point = x;
        if (map && !(*map)[0].values.empty() && detail::sample_normal_map(*map, x, n)) return true;
        sampler.phi(x, &g);
        n = g;
        return norm(n) > 0;
    };
}

SharpenReport sharpen_mesh(Mesh& m, const SurfaceProbe& probe, const SharpenOptions& o, Progress* progress) {
    const auto start = std::chrono::steady_clock::now();
    check_mesh(m, "sharpen_mesh");
    if (o.iterations < 1)
        throw InvalidInput("sharpen_mesh: iterations = " + std::to_string(o.iterations) + ": expected >= 1");
    if (!(o.max_move > 0) || !std::isfinite(o.max_move))
        throw InvalidInput("sharpen_mesh: max_move = " + std::to_string(o.max_move) + ": expected > 0");
    if (!(o.truncation >= 0 && o.truncation < 1))
        throw InvalidInput("sharpen_mesh: truncation = " + std::to_string(o.truncation) + ": expected in [0, 1)");
    if (o.threads < 0) throw InvalidInput("sharpen_mesh: threads = " + std::to_string(o.threads) + ": expected >= 0");

    const std::size_t nv = m.positions.size(), nf = m.triangles.size();
    std::vector<Vec3d> x(nv), x0(nv);
    for (std::size_t i = 0; i < nv; ++i) x[i] = x0[i] = Vec3d(m.positions[i]);
    // faces of each vertex (CSR)
    std::vector<std::uint32_t> first(nv + 1, 0), ring(3 * nf);
    for (const Tri& t : m.triangles)
        for (std::uint32_t v : t) ++first[v + 1];
    for (std::size_t i = 0; i < nv; ++i) first[i + 1] += first[i];
    {
        std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
        for (std::size_t f = 0; f < nf; ++f)
            for (std::uint32_t v : m.triangles[f]) ring[fill[v]++] = std::uint32_t(f);
    }

    // each face's normal (area vector) at the start: no face may turn from it by 120° or shrink to nothing
    std::vector<Vec3d> start_normal(nf);
    for (std::size_t f = 0; f < nf; ++f) {
        const Tri& t = m.triangles[f];
        start_normal[f] = face_normal(x0[t[0]], x0[t[1]], x0[t[2]]);
    }
    const double min_area = kMinArea * o.max_move * o.max_move;
    SharpenReport r;
    r.vertices = nv;
    std::vector<Vec3d> dual_point(nf), dual_normal(nf);
    std::vector<char> has_dual(nf);
    std::vector<double> area(nf);
    std::vector<Vec3d> target(nv);
    std::vector<int> rank(nv);
    std::vector<std::uint32_t> order;
    tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
    for (int it = 0; it < o.iterations; ++it) {
        detail::begin(progress, "sharpen");
        // dual step: each face's centroid to the surface, with the surface's normal there
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf),
                              [&](const tbb::blocked_range<std::size_t>& range) {
                                  for (std::size_t f = range.begin(); f != range.end(); ++f) {
                                      const Tri& t = m.triangles[f];
                                      const Vec3d c = (x[t[0]] + x[t[1]] + x[t[2]]) * (1.0 / 3.0);
                                      area[f] = 0.5 * norm(face_normal(x[t[0]], x[t[1]], x[t[2]]));
                                      Vec3d n;
                                      has_dual[f] = probe(c, dual_point[f], n) && norm(n) > 0;
                                      if (has_dual[f]) dual_normal[f] = n * (1.0 / norm(n));
                                  }
                              });
        });
        // primal step: each vertex to the point nearest to it that best fits its faces' tangent planes, within
        // max_move of its start; made one vertex at a time (each check sees its neighbours as they are), corners
        // first, then crease points, then the rest, nearest first: the vertex nearest a corner takes it, and the
        // others, which would meet it, stay where they are
        arena.execute([&] {
            tbb::parallel_for(
                tbb::blocked_range<std::size_t>(0, nv), [&](const tbb::blocked_range<std::size_t>& range) {
                    for (std::size_t v = range.begin(); v != range.end(); ++v) {
                        detail::Quadric q;
                        for (std::uint32_t k = first[v]; k < first[v + 1]; ++k) {
                            const std::uint32_t f = ring[k];
                            if (!has_dual[f] || !(area[f] > 0)) continue;
                            q.add_plane(dual_normal[f], -dot(dual_normal[f], dual_point[f]), area[f]);
                        }
                        rank[v] = 0;
                        if (!(q.w > 0) || !q.truncated_minimiser_near(x[v], o.truncation, target[v], &rank[v]))
                            continue;
                        const Vec3d d = target[v] - x0[v];
                        const double len = norm(d);
                        if (len > o.max_move) target[v] = x0[v] + d * (o.max_move / len);
                        if (norm(target[v] - x[v]) < 1e-12 * o.max_move) rank[v] = 0;
                    }
                });
        });
        order.clear();
        for (std::uint32_t v = 0; v < nv; ++v)
            if (rank[v] > 0) order.push_back(v);
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            if (rank[a] != rank[b]) return rank[a] > rank[b];
            const double da = norm(target[a] - x[a]), db = norm(target[b] - x[b]);
            return da != db ? da < db : a < b;
        });
        r.moved = r.refused = 0;
        for (const std::uint32_t v : order) {
            bool ok = true;
            for (std::uint32_t k = first[v]; k < first[v + 1] && ok; ++k) {
                const Tri& t = m.triangles[ring[k]];
                const Vec3d a = t[0] == v ? target[v] : x[t[0]], b = t[1] == v ? target[v] : x[t[1]],
                            c = t[2] == v ? target[v] : x[t[2]];
                const Vec3d before = start_normal[ring[k]], after = face_normal(a, b, c);
                const double nb = norm(before), na = norm(after);
                // a face that started without area (a grid sample exactly on the surface) may stay so, not shrink
                ok = nb < min_area ? na >= nb : na > min_area && dot(before, after) > kMinNormalCosine * nb * na;
            }
            if (!ok) {
                ++r.refused;
                continue;
            }
            x[v] = target[v];
            ++r.moved;
        }
        detail::tick(progress, double(it + 1) / o.iterations, "sharpen_mesh");
    }
    double sum = 0;
    for (std::size_t i = 0; i < nv; ++i) {
        const double d = norm(x[i] - x0[i]);
        sum += d;
        r.max_move = std::max(r.max_move, d);
        m.positions[i] = Vec3f(x[i]);
    }
    r.mean_move = nv ? sum / double(nv) : 0.0;
    m.normals.clear();
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
}

}  // namespace normalflow
