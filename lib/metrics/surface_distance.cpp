#include "metrics/surface_distance.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/errors.h"
#include "sdf/closest_triangle.h"
#include "sdf/triangle_bvh.h"

namespace normalflow {
namespace {

std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// Uniform in [0, 1) from 53 random bits.
double unit(std::uint64_t x) { return double(x >> 11) * (1.0 / 9007199254740992.0); }

Vec3d corner(const Mesh& m, std::uint32_t f, int c) { return Vec3d(m.positions[m.triangles[f][c]]); }

Vec3d face_normal(const Mesh& m, std::uint32_t f) {
    return normalized(cross(corner(m, f, 1) - corner(m, f, 0), corner(m, f, 2) - corner(m, f, 0)));
}

// Per-sample results of one direction (samples on `from`, distances to `to`).
struct Direction {
    std::vector<double> dist;
    std::vector<double> angle;  // degrees; NaN when the target face has zero area
};

Direction sample_direction(const Mesh& from, const Mesh& to, const ClosestTriangleQuery& q, std::size_t n,
                           std::uint64_t seed, std::uint64_t which, bool angles) {
    // Cumulative areas (serial: deterministic).
    std::vector<double> cdf(from.triangles.size());
    double total = 0;
    for (std::size_t f = 0; f < from.triangles.size(); ++f) {
        const auto fi = std::uint32_t(f);
        total +=
            0.5 * norm(cross(corner(from, fi, 1) - corner(from, fi, 0), corner(from, fi, 2) - corner(from, fi, 0)));
        cdf[f] = total;
    }
    if (!(total > 0) || !std::isfinite(total))
        throw InvalidInput("surface_distance: mesh " + std::string(which == 0 ? "a" : "b") +
                           " has zero total area, expected a surface");
    Direction out;
    out.dist.resize(n);
    if (angles) out.angle.resize(n);
    const std::uint64_t base = splitmix64(seed ^ splitmix64(which + 0x51ed2701ull));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        std::uint32_t hint = ClosestHit::kNone;
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            std::uint64_t s = splitmix64(base + 3 * std::uint64_t(i));
            const double u0 = unit(s), u1 = unit(s = splitmix64(s)), u2 = unit(splitmix64(s));
            const auto it = std::upper_bound(cdf.begin(), cdf.end(), u0 * total);
            const auto f = std::uint32_t(std::min<std::size_t>(std::size_t(it - cdf.begin()), cdf.size() - 1));
            const double s1 = std::sqrt(u1);
            const Vec3d p =
                corner(from, f, 0) * (1 - s1) + corner(from, f, 1) * (s1 * (1 - u2)) + corner(from, f, 2) * (s1 * u2);
            // Search radius: the previous answer's face bounds the distance (hint only speeds it up).
            const ClosestHit h = q.closest_within(p, std::numeric_limits<double>::infinity(), hint);
            hint = h.triangle;
            out.dist[i] = std::sqrt(h.squared_distance);
            if (angles) {
                const Vec3d na = face_normal(from, f), nb = face_normal(to, h.triangle);
                out.angle[i] = squared_norm(nb) > 0 && squared_norm(na) > 0
                                   ? std::acos(std::clamp(dot(na, nb), -1.0, 1.0)) * (180.0 / std::numbers::pi)
                                   : std::numeric_limits<double>::quiet_NaN();
            }
        }
    });
    return out;
}

}  // namespace

SurfaceDistance surface_distance(const Mesh& a, const Mesh& b, const SurfaceSamplingOptions& opt) {
    if (opt.samples == 0) throw InvalidInput("surface_distance: samples = 0, expected >= 1");
    if (a.triangles.empty()) throw InvalidInput("surface_distance: mesh a has no triangles");
    if (b.triangles.empty()) throw InvalidInput("surface_distance: mesh b has no triangles");
    check_mesh(a, "surface_distance (mesh a)");
    check_mesh(b, "surface_distance (mesh b)");
    const auto qa = make_bvh_query(a), qb = make_bvh_query(b);
    const Direction ab = sample_direction(a, b, *qb, opt.samples, opt.seed, 0, true);
    const Direction ba = sample_direction(b, a, *qa, opt.samples, opt.seed, 1, false);

    SurfaceDistance r;
    r.samples = opt.samples;
    double sum = 0, sum2 = 0, angle_sum = 0;
    std::size_t angle_n = 0;
    for (std::size_t i = 0; i < opt.samples; ++i) {
        const double d = ab.dist[i];
        sum += d;
        sum2 += d * d;
        r.max_a_to_b = std::max(r.max_a_to_b, d);
        if (!std::isnan(ab.angle[i])) {
            angle_sum += ab.angle[i];
            ++angle_n;
        }
    }
    for (std::size_t i = 0; i < opt.samples; ++i) {
        const double d = ba.dist[i];
        sum += d;
        sum2 += d * d;
        r.max_b_to_a = std::max(r.max_b_to_a, d);
    }
    const double n = 2.0 * double(opt.samples);
    r.mean = sum / n;
    r.rms = std::sqrt(sum2 / n);
    r.hausdorff = std::max(r.max_a_to_b, r.max_b_to_a);
    r.mean_normal_angle_deg = angle_n > 0 ? angle_sum / double(angle_n) : 0.0;
    return r;
}

