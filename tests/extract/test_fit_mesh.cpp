// Tests of fit_mesh_to_volume (lib/fit/fit_mesh.h): the user's mesh moved onto a volume's zero
// level set with its connectivity kept. Analytic cases first (a noisy icosphere lands on its sphere,
// a noisy box's faces turn flat), then properties (the open boundary stays, coincident positions
// stay coincident, the thread count does not matter), then bad input.

#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>

#include "core/errors.h"
#include "fit/fit_mesh.h"
#include "normals/volume_fixtures.h"
#include "sdf/sdf_test_meshes.h"

namespace normalflow {
namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;

/// Each vertex moved along a random direction by up to `amplitude` (fixed seed).
Mesh jittered(Mesh m, double amplitude, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-amplitude, amplitude);
    for (Vec3f& p : m.positions) p = Vec3f(Vec3d(p) + Vec3d(u(rng), u(rng), u(rng)));
    return m;
}

/// A box [lo, hi] with each face an n × n grid of quads (two triangles each), welded, outward.
Mesh grid_box(const Vec3d& lo, const Vec3d& hi, int n) {
    Mesh m;
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            const auto base = std::uint32_t(m.positions.size());
            for (int j = 0; j <= n; ++j)
                for (int i = 0; i <= n; ++i) {
                    Vec3d p;
                    p[axis] = side ? hi[axis] : lo[axis];
                    p[u] = lo[u] + (hi[u] - lo[u]) * i / n;
                    p[w] = lo[w] + (hi[w] - lo[w]) * j / n;
                    m.positions.push_back(Vec3f(p));
                }
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const std::uint32_t a = base + std::uint32_t(j * (n + 1) + i), b = a + 1,
                                        c = a + std::uint32_t(n + 1), d = c + 1;
                    if (side) {
                        m.triangles.push_back({a, b, d});
                        m.triangles.push_back({a, d, c});
                    } else {
                        m.triangles.push_back({a, d, b});
                        m.triangles.push_back({a, c, d});
                    }
                }
        }
    return m;  // edges and corners are repeated positions: welded by the fit, as an STL would be
}

/// Area-weighted mean angle (degrees) between the faces of m away from the box's edges (farther
/// than `reach` from every other face plane) and the face's axis.
double box_face_error(const Mesh& m, const Vec3d& lo, const Vec3d& hi, double reach) {
    double sum = 0, area = 0;
    for (const Tri& t : m.triangles) {
        const Vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        const Vec3d n = cross(b - a, c - a);
        const double ar = 0.5 * norm(n);
        if (ar <= 0) continue;
        const Vec3d g = (a + b + c) / 3.0;
        int near = 0, axis = 0;
        double best = 1e300;
        for (int k = 0; k < 3; ++k) {
            const double d = std::min(std::abs(g[k] - lo[k]), std::abs(g[k] - hi[k]));
            if (d < best) best = d, axis = k;
            near += d < reach;
        }
        if (near != 1) continue;
        sum += ar * std::acos(std::min(1.0, std::abs(n[axis]) / (2 * ar))) * kDeg;
        area += ar;
    }
    return sum / area;
}

TEST(FitMesh, NoisyIcosphereLandsOnItsSphereWithItsConnectivity) {
    const Vec3d c(16.3, 15.8, 16.1);
    const double r = 10.0;
    const Volume v = test::make_volume(32, 1.0, test::sphere_sdf(c, r));
    const Mesh noisy = jittered(test::icosphere(r, 3, c), 0.4, 7u);
    Mesh m = noisy;
    const FitReport rep = fit_mesh_to_volume(m, v);
    EXPECT_EQ(m.triangles, noisy.triangles);
    ASSERT_EQ(m.positions.size(), noisy.positions.size());
    double worst0 = 0, worst = 0;
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        worst0 = std::max(worst0, std::abs(norm(Vec3d(noisy.positions[i]) - c) - r));
        worst = std::max(worst, std::abs(norm(Vec3d(m.positions[i]) - c) - r));
    }
    std::printf("icosphere: radial error %.4f -> %.4f voxels, report mean |phi| %.5f max %.5f\n", worst0, worst,
                rep.mean_distance, rep.max_distance);
    EXPECT_GT(worst0, 0.3);
    // on the sphere up to the trilinear φ's error (the vertex update moves along face normals, off
    // the level set by a small fraction of a voxel on a curved surface)
    EXPECT_LT(worst, 0.05);
    EXPECT_EQ(rep.vertices, noisy.positions.size());
    EXPECT_EQ(rep.boundary_vertices, 0u);
    EXPECT_EQ(rep.outside_band, 0u);
    EXPECT_FALSE(has_open_boundary(noisy));
}

