// Tests for lib/normals/bricks.h: the scan conversion and the engine brick by brick against the whole run.
#include "normals/bricks.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "../sdf/sdf_test_meshes.h"
#include "band/layout.h"
#include "core/errors.h"
#include "sdf/winding_number.h"
#include "volume_fixtures.h"

namespace normalflow {
namespace {

// A sphere whose vertices were moved along their normals by up to ±amplitude (deterministic), and a box beside it.
Mesh noisy_scene(double amplitude) {
    Mesh s = test::icosphere(1.0, 4);
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        const Vec3f p = s.positions[i];
        const double n = test::hash_noise(int(i), 7, 11, 3u);
        s.positions[i] = p * float(1.0 + amplitude * n);
    }
    return test::concat(s, test::box_mesh({1.3, -0.5, -0.4}, {2.1, 0.5, 0.4}));
}

struct Result {
    Volume v;
    SmoothReport report;
};

// The whole run: scan_convert, then smooth_volume.
Result whole(const Mesh& m, const ScanConvertOptions& scan, const SmoothOptions& opt) {
    const auto q = make_bvh_query(m);
    Result r{scan_convert(m, *q, scan), {}};
    r.report = smooth_volume(r.v, opt);
    return r;
}

Result bricked(const Mesh& m, const ScanConvertOptions& scan, const SmoothOptions& opt, const BrickOptions& b,
               BrickReport* rep = nullptr) {
    const auto q = make_bvh_query(m);
    const WindingNumber wn(m);
    Result r;
    r.v = smooth_in_bricks(m, *q, &wn, scan, opt, b, rep, &r.report);
    return r;
}

// The largest |φ_a − φ_b| (voxels) over the samples within a voxel of either surface, and the number of samples whose
// sign differs.
std::pair<double, std::size_t> surface_difference(const Volume& a, const Volume& b) {
    EXPECT_EQ(a.grid.dims, b.grid.dims);
    const double h = a.grid.voxel_size;
    double worst = 0;
    std::size_t signs = 0;
    for (int k = 0; k < a.grid.dims[2]; ++k)
        for (int j = 0; j < a.grid.dims[1]; ++j)
            for (int i = 0; i < a.grid.dims[0]; ++i) {
                const double x = a.value(i, j, k) / h, y = b.value(i, j, k) / h;
                signs += (x < 0) != (y < 0);
                if (std::min(std::abs(x), std::abs(y)) < 1.0) worst = std::max(worst, std::abs(x - y));
            }
    return {worst, signs};
}

ScanConvertOptions scan_at(int resolution) {
    ScanConvertOptions s;
    s.resolution = resolution;
    s.half_width = 8.0f;
    return s;
}

SmoothOptions bilateral(int iterations, float ell) {
    SmoothOptions o;
    o.mode = SmoothMode::Bilateral;
    o.iterations = iterations;
    o.length_scale = ell;
    return o;
}

// Bricks whose halo covers what their interior depends on hold what the whole run holds: within 0.05 voxel near
// the surface (the bound), the same inside and outside everywhere, the grid and band layout of the whole
// run. The windows overlap the grid's border and each other; the bricks are far smaller than the grid.
TEST(Bricks, WithTheirHaloTheyHoldWhatTheWholeRunHolds) {
    const Mesh m = noisy_scene(0.02);
    const ScanConvertOptions scan = scan_at(72);
    const SmoothOptions opt = bilateral(1, 1.5f);
    const Result w = whole(m, scan, opt);
    BrickReport rep;
    const Result b = bricked(m, scan, opt, BrickOptions{.brick_voxels = 24}, &rep);
    EXPECT_EQ(rep.halo_voxels, (brick_halo_voxels(opt, 1) + 7) / 8 * 8);
    EXPECT_GT(rep.total(), 20);
    EXPECT_GT(rep.bricks_run, 10);
    EXPECT_EQ(rep.passes, 1);
    EXPECT_EQ(b.v.half_width, engine::kHalfWidth);
    const auto [worst, signs] = surface_difference(w.v, b.v);
    EXPECT_LT(worst, 0.05);
    EXPECT_EQ(signs, 0u);
    EXPECT_NO_THROW(b.v.check("bricks"));
}

// The filters' automatic stop is decided on the whole surface: a first pass of one iteration, then the run's
// iterations only where the whole run would go on. A smooth sphere stops after one (as the whole run does), a
// noisy one goes on to two, and either way the bricks hold what the whole run holds.
TEST(Bricks, TheAutomaticStopIsTheWholeRunsDecision) {
    for (const double amplitude : {0.0, 0.08}) {
        SCOPED_TRACE(amplitude);
        const Mesh m = noisy_scene(amplitude);
        const ScanConvertOptions scan = scan_at(80);
        const SmoothOptions opt = bilateral(0, 1.5f);
        const Result w = whole(m, scan, opt);
        BrickReport rep;
        const Result b = bricked(m, scan, opt, BrickOptions{.brick_voxels = 48}, &rep);
        EXPECT_EQ(b.report.stopped_smooth, w.report.stopped_smooth);
        EXPECT_EQ(rep.passes, w.report.iterations_run() == 1 ? 1 : 2);
        EXPECT_EQ(b.report.iterations_run(), w.report.iterations_run());
        EXPECT_EQ(w.report.iterations_run(), amplitude == 0.0 ? 1 : 2);
        EXPECT_LT(surface_difference(w.v, b.v).first, 0.05);
    }
}

// A checkpoint that stops the run after the first pass leaves the first iteration's volume; the result does not
// depend on the number of threads.
TEST(Bricks, ACheckpointStopsAfterTheFirstPassAndThreadsChangeNothing) {
    const Mesh m = noisy_scene(0.03);
    const ScanConvertOptions scan = scan_at(40);
    SmoothOptions opt = bilateral(2, 1.5f);
    int asked = 0;
    const SmoothCheckpoint stop = [&](const Volume& v) {
        ++asked;
        EXPECT_GT(v.block_count(), 0u);
        return false;
    };
    const auto q = make_bvh_query(m);
    const WindingNumber wn(m);
    BrickReport rep;
    SmoothReport sr;
    const BrickOptions b{.brick_voxels = 32};
    const Volume stopped = smooth_in_bricks(m, *q, &wn, scan, opt, b, &rep, &sr, nullptr, &stop);
    EXPECT_EQ(asked, 1);
    EXPECT_TRUE(sr.stopped_at_checkpoint);
    EXPECT_EQ(rep.passes, 1);
    opt.iterations = 1;
    const Volume one = smooth_in_bricks(m, *q, &wn, scan, opt, b);
    EXPECT_EQ(stopped.values, one.values);
    opt.iterations = 2;
    opt.threads = 1;
    const Volume a = smooth_in_bricks(m, *q, &wn, scan, opt, b);
    opt.threads = 2;
    const Volume c = smooth_in_bricks(m, *q, &wn, scan, opt, b);
    EXPECT_EQ(a.block_table, c.block_table);
    EXPECT_EQ(a.values, c.values);
}

TEST(Bricks, BadOptionsAreRefused) {
    const Mesh m = noisy_scene(0.0);
    const auto q = make_bvh_query(m);
    const WindingNumber wn(m);
    const SmoothOptions opt = bilateral(1, 1.5f);
    EXPECT_THROW(smooth_in_bricks(m, *q, &wn, scan_at(32), opt, BrickOptions{.brick_voxels = 4}), InvalidInput);
    EXPECT_THROW(smooth_in_bricks(m, *q, &wn, scan_at(32), opt, BrickOptions{.brick_voxels = 16, .halo_voxels = -1}),
                 InvalidInput);
}

}  // namespace
}  // namespace normalflow
