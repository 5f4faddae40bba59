// Tests of the level-set normal-map engine (lib/normals/smooth.h), what its filters do: analytic
// cases with known answers (sphere drift, mean curvature flow radius), energy decrease, feature
// preservation, high-boost, and a real noisy model. How it runs (independence of the triangulation
// and of the thread count, the band, stops, cancellation, bad input): test_smooth_run.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"
#include "extract/extract_surface.h"
#include "io/io.h"
#include "metrics/surface_distance.h"
#include "normals/smooth.h"
#include "sdf/scan_convert.h"
#include "sdf/triangle_bvh.h"
#include "smooth_fixtures.h"
#include "volume_fixtures.h"

namespace normalflow {
namespace {

using test::add_noise;
using test::add_smooth_noise;
using test::box_normal_error;
using test::box_sdf;
using test::BoxNormalError;
using test::equivalent_radius;
using test::make_volume;
using test::options;
using test::radial_stats;
using test::RadialStats;
using test::sphere_sdf;
using test::total_curvature;

/// The µ of each main iteration of a report.
std::vector<float> mus(const SmoothReport& r) {
    std::vector<float> m;
    for (const SmoothIteration& it : r.iterations) m.push_back(it.mu);
    return m;
}

// ------------------------------------------------------------------------------------------------
// Known answers

TEST(SmoothVolume, SphereDoesNotDriftIsotropic) {
    const Vec3d c(24.3, 23.8, 24.1);
    Volume v = make_volume(48, 1.0, sphere_sdf(c, 14.0));
    const double r0 = equivalent_radius(v);
    SmoothOptions o;  // library defaults (50 normal steps per main iteration)
    o.mode = SmoothMode::Isotropic;
    o.iterations = 5;
    const SmoothReport rep = smooth_volume(v, o);
    EXPECT_EQ(rep.iterations_run(), 5);
    const double r1 = equivalent_radius(v);
    std::printf("isotropic sphere: r0 %.4f r1 %.4f (voxels)\n", r0, r1);
    EXPECT_LT(std::abs(r1 - r0), 0.05);
    EXPECT_LT(radial_stats(v, c).max_deviation, 0.15);  // still a sphere
}

TEST(SmoothVolume, HandsOutItsLastNormalMapUnitAndRadialOnASphere) {
    const Vec3d c(24.3, 23.8, 24.1);
    for (const SmoothMode mode : {SmoothMode::Isotropic, SmoothMode::Bilateral}) {
        SCOPED_TRACE(to_string(mode));
        Volume v = make_volume(48, 1.0, sphere_sdf(c, 14.0));
        SmoothOptions o;
        o.mode = mode;
        o.iterations = 2;
        NormalMap map;
        smooth_volume(v, o, nullptr, &map);
        std::size_t defined = 0, near_surface = 0;
        double worst = 0;
        for (int k = 0; k < 48; ++k)
            for (int j = 0; j < 48; ++j)
                for (int i = 0; i < 48; ++i) {
                    const Vec3d p = v.grid.world(Vec3d(i, j, k));
                    const bool near = std::abs(norm(p - c) - 14.0) < 1.0;
                    near_surface += near;
                    if (!(std::abs(map[0].value(i, j, k)) < 1.5f)) continue;
                    ++defined;
                    const Vec3d n(map[0].value(i, j, k), map[1].value(i, j, k), map[2].value(i, j, k));
                    EXPECT_NEAR(norm(n), 1.0, 1e-3);
                    if (near)
                        worst = std::max(worst, std::acos(std::min(1.0, dot(n, (p - c) / norm(p - c)))) * 57.29578);
                }
        EXPECT_GE(defined, near_surface);  // every sample within a voxel of the surface, and more
        EXPECT_LT(worst, 5.0);             // outward and radial (the worst sample; 3.4° measured)
    }
    Volume v = make_volume(48, 1.0, sphere_sdf(c, 14.0));
    SmoothOptions o;
    o.mode = SmoothMode::MeanCurvature;
    o.iterations = 1;
    NormalMap map;
    smooth_volume(v, o, nullptr, &map);
    EXPECT_TRUE(map[0].values.empty());  // mean curvature flow has no normal map
}

TEST(SmoothVolume, SphereDoesNotDriftAnisotropic) {
    const Vec3d c(24.3, 23.8, 24.1);
    Volume v = make_volume(48, 1.0, sphere_sdf(c, 14.0));
    const double r0 = equivalent_radius(v);
    SmoothOptions o;  // library defaults
    o.iterations = 5;
    smooth_volume(v, o);
    const double r1 = equivalent_radius(v);
    std::printf("anisotropic sphere: r0 %.4f r1 %.4f (voxels)\n", r0, r1);
    EXPECT_LT(std::abs(r1 - r0), 0.05);
    EXPECT_LT(radial_stats(v, c).max_deviation, 0.15);
}

TEST(SmoothVolume, SphereDoesNotDriftWithVoxelSize) {
    // world units: the same sphere at h = 0.05 must behave exactly as at h = 1 (engine works in voxels)
    const double h = 0.05;
    const Vec3d c(24.3 * h, 23.8 * h, 24.1 * h);
    Volume v = make_volume(48, h, sphere_sdf(c, 14.0 * h));
    const double r0 = equivalent_radius(v);
    smooth_volume(v, options(SmoothMode::Isotropic, 2));
    EXPECT_LT(std::abs(equivalent_radius(v) - r0), 0.05);
    EXPECT_FLOAT_EQ(v.background, float(8.0 * h));
}

TEST(SmoothVolume, MeanCurvatureFlowShrinksSphereAsSqrtR0SquaredMinus4t) {
    // φ_t = |∇φ| H with H = κ1 + κ2 = 2/r: dr/dt = −2/r, so r(t)² = r0² − 4t (voxel units, h = 1).
    const double r0 = 16.0;
    const Vec3d c(26.2, 25.9, 26.4);
    Volume v = make_volume(52, 1.0, sphere_sdf(c, r0));
    const double r0_measured = equivalent_radius(v);
    SmoothOptions o = options(SmoothMode::MeanCurvature, 1);
    o.normal_steps = 50;
    o.refit_dt = 0.1f;
    double t = 0.0;
    for (int round = 0; round < 3; ++round) {
        smooth_volume(v, o);
        t += o.normal_steps * double(o.refit_dt);
        const double expected = std::sqrt(r0_measured * r0_measured - 4.0 * t);
        const double r = equivalent_radius(v);
        std::printf("mcf: t %.1f r %.4f expected %.4f (%.2f%%)\n", t, r, expected, 100.0 * (r - expected) / expected);
        EXPECT_NEAR(r, expected, 0.02 * expected) << "t = " << t;
        EXPECT_LT(r, r0_measured);
    }
    // still a sphere, centred where it was
    const RadialStats s = radial_stats(v, c);
    EXPECT_LT(s.max_deviation, 0.2);
}

// ------------------------------------------------------------------------------------------------
// Energies

TEST(SmoothVolume, NormalEnergyDecreasesInLoopAndRefitEnergyInRefit) {
    for (const SmoothMode mode : {SmoothMode::Isotropic, SmoothMode::Anisotropic}) {
        Volume v = make_volume(48, 1.0, sphere_sdf(Vec3d(24, 24, 24), 14.0));
        add_noise(v, 0.3, 7u);
        const SmoothReport rep = smooth_volume(v, options(mode, 3));
        ASSERT_EQ(rep.iterations.size(), 3u);
        for (int it = 0; it < 3; ++it) {
            const SmoothIteration& r = rep.iterations[std::size_t(it)];
            const auto& g = r.normal_energy;
            ASSERT_EQ(g.size(), 26u);  // before each of 25 steps and after the last
            EXPECT_LT(r.normal_energy_end(), r.normal_energy_start()) << to_string(mode);
            for (std::size_t s = 1; s < g.size(); ++s)
                EXPECT_LE(g[s], g[s - 1] * (1.0 + 1e-6)) << to_string(mode) << " iteration " << it << " step " << s;
            const auto& d = r.refit_energy;
            ASSERT_GE(d.size(), 2u);
            EXPECT_LT(r.refit_energy_end, r.refit_energy_start()) << to_string(mode);
            // D decreases at every refit step up to the one where the refit stopped, and the
            // result is the iterate with the smallest D
            for (std::size_t s = 1; s + 1 < d.size(); ++s)
                EXPECT_LT(d[s], d[s - 1]) << to_string(mode) << " iteration " << it << " step " << s;
            EXPECT_EQ(r.refit_energy_end, *std::min_element(d.begin(), d.end()));
            EXPECT_GE(r.refit_steps, 1);
            EXPECT_GT(r.band_voxels, 0u);
            EXPECT_GE(r.allocated_voxels, r.band_voxels);
        }
        if (mode == SmoothMode::Isotropic) {
            // the first loop sees the noise: a large drop of G
            EXPECT_LT(rep.iterations[0].normal_energy_end(), 0.5 * rep.iterations[0].normal_energy_start());
        }
    }
}

// ------------------------------------------------------------------------------------------------
// Features

TEST(SmoothVolume, AnisotropicKeepsNoisyCubeEdgesWhereIsotropicRoundsThem) {
    const Vec3d c(24.4, 23.7, 24.2), e(13, 13, 13);
    const Volume noisy = [&] {
        Volume v = make_volume(48, 1.0, box_sdf(c, e));
        add_noise(v, 0.25, 11u);
        return v;
    }();
    const BoxNormalError err0 = box_normal_error(extract_surface(noisy), c, e, 2.5);
    Volume iso = noisy, aniso = noisy;
    smooth_volume(iso, options(SmoothMode::Isotropic, 3));
    smooth_volume(aniso, options(SmoothMode::Anisotropic, 3));
    const BoxNormalError ei = box_normal_error(extract_surface(iso), c, e, 2.5);
    const BoxNormalError ea = box_normal_error(extract_surface(aniso), c, e, 2.5);
    std::printf(
        "cube normal error (deg) near edges / on faces: noisy %.2f / %.2f, isotropic %.2f / %.2f, "
        "anisotropic %.2f / %.2f\n",
        err0.near_edges, err0.on_faces, ei.near_edges, ei.on_faces, ea.near_edges, ea.on_faces);
    // both remove the noise on the flat parts
    EXPECT_LT(ei.on_faces, 0.5 * err0.on_faces);
    EXPECT_LT(ea.on_faces, 0.5 * err0.on_faces);
    // isotropic rounds the edges, anisotropic keeps them sharp
    EXPECT_LT(ea.near_edges, 0.6 * ei.near_edges);
    EXPECT_LT(ea.near_edges, err0.near_edges);
}

TEST(SmoothVolume, RobustConductanceScaleRemovesHeavyNoiseAndKeepsEdges) {
    // Noise far above µ = 0.1/voxel: with the fixed scale (mu_robust = 0) the anisotropic flow takes
    // much of it for features and keeps it; the default robust scale raises µ to the noise level,
    // removes the noise on the faces and still keeps the edges sharper than isotropic smoothing does.
    const Vec3d c(24.4, 23.7, 24.2), e(13, 13, 13);
    const Volume noisy = [&] {
        Volume v = make_volume(48, 1.0, box_sdf(c, e));
        add_smooth_noise(v, 4.0, 3.0, 5u);  // correlated over 3 voxels: faces about 50° off
        return v;
    }();
    const BoxNormalError err0 = box_normal_error(extract_surface(noisy), c, e, 2.5);
    Volume fixed = noisy, robust = noisy, iso = noisy;
    SmoothOptions o = options(SmoothMode::Anisotropic, 3);
    ASSERT_GT(o.mu_robust, 0.0f);  // the default
    const SmoothReport rr = smooth_volume(robust, o);
    o.mu_robust = 0.0f;
    const SmoothReport rf = smooth_volume(fixed, o);
    smooth_volume(iso, options(SmoothMode::Isotropic, 3));
    const BoxNormalError ef = box_normal_error(extract_surface(fixed), c, e, 2.5);
    const BoxNormalError er = box_normal_error(extract_surface(robust), c, e, 2.5);
    const BoxNormalError ei = box_normal_error(extract_surface(iso), c, e, 2.5);
    std::printf(
        "heavy noise, cube normal error (deg) near edges / on faces: noisy %.2f / %.2f, fixed mu %.2f / "
        "%.2f, robust mu %.2f / %.2f, isotropic %.2f / %.2f; robust mu %.3f -> %.3f\n",
        err0.near_edges, err0.on_faces, ef.near_edges, ef.on_faces, er.near_edges, er.on_faces, ei.near_edges,
        ei.on_faces, double(mus(rr).front()), double(mus(rr).back()));
    const std::vector<float> mf = mus(rf), mr = mus(rr);
    ASSERT_EQ(mf.size(), 3u);
    ASSERT_EQ(mr.size(), 3u);
    for (const float m : mf) EXPECT_EQ(m, 0.1f);                              // fixed: the option's µ
    EXPECT_GT(mr.front(), 0.2f);                                              // the noise raises the scale...
    for (std::size_t i = 1; i < mr.size(); ++i) EXPECT_LE(mr[i], mr[i - 1]);  // ...and never rises
    for (const float m : mr) EXPECT_GE(m, 0.1f);                              // never below the option's µ
    EXPECT_LT(er.on_faces, 0.7 * ef.on_faces);
    EXPECT_LT(er.near_edges, ef.near_edges);
    EXPECT_LT(er.near_edges, ei.near_edges);
}

TEST(SmoothVolume, RobustConductanceScaleLeavesACleanBoxAlone) {
    // A clean box has no noise to estimate. After pre-smoothing its edges bend the normals over a few
    // voxels, and on the smaller box that covers more than 3/4 of the surface (a scale measured on the
    // pre-smoothed normals alone rose to 0.168 and blurred the edges from 17° to 29°); the raw normals
    // are flat there, so the scale stays µ and the result is the fixed-scale result, bit for bit.
    struct Box {
        int n;
        Vec3d c, e;
    };
    for (const Box& box :
         {Box{48, Vec3d(24.4, 23.7, 24.2), Vec3d(13, 13, 13)}, Box{40, Vec3d(20.3, 19.6, 20.2), Vec3d(11, 9, 10)}}) {
        const Volume v0 = make_volume(box.n, 1.0, box_sdf(box.c, box.e));
        Volume a = v0, b = v0;
        SmoothOptions o = options(SmoothMode::Anisotropic, 3);
        const SmoothReport r = smooth_volume(b, o);  // the default robust scale
        o.mu_robust = 0.0f;
        smooth_volume(a, o);
        const BoxNormalError ef = box_normal_error(extract_surface(a), box.c, box.e, 2.5);
        const BoxNormalError er = box_normal_error(extract_surface(b), box.c, box.e, 2.5);
        std::printf(
            "clean box %d: normal error (deg) near edges / on faces: fixed mu %.3f / %.3f, robust mu %.3f / "
            "%.3f; robust mu %.3f -> %.3f\n",
            box.n, ef.near_edges, ef.on_faces, er.near_edges, er.on_faces, double(mus(r).front()),
            double(mus(r).back()));
        for (const float m : mus(r)) EXPECT_EQ(m, 0.1f) << box.n;
        ASSERT_EQ(a.values.size(), b.values.size());
        EXPECT_EQ(0, std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float))) << box.n;
    }
}