namespace {

/// Points sampled on m: its vertices, then samples_per_face points per face (fixed barycentric
/// coordinates spread over the triangle, no randomness).
std::vector<Vec3d> sample_points(const Mesh& m, int samples_per_face) {
    std::vector<Vec3d> s;
    s.reserve(m.positions.size() + m.triangles.size() * static_cast<std::size_t>(samples_per_face));
    for (const auto& p : m.positions) s.push_back(Vec3d{p[0], p[1], p[2]});
    // Barycentric points: the centroid, then points towards each corner.
    static constexpr double kBary[][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3},
                                          {0.6, 0.2, 0.2},
                                          {0.2, 0.6, 0.2},
                                          {0.2, 0.2, 0.6},
                                          {0.5, 0.5, 0.0},
                                          {0.0, 0.5, 0.5},
                                          {0.5, 0.0, 0.5}};
    const int ns = std::min(samples_per_face, 7);
    for (const auto& t : m.triangles)
        for (int k = 0; k < ns; ++k) {
            Vec3d q{0, 0, 0};
            for (int c = 0; c < 3; ++c) {
                const auto& p = m.positions[t[c]];
                for (int d = 0; d < 3; ++d) q[d] += kBary[k][c] * p[d];
            }
            s.push_back(q);
        }
    return s;
}

}  // namespace

double sampled_max_distance(const Mesh& from, const Mesh& to, int samples_per_face) {
    if (from.triangles.empty() || to.triangles.empty()) return 0.0;
    const auto query = make_bvh_query(to);
    const auto pts = sample_points(from, samples_per_face);
    // Only the largest distance is wanted: a point with a triangle closer than the largest distance found so far
    // (its block's: a lower bound of the answer) cannot raise it, and the search within that radius is short. The
    // points that may raise it are measured exactly. Every point's distance is then either measured or below a
    // measured one, so the maximum is exact, whatever the blocks and threads. A sparse pass first gives each block a
    // bound to start from.
    constexpr std::size_t kStride = 64, kBlock = 1024;
    double seed = 0.0;
    {
        const std::size_t sparse = (pts.size() + kStride - 1) / kStride;
        std::vector<double> d(sparse, 0.0);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, sparse, 256), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) d[i] = query->closest(pts[i * kStride]).squared_distance;
        });
        for (double x : d) seed = std::max(seed, x);
    }
    const std::size_t blocks = (pts.size() + kBlock - 1) / kBlock;
    std::vector<double> block_max(blocks, seed);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            double mx = seed;
            std::uint32_t hint = ClosestHit::kNone;
            for (std::size_t i = b * kBlock; i < std::min(pts.size(), (b + 1) * kBlock); ++i) {
                // a triangle strictly closer than the bound: the point cannot raise it
                const ClosestHit near = query->closest_within(pts[i], mx, hint);
                if (near.found()) {
                    hint = near.triangle;
                    continue;
                }
                const ClosestHit h = query->closest_within(pts[i], std::numeric_limits<double>::infinity(), hint);
                hint = h.triangle;
                mx = std::max(mx, h.squared_distance);
            }
            block_max[b] = mx;
        }
    });
    double mx = seed;
    for (double x : block_max) mx = std::max(mx, x);
    return std::sqrt(mx);
}

SampledDistance sampled_hausdorff(const Mesh& a, const Mesh& b, int samples_per_face) {
    SampledDistance r;
    r.a_to_b = sampled_max_distance(a, b, samples_per_face);
    r.b_to_a = sampled_max_distance(b, a, samples_per_face);
    r.hausdorff = std::max(r.a_to_b, r.b_to_a);
    return r;
}

}  // namespace normalflow