/// Area-weighted mean angle (degrees) between the faces of m and the sphere's normal at their centroids.
double sphere_face_error(const Mesh& m, const Vec3d& c) {
    double sum = 0, area = 0;
    for (const Tri& t : m.triangles) {
        const Vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), d(m.positions[t[2]]);
        const Vec3d n = cross(b - a, d - a);
        const double ar = 0.5 * norm(n);
        if (ar <= 0) continue;
        const Vec3d radial = normalized((a + b + d) / 3.0 - c);
        sum += ar * std::acos(std::clamp(dot(n, radial) / (2 * ar), -1.0, 1.0)) * kDeg;
        area += ar;
    }
    return sum / area;
}

TEST(FitMesh, VertexUpdateTurnsTheFacesToTheVolumesNormals) {
    // A fine icosphere jittered by more than its edge length is tangled: projected onto the sphere,
    // its vertices keep their tangential disorder and many triangles stand at an angle to it. The
    // vertex update turns them toward the volume's normals.
    const Vec3d c(16.3, 15.8, 16.1);
    const Volume v = test::make_volume(32, 1.0, test::sphere_sdf(c, 10.0));
    const Mesh noisy = jittered(test::icosphere(10.0, 4, c), 0.5, 3u);
    Mesh projected = noisy, fitted = noisy;
    FitOptions o;
    o.vertex_steps = 0;
    fit_mesh_to_volume(projected, v, o);
    fit_mesh_to_volume(fitted, v);
    const double e0 = sphere_face_error(noisy, c), ep = sphere_face_error(projected, c),
                 ef = sphere_face_error(fitted, c);
    std::printf("icosphere faces against the sphere's normals: noisy %.2f°, projected %.2f°, fitted %.2f°\n", e0, ep,
                ef);
    EXPECT_LT(ep, e0);
    EXPECT_LT(ef, 0.97 * ep);  // measured 5.62° → 5.31°: a small correction on top of the projection
}

/// A box of voxel-aligned planes: projection puts a jittered, finely meshed box back on its faces.
TEST(FitMesh, JitteredBoxFacesComeBackFlat) {
    const Vec3d lo(6.3, 5.8, 6.1), hi(25.7, 26.2, 25.9);
    const Vec3d centre = (lo + hi) * 0.5, half = (hi - lo) * 0.5;
    const Volume v = test::make_volume(32, 1.0, test::box_sdf(centre, half));
    const Mesh noisy = jittered(grid_box(lo, hi, 24), 0.3, 3u);
    Mesh fitted = noisy;
    fit_mesh_to_volume(fitted, v);
    const double e0 = box_face_error(noisy, lo, hi, 2.0), ef = box_face_error(fitted, lo, hi, 2.0);
    std::printf("box faces farther than 2 voxels from an edge: noisy %.3f°, fitted %.3f°\n", e0, ef);
    EXPECT_LT(ef, 0.1 * e0);
    EXPECT_LT(ef, 1.5);  // ∇φ is smeared over about two voxels next to the edges (see fit_mesh.h)
}

