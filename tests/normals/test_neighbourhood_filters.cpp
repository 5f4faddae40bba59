// Tests of the neighbourhood filters of the normal map (SmoothMode::Bilateral and Guided,
// lib/normals/stages/bilateral.cpp and guided.cpp, on surface_filter.h) and of what they rely on:
// the length scale in the model's units and the volume constraint. Known answers first (a sphere
// does not drift, a noisy cube comes out with flat faces and sharp edges), then properties (a finer
// grid is no worse, a clean box is left alone, the thread count does not matter), then bad options.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "core/errors.h"
#include "extract/extract_surface.h"
#include "normals/smooth.h"
#include "volume_fixtures.h"

namespace normalflow {
namespace {

using test::add_noise;
using test::box_normal_error;
using test::box_sdf;
using test::BoxNormalError;
using test::bumpy_box;
using test::equivalent_radius;
using test::make_volume;
using test::sphere_sdf;

SmoothOptions options(SmoothMode mode, float length_scale = 4.0f) {
    SmoothOptions o;
    o.mode = mode;
    o.length_scale = length_scale;
    return o;
}

TEST(NeighbourhoodFilters, SphereDoesNotDrift) {
    const Vec3d c(24.3, 23.8, 24.1);
    for (const SmoothMode mode : {SmoothMode::Bilateral, SmoothMode::Guided}) {
        Volume v = make_volume(48, 1.0, sphere_sdf(c, 14.0));
        const double r0 = equivalent_radius(v);
        // a length scale of 2 voxels (the sphere's radius is 7 of them; the filter rounds off what
        // is curved over about one disc, 4.8 voxels with the default scale of 4)
        const SmoothReport rep = smooth_volume(v, options(mode, 2.0f));
        // a clean sphere is smooth after the first filter: one main iteration
        EXPECT_EQ(rep.iterations_run(), 1) << to_string(mode);
        EXPECT_TRUE(rep.stopped_smooth) << to_string(mode);
        EXPECT_LT(rep.iterations[0].roughness, kNeighbourhoodRoughness) << to_string(mode);
        const double r1 = equivalent_radius(v);
        const double dev = test::radial_stats(v, c).max_deviation;
        std::printf("%s sphere: r0 %.4f r1 %.4f, max radial deviation %.4f (voxels)\n", to_string(mode), r0, r1, dev);
        EXPECT_LT(std::abs(r1 - r0), 0.05) << to_string(mode);
        EXPECT_LT(dev, 0.15) << to_string(mode);  // still a sphere, as under the diffusions
    }
}

TEST(NeighbourhoodFilters, NoisyCubeComesOutWithFlatFacesAndSharpEdges) {
    // Per-sample noise of 0.25 voxel: the faces of the extracted noisy cube are about 10° off. The
    // bilateral filter flattens the faces as well as isotropic diffusion does and keeps the 90°
    // edges, which isotropic diffusion rounds.
    const Vec3d c(24.4, 23.7, 24.2), e(13, 13, 13);
    const Volume noisy = [&] {
        Volume v = make_volume(48, 1.0, box_sdf(c, e));
        add_noise(v, 0.25, 11u);
        return v;
    }();
    const Volume clean = make_volume(48, 1.0, box_sdf(c, e));
    const BoxNormalError e0 = box_normal_error(extract_surface(noisy), c, e, 2.5);
    const BoxNormalError floor = box_normal_error(extract_surface(clean), c, e, 2.5);
    Volume iso = noisy, bil = noisy;
    SmoothOptions oi;
    oi.mode = SmoothMode::Isotropic;
    oi.iterations = 3;
    oi.normal_steps = 25;
    smooth_volume(iso, oi);
    smooth_volume(bil, options(SmoothMode::Bilateral));
    const BoxNormalError ei = box_normal_error(extract_surface(iso), c, e, 2.5);
    const BoxNormalError eb = box_normal_error(extract_surface(bil), c, e, 2.5);
    std::printf(
        "cube normal error (deg) near edges / on faces: clean %.2f / %.2f, noisy %.2f / %.2f, isotropic "
        "%.2f / %.2f, bilateral %.2f / %.2f\n",
        floor.near_edges, floor.on_faces, e0.near_edges, e0.on_faces, ei.near_edges, ei.on_faces, eb.near_edges,
        eb.on_faces);
    EXPECT_LT(eb.on_faces, 0.25 * e0.on_faces);     // the faces are flat
    EXPECT_LT(eb.on_faces, 0.5 * ei.on_faces);      // flatter than isotropic diffusion makes them
    EXPECT_LT(eb.near_edges, 0.5 * ei.near_edges);  // the edges are not rounded
    EXPECT_LT(eb.near_edges, e0.near_edges);
}

TEST(NeighbourhoodFilters, CleanBoxIsHarmedLessThanByTheDiffusions) {
    // First do no harm. A clean box through the filter: the edges come out much closer to the
    // box's own extraction than through the paper's anisotropic diffusion (the engine's default,
    // which rounds them), and the faces stay within a few degrees of flat. Not yet within half a
    // degree of the extraction (issue 19's target; see docs/history/benchmarks-2026.md).
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    const Volume v0 = make_volume(40, 1.0, box_sdf(c, e));
    const BoxNormalError floor = box_normal_error(extract_surface(v0), c, e, 2.5);
    Volume aniso = v0;
    smooth_volume(aniso, SmoothOptions{});
    const BoxNormalError ea = box_normal_error(extract_surface(aniso), c, e, 2.5);
    for (const SmoothMode mode : {SmoothMode::Bilateral, SmoothMode::Guided}) {
        Volume v = v0;
        smooth_volume(v, options(mode));
        const BoxNormalError r = box_normal_error(extract_surface(v), c, e, 2.5);
        std::printf(
            "clean box, %s: normal error (deg) near edges / on faces %.3f / %.3f (unsmoothed %.3f / %.3f, "
            "anisotropic %.3f / %.3f)\n",
            to_string(mode), r.near_edges, r.on_faces, floor.near_edges, floor.on_faces, ea.near_edges, ea.on_faces);
        EXPECT_LT(r.near_edges, 0.75 * ea.near_edges) << to_string(mode);
        EXPECT_LT(r.on_faces, 3.0) << to_string(mode);
    }
}

TEST(NeighbourhoodFilters, FinerGridIsNoWorse) {
    // The same noisy box at voxel sizes 1 and 1/2, the length scale given in world units (3): the
    // filter's disc and the refit time follow the model, so the finer grid is at least as good.
    // (The diffusions count their steps in voxels: there the finer grid smooths a quarter as much.)
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    const test::Sdf sdf = bumpy_box(c, e, 0.35, 4.0);
    BoxNormalError err[2];
    const double hs[2] = {1.0, 0.5};
    for (int k = 0; k < 2; ++k) {
        const double h = hs[k];
        Volume v = make_volume(int(std::lround(40 / h)), h, sdf);
        smooth_volume(v, options(SmoothMode::Bilateral, float(3.0 / h)));
        err[k] = box_normal_error(extract_surface(v), c, e, 2.5);
        std::printf("bumpy box at h = %.2f: normal error (deg) near edges / on faces %.2f / %.2f\n", h,
                    err[k].near_edges, err[k].on_faces);
    }
    const BoxNormalError bumpy = box_normal_error(extract_surface(make_volume(40, 1.0, sdf)), c, e, 2.5);
    EXPECT_LT(err[0].on_faces, 0.5 * bumpy.on_faces);    // the coarse grid removed the bumps...
    EXPECT_LE(err[1].on_faces, err[0].on_faces + 0.25);  // ...and the fine grid too
    EXPECT_LE(err[1].near_edges, err[0].near_edges + 0.25);
}

TEST(NeighbourhoodFilters, VolumeIsKeptThroughTheRefit) {
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    Volume v0 = make_volume(40, 1.0, box_sdf(c, e));
    add_noise(v0, 0.3, 5u);
    const double vol0 = test::inside_volume(v0);
    Volume kept = v0, free = v0;
    SmoothOptions o = options(SmoothMode::Bilateral);
    const SmoothReport rk = smooth_volume(kept, o);
    o.preserve_volume = false;
    const SmoothReport rf = smooth_volume(free, o);
    const double dk = test::inside_volume(kept) / vol0 - 1.0, df = test::inside_volume(free) / vol0 - 1.0;
    std::printf("noisy box volume change: kept %+.4f%%, free %+.4f%%; shifts", 100 * dk, 100 * df);
    for (const SmoothIteration& it : rk.iterations) std::printf(" %.4f", double(it.volume_shift));
    std::printf("\n");
    EXPECT_LT(std::abs(dk), 0.002);
    EXPECT_LT(std::abs(dk), std::abs(df));  // the constraint is what keeps it
    for (const SmoothIteration& it : rf.iterations) EXPECT_EQ(it.volume_shift, 0.0f);
}

TEST(NeighbourhoodFilters, StopsWhenTheFilterLeavesASmoothMap) {
    // Noise the first iteration does not fully remove: a second one runs. With iterations given,
    // all of them run.
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    Volume noisy = make_volume(40, 1.0, box_sdf(c, e));
    test::add_smooth_noise(noisy, 1.5, 3.0, 7u);
    Volume a = noisy, b = noisy, clean = make_volume(40, 1.0, sphere_sdf(c, 12.0));
    const SmoothReport ra = smooth_volume(a, options(SmoothMode::Bilateral));
    std::printf("noisy box: roughness");
    for (const SmoothIteration& it : ra.iterations) std::printf(" %.4f", double(it.roughness));
    std::printf("\n");
    ASSERT_EQ(ra.iterations_run(), kNeighbourhoodIterations);
    EXPECT_GE(ra.iterations[0].roughness, kNeighbourhoodRoughness);
    EXPECT_FALSE(ra.stopped_smooth);
    SmoothOptions o = options(SmoothMode::Bilateral);
    o.iterations = 3;
    const SmoothReport rc = smooth_volume(clean, o);
    EXPECT_EQ(rc.iterations_run(), 3);  // asked for: no early stop
    EXPECT_FALSE(rc.stopped_smooth);
    (void)b;
}

TEST(NeighbourhoodFilters, BitIdenticalWithOneAndTwoThreads) {
    for (const SmoothMode mode : {SmoothMode::Bilateral, SmoothMode::Guided}) {
        Volume v = make_volume(40, 1.0, box_sdf(Vec3d(20.3, 19.6, 20.2), Vec3d(11, 9, 10)));
        add_noise(v, 0.3, 3u);
        Volume v1 = v, v2 = v;
        SmoothOptions o = options(mode);
        o.threads = 1;
        const SmoothReport r1 = smooth_volume(v1, o);
        o.threads = 2;
        const SmoothReport r2 = smooth_volume(v2, o);
        ASSERT_EQ(v1.block_coords, v2.block_coords) << to_string(mode);
        ASSERT_EQ(v1.values.size(), v2.values.size());
        EXPECT_EQ(0, std::memcmp(v1.values.data(), v2.values.data(), v1.values.size() * sizeof(float)))
            << to_string(mode);
        ASSERT_EQ(r1.iterations.size(), r2.iterations.size());
        for (std::size_t i = 0; i < r1.iterations.size(); ++i) {
            EXPECT_EQ(r1.iterations[i].normal_energy, r2.iterations[i].normal_energy) << to_string(mode);
            EXPECT_EQ(r1.iterations[i].refit_energy, r2.iterations[i].refit_energy) << to_string(mode);
            EXPECT_EQ(r1.iterations[i].volume_shift, r2.iterations[i].volume_shift) << to_string(mode);
        }
    }
}

TEST(NeighbourhoodFilters, DefaultsFollowTheLengthScale) {
    SmoothOptions o = options(SmoothMode::Bilateral, 5.0f);
    EXPECT_EQ(default_normal_steps(SmoothMode::Bilateral), kNeighbourhoodPasses);
    EXPECT_EQ(default_normal_steps(SmoothMode::Anisotropic), 50);
    // the refit time kNeighbourhoodRefitTime·ℓ² in steps of refit_dt
    EXPECT_EQ(default_refit_steps(o), int(std::ceil(kNeighbourhoodRefitTime * 25.0f / o.refit_dt)));
    o.length_scale = 10.0f;  // twice the length: four times the steps
    EXPECT_EQ(default_refit_steps(o), int(std::ceil(kNeighbourhoodRefitTime * 100.0f / o.refit_dt)));
    o.length_scale = 1.0f;  // never below the diffusions' 40
    EXPECT_EQ(default_refit_steps(o), 40);
    o.mode = SmoothMode::Anisotropic;
    o.length_scale = 10.0f;
    EXPECT_EQ(default_refit_steps(o), 40);
}

TEST(NeighbourhoodFilters, BadOptionsNameTheField) {
    const Volume v = make_volume(24, 1.0, sphere_sdf(Vec3d(12, 12, 12), 6.0));
    auto expect_bad = [&](auto set, const char* field) {
        Volume w = v;
        SmoothOptions o = options(SmoothMode::Bilateral);
        set(o);
        try {
            smooth_volume(w, o);
            ADD_FAILURE() << "no error for " << field;
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
        }
    };
    expect_bad([](SmoothOptions& o) { o.length_scale = -1.0f; }, "length_scale");
    expect_bad([](SmoothOptions& o) { o.length_scale = NAN; }, "length_scale");
    expect_bad([](SmoothOptions& o) { o.sigma_spatial = 0.0f; }, "sigma_spatial");
    expect_bad([](SmoothOptions& o) { o.sigma_range = -0.1f; }, "sigma_range");
    expect_bad([](SmoothOptions& o) { o.sigma_range = INFINITY; }, "sigma_range");
}

}  // namespace
}  // namespace normalflow