// ------------------------------------------------------------------------------------------------
// High-boost

/// Sphere with bumps: the zero set of |p − c| − r − a·sin(ωx)sin(ωy)sin(ωz) (not a distance; the
/// engine reinitialises it).
test::Sdf bumpy_sphere(const Vec3d& c, double r, double a, double w) {
    return [=](const Vec3d& p) {
        const Vec3d d = p - c;
        return norm(d) - r - a * std::sin(w * d.x) * std::sin(w * d.y) * std::sin(w * d.z);
    };
}

TEST(SmoothVolume, HighBoostRaisesTotalCurvatureOfBumpySurface) {
    const Vec3d c(24.2, 23.9, 24.3);
    Volume v = make_volume(48, 1.0, bumpy_sphere(c, 14.0, 1.0, 0.45));
    smooth_volume(v, options(SmoothMode::Isotropic, 1));  // a distance function to start from
    const double k0 = total_curvature(v);
    Volume boosted = v, smoothed = v;
    SmoothOptions o = options(SmoothMode::HighBoost, 2);
    o.alpha = 1.0f;
    smooth_volume(boosted, o);
    smooth_volume(smoothed, options(SmoothMode::Isotropic, 2));
    const double kb = total_curvature(boosted), ks = total_curvature(smoothed);
    std::printf("total curvature: start %.2f highboost %.2f isotropic %.2f\n", k0, kb, ks);
    EXPECT_GT(kb, 1.1 * k0);
    EXPECT_LT(ks, k0);
}