TEST(FitMesh, ANormalMapKeepsTheFacesNextToTheEdgesFlatToo) {
    // The engine's filtered normal map of a box is piecewise constant: each sample has the normal of the
    // face nearest to it, sharp across the edges, where ∇φ of the grid turns over about two voxels.
    const Vec3d lo(6.3, 5.8, 6.1), hi(25.7, 26.2, 25.9);
    const Vec3d centre = (lo + hi) * 0.5, half = (hi - lo) * 0.5;
    const Volume v = test::make_volume(32, 1.0, test::box_sdf(centre, half));
    NormalMap map;
    for (int a = 0; a < 3; ++a)
        map[std::size_t(a)] = test::make_volume(32, 1.0, [&](const Vec3d& p) {
            int axis = 0;
            double best = -1e300;
            for (int k = 0; k < 3; ++k) {
                const double d = std::abs(p[k] - centre[k]) - half[k];
                if (d > best) best = d, axis = k;
            }
            return axis == a ? (p[a] > centre[a] ? 1.0 : -1.0) : 0.0;
        });
    const Mesh noisy = jittered(grid_box(lo, hi, 24), 0.3, 3u);
    Mesh by_gradient = noisy, by_map = noisy;
    fit_mesh_to_volume(by_gradient, v);
    fit_mesh_to_volume(by_map, v, {}, &map);
    // the faces within 2 voxels of an edge (but not at a corner): where ∇φ is smeared
    const double eg = box_face_error(by_gradient, lo, hi, 0.5), em = box_face_error(by_map, lo, hi, 0.5);
    std::printf("box faces, all but the edge strips of 0.5 voxel: ∇φ %.3f°, normal map %.3f°\n", eg, em);
    EXPECT_LT(em, 0.85 * eg);  // measured 1.80° against 2.22°
    // where the map has no normal (kNoNormal everywhere), the fit falls back to ∇φ: the same result
    NormalMap none;
    for (Volume& c : none) c = test::make_volume(32, 1.0, [](const Vec3d&) { return double(kNoNormal); });
    Mesh fallback = noisy;
    fit_mesh_to_volume(fallback, v, {}, &none);
    EXPECT_EQ(fallback.positions, by_gradient.positions);
}

TEST(FitMesh, OpenBoundaryStaysAndItsRingsMovePartly) {
    // The upper half of an icosphere of radius 10 onto a sphere of radius 9.5: the rim is held, the
    // rings next to it move by 1/3 and 2/3, the rest lands on the smaller sphere.
    const Vec3d c(16.3, 15.8, 16.1);
    const Mesh full = test::icosphere(10.0, 3, c);
    Mesh half;
    half.positions = full.positions;
    for (const Tri& t : full.triangles) {
        double z = 0;
        for (std::uint32_t k : t) z += full.positions[k].z;
        if (z / 3 > c.z + 0.5) half.triangles.push_back(t);
    }
    ASSERT_TRUE(has_open_boundary(half));
    const Volume v = test::make_volume(32, 1.0, test::sphere_sdf(c, 9.5));
    Mesh m = half;
    const FitReport rep = fit_mesh_to_volume(m, v);
    EXPECT_GT(rep.boundary_vertices, 10u);
    // which positions are on the rim: on an edge of one face
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> count;
    for (const Tri& t : half.triangles)
        for (int e = 0; e < 3; ++e) ++count[std::minmax(t[std::size_t(e)], t[std::size_t((e + 1) % 3)])];
    std::vector<char> rim(half.positions.size(), 0), used(half.positions.size(), 0);
    for (const auto& [edge, n] : count)
        if (n == 1) rim[edge.first] = rim[edge.second] = 1;
    for (const Tri& t : half.triangles)
        for (std::uint32_t k : t) used[k] = 1;
    std::size_t rim_count = 0, top_checked = 0;
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        if (rim[i]) {
            ++rim_count;
            EXPECT_EQ(Vec3d(m.positions[i]), Vec3d(half.positions[i])) << "rim vertex " << i << " moved";
        }
        if (used[i] && half.positions[i].z > c.z + 6.0) {  // far from the rim
            EXPECT_NEAR(norm(Vec3d(m.positions[i]) - c), 9.5, 0.1);
            ++top_checked;
        }
    }
    EXPECT_EQ(rim_count, rep.boundary_vertices);
    EXPECT_GT(top_checked, 20u);
    EXPECT_EQ(m.triangles, half.triangles);
}

