// Tests of the total-variation filter of the normal map (SmoothMode::TotalVariation,
// lib/normals/stages/total_variation.h). Known answers first: a noisy cube comes out with planar
// faces meeting at right angles; then properties of the solver (its objective falls, more
// iterations do not raise it) and of the mode (a finer grid is no worse, a sphere does not drift,
// the thread count does not matter, a bad option is named).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "core/errors.h"
#include "extract/extract_surface.h"
#include "normals/smooth.h"
#include "volume_fixtures.h"

namespace normalflow {
namespace {

using test::add_noise;
using test::box_sdf;
using test::bumpy_box;
using test::make_volume;

constexpr double kDeg = 180.0 / 3.14159265358979323846;

SmoothOptions tv(float length_scale = 4.0f) {
    SmoothOptions o;
    o.mode = SmoothMode::TotalVariation;
    o.length_scale = length_scale;
    return o;
}

/// The faces of a box (centre c, half extents e) on a mesh: per face (axis × sign) the area-weighted
/// mean normal of the triangles at least `reach` from the box's edges, and the area-weighted mean
/// angle of those triangles' normals to it (the spread: 0 for a planar face).
struct BoxFaces {
    std::array<Vec3d, 6> mean{};
    std::array<double, 6> spread{};
};

BoxFaces box_faces(const Mesh& m, const Vec3d& c, const Vec3d& e, double reach) {
    std::array<Vec3d, 6> sum{};
    std::array<double, 6> area{};
    // the face a triangle lies on, away from the edges (-1: near an edge, or of zero area)
    auto classify = [&](const Tri& t, Vec3d& n, double& a) {
        test::BoxTriangle bt;
        if (!test::box_triangle(m, t, c, e, reach, bt) || bt.near != 1) return -1;
        n = bt.normal;
        a = bt.area;
        return 2 * bt.axis + (bt.side < 0 ? 0 : 1);
    };
    for (const auto& t : m.triangles) {
        Vec3d n;
        double a;
        const int f = classify(t, n, a);
        if (f < 0) continue;
        sum[std::size_t(f)] = sum[std::size_t(f)] + n * a;
        area[std::size_t(f)] += a;
    }
    BoxFaces out;
    for (int f = 0; f < 6; ++f)
        out.mean[std::size_t(f)] = sum[std::size_t(f)] / std::max(norm(sum[std::size_t(f)]), 1e-30);
    std::array<double, 6> ang{};
    for (const auto& t : m.triangles) {
        Vec3d n;
        double a;
        const int f = classify(t, n, a);
        if (f < 0) continue;
        ang[std::size_t(f)] += a * std::acos(std::clamp(dot(n, out.mean[std::size_t(f)]), -1.0, 1.0)) * kDeg;
    }
    for (int f = 0; f < 6; ++f)
        out.spread[std::size_t(f)] = area[std::size_t(f)] > 0 ? ang[std::size_t(f)] / area[std::size_t(f)] : 180.0;
    return out;
}

double max_spread(const BoxFaces& b) { return *std::max_element(b.spread.begin(), b.spread.end()); }

/// The largest |dihedral − 90°| between the mean normals of adjacent faces (different axes).
double worst_right_angle(const BoxFaces& b) {
    double worst = 0;
    for (int f = 0; f < 6; ++f)
        for (int g = 0; g < 6; ++g)
            if (f / 2 != g / 2) {
                const double a =
                    std::acos(std::clamp(dot(b.mean[std::size_t(f)], b.mean[std::size_t(g)]), -1.0, 1.0)) * kDeg;
                worst = std::max(worst, std::abs(a - 90.0));
            }
    return worst;
}

TEST(TotalVariation, NoisyCubeComesOutWithPlanarFacesAtRightAngles) {
    const Vec3d c(24.4, 23.7, 24.2), e(13, 13, 13);
    Volume noisy = make_volume(48, 1.0, box_sdf(c, e));
    add_noise(noisy, 0.25, 11u);
    Volume iso = noisy, flat = noisy;
    SmoothOptions oi;
    oi.mode = SmoothMode::Isotropic;
    oi.iterations = 3;
    oi.normal_steps = 25;
    smooth_volume(iso, oi);
    // One main iteration: the solve and the refit it drives. (With the mode's default two, the
    // second solve starts from the refitted faces and the worst face tilts in terraces: 4.5°;
    // the bilateral filter's second iteration also raises its spread, 1.5° → 2.5°.)
    SmoothOptions ot = tv();
    ot.iterations = 1;
    const SmoothReport rep = smooth_volume(flat, ot);
    const BoxFaces f0 = box_faces(extract_surface(noisy), c, e, 2.5);
    const BoxFaces fi = box_faces(extract_surface(iso), c, e, 2.5);
    const BoxFaces ft = box_faces(extract_surface(flat), c, e, 2.5);
    std::printf(
        "cube face spread (deg, worst face): noisy %.2f, isotropic %.2f, tv %.2f; worst |dihedral - 90| "
        "noisy %.2f, isotropic %.2f, tv %.2f\n",
        max_spread(f0), max_spread(fi), max_spread(ft), worst_right_angle(f0), worst_right_angle(fi),
        worst_right_angle(ft));
    EXPECT_LT(max_spread(ft), 0.35 * max_spread(fi));  // planar: a small fraction of isotropic's spread
    EXPECT_LT(max_spread(ft), 0.2 * max_spread(f0));
    EXPECT_LT(worst_right_angle(ft), 1.5);  // the faces meet at 90°
    EXPECT_LT(test::box_normal_error(extract_surface(flat), c, e, 2.5).near_edges,
              0.5 * test::box_normal_error(extract_surface(iso), c, e, 2.5).near_edges);  // and the edges stay sharp
    // the solver lowered its objective in every main iteration
    for (const SmoothIteration& it : rep.iterations) {
        ASSERT_EQ(it.normal_energy.size(), 2u);
        EXPECT_LT(it.normal_energy[1], it.normal_energy[0]);
    }
}

TEST(TotalVariation, MoreSolverIterationsDoNotRaiseTheObjective) {
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    Volume v0 = make_volume(40, 1.0, box_sdf(c, e));
    add_noise(v0, 0.3, 5u);
    double end[2];
    const int steps[2] = {25, 200};
    for (int k = 0; k < 2; ++k) {
        Volume v = v0;
        SmoothOptions o = tv();
        o.iterations = 1;
        o.normal_steps = steps[k];
        const SmoothReport r = smooth_volume(v, o);
        end[k] = r.iterations[0].normal_energy[1];
        std::printf("tv objective after %d iterations: %.2f (from %.2f)\n", steps[k], end[k],
                    r.iterations[0].normal_energy[0]);
    }
    EXPECT_LE(end[1], end[0]);
}

TEST(TotalVariation, SphereDoesNotDrift) {
    const Vec3d c(24.3, 23.8, 24.1);
    Volume v = make_volume(48, 1.0, test::sphere_sdf(c, 14.0));
    const double r0 = test::equivalent_radius(v);
    smooth_volume(v, tv(2.0f));
    const double r1 = test::equivalent_radius(v);
    const double dev = test::radial_stats(v, c).max_deviation;
    std::printf("tv sphere: r0 %.4f r1 %.4f, max radial deviation %.4f (voxels)\n", r0, r1, dev);
    EXPECT_LT(std::abs(r1 - r0), 0.05);
    EXPECT_LT(dev, 0.5);  // total variation makes a sphere faceted (piecewise-constant normals), not smaller
}

TEST(TotalVariation, FinerGridIsNoWorse) {
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    const test::Sdf sdf = bumpy_box(c, e, 0.35, 4.0);
    test::BoxNormalError err[2];
    const double hs[2] = {1.0, 0.5};
    for (int k = 0; k < 2; ++k) {
        const double h = hs[k];
        Volume v = make_volume(int(std::lround(40 / h)), h, sdf);
        smooth_volume(v, tv(float(3.0 / h)));
        err[k] = test::box_normal_error(extract_surface(v), c, e, 2.5);
        std::printf("tv, bumpy box at h = %.2f: normal error (deg) near edges / on faces %.2f / %.2f\n", h,
                    err[k].near_edges, err[k].on_faces);
    }
    const test::BoxNormalError bumpy = test::box_normal_error(extract_surface(make_volume(40, 1.0, sdf)), c, e, 2.5);
    EXPECT_LT(err[0].on_faces, 0.5 * bumpy.on_faces);
    EXPECT_LE(err[1].on_faces, err[0].on_faces + 0.25);
    EXPECT_LE(err[1].near_edges, err[0].near_edges + 0.25);
}

TEST(TotalVariation, BitIdenticalWithOneAndTwoThreads) {
    Volume v = make_volume(40, 1.0, box_sdf(Vec3d(20.3, 19.6, 20.2), Vec3d(11, 9, 10)));
    add_noise(v, 0.3, 3u);
    Volume v1 = v, v2 = v;
    SmoothOptions o = tv();
    o.threads = 1;
    const SmoothReport r1 = smooth_volume(v1, o);
    o.threads = 2;
    const SmoothReport r2 = smooth_volume(v2, o);
    ASSERT_EQ(v1.values.size(), v2.values.size());
    EXPECT_EQ(0, std::memcmp(v1.values.data(), v2.values.data(), v1.values.size() * sizeof(float)));
    ASSERT_EQ(r1.iterations.size(), r2.iterations.size());
    for (std::size_t i = 0; i < r1.iterations.size(); ++i)
        EXPECT_EQ(r1.iterations[i].normal_energy, r2.iterations[i].normal_energy);
}

TEST(TotalVariation, BadLambdaIsNamed) {
    for (const float bad : {0.0f, -1.0f, float(NAN), float(INFINITY)}) {
        Volume v = make_volume(24, 1.0, test::sphere_sdf(Vec3d(12, 12, 12), 6.0));
        SmoothOptions o = tv();
        o.tv_lambda = bad;
        try {
            smooth_volume(v, o);
            ADD_FAILURE() << "no error for tv_lambda " << bad;
        } catch (const InvalidInput& ex) {
            EXPECT_NE(std::string(ex.what()).find("tv_lambda"), std::string::npos) << ex.what();
        }
    }
}

}  // namespace
}  // namespace normalflow
