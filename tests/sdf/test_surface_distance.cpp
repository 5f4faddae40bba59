// Tests for lib/metrics/surface_distance.h: analytic cases with known answers, properties, bad input.
#include "metrics/surface_distance.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "core/errors.h"
#include "sdf/closest_triangle.h"
#include "sdf_test_meshes.h"

namespace normalflow {
namespace {

SurfaceSamplingOptions few(std::size_t n = 20000) { return {n, 1}; }

TEST(SurfaceDistance, ConcentricSpheresAreTheRadiusDifferenceApart) {
    // Icospheres (chord error about 5e-3): every point of one is (r2 − r1) ± chord from the other.
    const Mesh a = test::icosphere(1.0, 4), b = test::icosphere(1.3, 4);
    const double chord = test::sphere_chord_error(b, 1.3);
    const SurfaceDistance d = surface_distance(a, b, few());
    EXPECT_NEAR(d.mean, 0.3, chord + 1e-3);
    EXPECT_NEAR(d.rms, 0.3, chord + 1e-3);
    EXPECT_NEAR(d.max_a_to_b, 0.3, chord + 1e-3);
    EXPECT_NEAR(d.max_b_to_a, 0.3, chord + 1e-3);
    EXPECT_NEAR(d.hausdorff, 0.3, chord + 1e-3);
    EXPECT_LT(d.mean_normal_angle_deg, 2.0);  // radial normals, up to the facet tilt
    EXPECT_EQ(d.samples, 20000u);
}

TEST(SurfaceDistance, CubeAgainstItselfAndShifted) {
    const Mesh a = test::box_mesh({0, 0, 0}, {1, 1, 1});
    const SurfaceDistance same = surface_distance(a, a, few());
    EXPECT_LT(same.hausdorff, 1e-6);
    EXPECT_NEAR(same.mean_normal_angle_deg, 0.0, 1e-3);

    // Shift by s along x. Distances to B's *surface*: A's face x = 0 is s away; A's face x = 1 lies
    // inside B, min(s, distance to the square's border) away; a point of a side face at x < s is
    // s − x away, the rest lies on B. With P(border distance > t) = (1 − 2t)²:
    //   mean = (s + (1 − (1 − 2s)³)/6 + 4 s²/2) / 6,
    //   mean of squares = (s² + (s² − 8s³/3 + 2s⁴) + 4 s³/3) / 6; B → A is the mirror image.
    const double s = 0.1;
    const Mesh b = test::box_mesh({s, 0, 0}, {1 + s, 1, 1});
    const SurfaceDistance d = surface_distance(a, b, few());
    EXPECT_NEAR(d.hausdorff, s, 1e-5);
    EXPECT_NEAR(d.max_a_to_b, s, 1e-5);
    EXPECT_NEAR(d.max_b_to_a, s, 1e-5);
    EXPECT_NEAR(d.mean, (s + (1 - std::pow(1 - 2 * s, 3)) / 6 + 2 * s * s) / 6, 1e-3);
    EXPECT_NEAR(d.rms, std::sqrt((s * s + (s * s - 8 * s * s * s / 3 + 2 * std::pow(s, 4)) + 4 * s * s * s / 3) / 6),
                1e-3);
}

TEST(SurfaceDistance, AngleBetweenAPlaneAndATiltedPlane) {
    // A square sheet at z = 0 against the same sheet rotated by 20° about the x axis and lifted, so
    // every closest point lies in the interior of the tilted sheet: the angle is 20° everywhere.
    const Mesh a = test::sheet(0.5, 4);
    Mesh b = test::sheet(2.0, 4);
    const double t = 20.0 * std::numbers::pi / 180.0;
    for (Vec3f& p : b.positions) {
        const double y = p.y, z = p.z;
        p = Vec3f(Vec3d(p.x, y * std::cos(t) - z * std::sin(t), y * std::sin(t) + z * std::cos(t) + 0.5));
    }
    const SurfaceDistance d = surface_distance(a, b, few(5000));
    EXPECT_NEAR(d.mean_normal_angle_deg, 20.0, 1e-4);
    const SurfaceDistance flipped = surface_distance(a, test::flipped(b), few(5000));
    EXPECT_NEAR(flipped.mean_normal_angle_deg, 160.0, 1e-4);
    // The distance from (x, y, 0) to the plane through (0, 0, 0.5) with normal (0, −sin t, cos t) is
    // y sin t + 0.5 cos t, largest at y = 0.5.
    EXPECT_NEAR(d.max_a_to_b, 0.5 * std::sin(t) + 0.5 * std::cos(t), 1e-3);
}

TEST(SurfaceDistance, DeterministicForASeedAndAnyThreadCount) {
    const Mesh a = test::torus_mesh(1.0, 0.3, 48, 24), b = test::icosphere(1.1, 3);
    SurfaceDistance d1, d2;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        d1 = surface_distance(a, b, few());
    }
    {
        tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
        d2 = surface_distance(a, b, few());
    }
    EXPECT_EQ(d1.mean, d2.mean);
    EXPECT_EQ(d1.rms, d2.rms);
    EXPECT_EQ(d1.hausdorff, d2.hausdorff);
    EXPECT_EQ(d1.mean_normal_angle_deg, d2.mean_normal_angle_deg);
    const SurfaceDistance other = surface_distance(a, b, {20000, 2});
    EXPECT_NE(other.mean, d1.mean);
    EXPECT_NEAR(other.mean, d1.mean, 0.05 * d1.mean);
}

TEST(SurfaceDistance, SamplesAreUniformByArea) {
    // A = a triangle of area 4 at the origin and one of area 1 about 100 away; B = the big one lifted
    // by 0.1. By area, 1/5 of A's samples lie on the small triangle (distance D in [97, 101.5] from B),
    // the rest 0.1 from B, and B's samples are 0.1 from A:
    //   mean = (0.8 · 0.1 + 0.2 · D + 0.1) / 2 in [9.8, 10.25];
    // a sampler uniform by face (1/2 on each) would give about 24.
    const double l = 2.0 * std::sqrt(2.0), s = std::sqrt(2.0);
    Mesh a;
    a.positions = {Vec3f(0, 0, 0),   Vec3f(float(l), 0, 0),       Vec3f(0, float(l), 0),
                   Vec3f(100, 0, 0), Vec3f(float(100 + s), 0, 0), Vec3f(100, float(s), 0)};
    a.triangles = {{0, 1, 2}, {3, 4, 5}};
    Mesh b;
    b.positions = {Vec3f(0, 0, 0.1f), Vec3f(float(l), 0, 0.1f), Vec3f(0, float(l), 0.1f)};
    b.triangles = {{0, 1, 2}};
    const SurfaceDistance d = surface_distance(a, b, few(20000));
    EXPECT_GT(d.mean, 9.8 - 0.5);  // 0.5: a few standard deviations of the sampled fraction
    EXPECT_LT(d.mean, 10.25 + 0.5);
    EXPECT_NEAR(d.max_b_to_a, 0.1, 1e-6);
}

TEST(SurfaceDistance, SampledMaxDistanceIsTheLargestOfItsPointsWhateverItSkips) {
    // sampled_max_distance searches in full only the points that may raise the largest distance found so far. Its
    // answer must be the largest of all its points' exact distances, measured here one by one by brute force: the
    // vertices and the centroids (samples_per_face = 1) of a bumpy sphere with one spike, to a sphere.
    Mesh from = test::icosphere(1.0, 3);
    for (std::size_t i = 0; i < from.positions.size(); ++i) {
        const double bump = 1.0 + 0.02 * std::sin(37.0 * double(i));  // deterministic, in [0.98, 1.02]
        from.positions[i] = Vec3f(Vec3d(from.positions[i]) * bump);
    }
    from.positions[from.positions.size() / 3] = from.positions[from.positions.size() / 3] * 1.25f;  // the spike
    const Mesh to = test::icosphere(1.0, 4);
    const auto brute = make_brute_force_query(to);
    double expected = 0.0;
    for (const Vec3f& p : from.positions) expected = std::max(expected, brute->closest(Vec3d(p)).squared_distance);
    for (const Tri& t : from.triangles) {
        Vec3d c(0, 0, 0);
        for (int k = 0; k < 3; ++k) c = c + Vec3d(from.positions[t[k]]) * (1.0 / 3);  // as sample_points
        expected = std::max(expected, brute->closest(c).squared_distance);
    }
    expected = std::sqrt(expected);
    EXPECT_GT(expected, 0.2);  // the spike's
    EXPECT_DOUBLE_EQ(sampled_max_distance(from, to, 1), expected);
    // without the spike: the largest bump, found among many points of about the same distance
    Mesh bumpy = from;
    bumpy.positions[from.positions.size() / 3] = bumpy.positions[from.positions.size() / 3] / 1.25f;
    double bump_max = 0.0;
    for (const Vec3f& p : bumpy.positions) bump_max = std::max(bump_max, brute->closest(Vec3d(p)).squared_distance);
    for (const Tri& t : bumpy.triangles) {
        Vec3d c(0, 0, 0);
        for (int k = 0; k < 3; ++k) c = c + Vec3d(bumpy.positions[t[k]]) * (1.0 / 3);
        bump_max = std::max(bump_max, brute->closest(c).squared_distance);
    }
    EXPECT_LT(std::sqrt(bump_max), 0.03);
    EXPECT_DOUBLE_EQ(sampled_max_distance(bumpy, to, 1), std::sqrt(bump_max));
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        EXPECT_DOUBLE_EQ(sampled_max_distance(bumpy, to, 1), std::sqrt(bump_max));
    }
}

TEST(SurfaceDistance, BadInput) {
    const Mesh a = test::icosphere(1.0, 1);
    EXPECT_THROW(surface_distance(a, Mesh{}), InvalidInput);
    EXPECT_THROW(surface_distance(Mesh{}, a), InvalidInput);
    EXPECT_THROW(surface_distance(a, a, {0, 1}), InvalidInput);
    Mesh flat;
    flat.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    flat.triangles = {{0, 1, 2}};
    EXPECT_THROW(surface_distance(flat, a), InvalidInput);
    Mesh bad = a;
    bad.triangles.push_back({0, 1, 500});
    EXPECT_THROW(surface_distance(a, bad), InvalidInput);
}

}  // namespace
}  // namespace normalflow