TEST(FitMesh, CoincidentPositionsMoveTogether) {
    // The icosphere as an unwelded soup (three positions per triangle): the same fit as welded, and
    // not an open surface.
    const Vec3d c(16.3, 15.8, 16.1);
    const Volume v = test::make_volume(32, 1.0, test::sphere_sdf(c, 10.0));
    const Mesh welded = jittered(test::icosphere(10.0, 2, c), 0.3, 5u);
    Mesh soup;
    for (const Tri& t : welded.triangles) {
        const auto b = std::uint32_t(soup.positions.size());
        for (std::uint32_t k : t) soup.positions.push_back(welded.positions[k]);
        soup.triangles.push_back({b, b + 1, b + 2});
    }
    EXPECT_FALSE(has_open_boundary(soup));
    Mesh a = welded, b = soup;
    fit_mesh_to_volume(a, v);
    fit_mesh_to_volume(b, v);
    for (std::size_t f = 0; f < welded.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(Vec3d(b.positions[3 * f + std::size_t(k)]),
                      Vec3d(a.positions[welded.triangles[f][std::size_t(k)]]));
}

TEST(FitMesh, SameResultWithOneAndTwoThreads) {
    const Vec3d lo(6.3, 5.8, 6.1), hi(25.7, 26.2, 25.9);
    const Volume v = test::make_volume(32, 1.0, test::box_sdf((lo + hi) * 0.5, (hi - lo) * 0.5));
    const Mesh noisy = jittered(grid_box(lo, hi, 24), 0.3, 9u);
    Mesh a = noisy, b = noisy;
    tbb::task_arena(1).execute([&] { fit_mesh_to_volume(a, v); });
    tbb::task_arena(2).execute([&] { fit_mesh_to_volume(b, v); });
    for (std::size_t i = 0; i < a.positions.size(); ++i) ASSERT_EQ(Vec3d(a.positions[i]), Vec3d(b.positions[i]));
}

TEST(FitMesh, VerticesOutsideTheBandOrInNoTriangleStay) {
    const Vec3d c(16.3, 15.8, 16.1);
    const Volume v = test::make_volume(32, 1.0, test::sphere_sdf(c, 8.0));
    Mesh m = test::icosphere(8.3, 2, c);
    // a far closed piece, 14 voxels from the surface (the band is 3): a tetrahedron
    const auto b = std::uint32_t(m.positions.size());
    for (const Vec3d p : {Vec3d(30, 30, 30), Vec3d(31, 30, 30), Vec3d(30, 31, 30), Vec3d(30, 30, 31)})
        m.positions.push_back(Vec3f(p));
    for (const Tri t : {Tri{b, b + 2, b + 1}, Tri{b, b + 1, b + 3}, Tri{b, b + 3, b + 2}, Tri{b + 1, b + 2, b + 3}})
        m.triangles.push_back(t);
    m.positions.push_back(Vec3f(c + Vec3d(4.9, 6.1, 2.6)));  // in no triangle, next to the surface
    const Mesh before = m;
    const FitReport rep = fit_mesh_to_volume(m, v);
    EXPECT_EQ(rep.outside_band, 4u);
    for (std::uint32_t k = b; k < b + 5; ++k) EXPECT_EQ(Vec3d(m.positions[k]), Vec3d(before.positions[k]));
    EXPECT_NEAR(norm(Vec3d(m.positions[0]) - c), 8.0, 0.1);
}

TEST(FitMesh, BadInputIsRefused) {
    const Volume v = test::make_volume(16, 1.0, test::sphere_sdf(Vec3d(8, 8, 8), 4.0));
    Mesh m = test::icosphere(4.0, 1, Vec3d(8, 8, 8));
    FitOptions o;
    o.vertex_steps = -1;
    EXPECT_THROW(fit_mesh_to_volume(m, v, o), InvalidInput);
    o = FitOptions{};
    o.boundary_rings = -2;
    EXPECT_THROW(fit_mesh_to_volume(m, v, o), InvalidInput);
    Mesh bad = m;
    bad.triangles.push_back({0, 1, 9999});
    EXPECT_THROW(fit_mesh_to_volume(bad, v), InvalidInput);
    bad = m;
    bad.positions[0].x = NAN;
    EXPECT_THROW(fit_mesh_to_volume(bad, v), InvalidInput);
}

}  // namespace
}  // namespace normalflow