TEST(SmoothVolume, HighBoostLeavesSphereASphere) {
    const Vec3d c(24.3, 23.8, 24.1);
    Volume v = make_volume(48, 1.0, sphere_sdf(c, 14.0));
    const double r0 = equivalent_radius(v);
    const RadialStats s0 = radial_stats(v, c);
    SmoothOptions o = options(SmoothMode::HighBoost, 3);
    smooth_volume(v, o);
    const RadialStats s1 = radial_stats(v, c);
    std::printf("highboost sphere: r0 %.4f r1 %.4f, max radial deviation %.4f -> %.4f\n", r0, equivalent_radius(v),
                s0.max_deviation, s1.max_deviation);
    EXPECT_LT(std::abs(equivalent_radius(v) - r0), 0.1);
    EXPECT_LT(s1.max_deviation, 0.2);
}

// ------------------------------------------------------------------------------------------------
// Real data (skipped without shared/data)

TEST(SmoothVolume, RealNoisyFandiskGetsCloserToTheGroundTruth) {
    const std::filesystem::path dir = std::filesystem::path(NORMALFLOW_TEST_DATA) / "pairs_gnf";
    if (!std::filesystem::exists(dir / "fandisk_n0.3.ply")) GTEST_SKIP() << "no " << dir;
    const Mesh noisy = read_mesh((dir / "fandisk_n0.3.ply").string());
    const Mesh truth = read_mesh((dir / "fandisk_gt.ply").string());
    ScanConvertOptions so;
    so.resolution = 64;
    const Volume v0 = scan_convert(noisy, *make_bvh_query(noisy), so);
    SurfaceSamplingOptions ss;
    ss.samples = 20000;
    const SurfaceDistance d0 = surface_distance(extract_surface(v0), truth, ss);
    Volume iso = v0, aniso = v0;
    smooth_volume(iso, options(SmoothMode::Isotropic, 3));
    smooth_volume(aniso, options(SmoothMode::Anisotropic, 3));
    const SurfaceDistance di = surface_distance(extract_surface(iso), truth, ss);
    const SurfaceDistance da = surface_distance(extract_surface(aniso), truth, ss);
    std::printf("fandisk_n0.3 at 64: normal error (deg) voxelised noisy %.2f, isotropic %.2f, anisotropic %.2f\n",
                d0.mean_normal_angle_deg, di.mean_normal_angle_deg, da.mean_normal_angle_deg);
    EXPECT_LT(di.mean_normal_angle_deg, d0.mean_normal_angle_deg);
    EXPECT_LT(da.mean_normal_angle_deg, d0.mean_normal_angle_deg);
    EXPECT_LT(da.mean, 0.5 * v0.grid.voxel_size);  // no drift
}

}  // namespace
}  // namespace normalflow
