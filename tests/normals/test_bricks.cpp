// Tests for lib/normals/bricks.h: the scan conversion and the engine brick by brick against the whole run.
#include "normals/bricks.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

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

// The largest |φ_a − φ_b| (voxels) over the samples within `near` voxels of either surface, and the number of samples
// whose sign differs.
std::pair<double, std::size_t> surface_difference(const Volume& a, const Volume& b, double near = 1.0) {
    EXPECT_EQ(a.grid.dims, b.grid.dims);
    const double h = a.grid.voxel_size;
    double worst = 0;
    std::size_t signs = 0;
    for (int k = 0; k < a.grid.dims[2]; ++k)
        for (int j = 0; j < a.grid.dims[1]; ++j)
            for (int i = 0; i < a.grid.dims[0]; ++i) {
                const double x = a.value(i, j, k) / h, y = b.value(i, j, k) / h;
                signs += (x < 0) != (y < 0);
                if (std::min(std::abs(x), std::abs(y)) < near) worst = std::max(worst, std::abs(x - y));
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

// Bricks hold the whole run's surface to float rounding, not merely within the 0.05 voxel: the windows take
// their surface points in the whole grid's coordinates (SmoothOptions::sample_origin, tested in test_fast_engine),
// and the volume constraint over the whole surface takes the whole run's Newton steps
// (restore_volume's kVolumeNewtonSteps). With its first step alone this scene stood 0.0175 voxel off after two
// iterations; fandisk at 512 in bricks of 256 stood 0.071 voxel off before both.
TEST(Bricks, TheyHoldTheWholeRunsSurfaceToRounding) {
    const Mesh m = noisy_scene(0.05);
    const ScanConvertOptions scan = scan_at(96);
    const SmoothOptions opt = bilateral(2, 2.0f);
    const Result w = whole(m, scan, opt);
    BrickReport rep;
    const Result b = bricked(m, scan, opt, BrickOptions{.brick_voxels = 40}, &rep);
    EXPECT_EQ(rep.passes, 2);
    const auto [worst, signs] = surface_difference(w.v, b.v, 0.5);
    EXPECT_EQ(signs, 0u);
    std::printf("bricks of 40, two iterations: %.3g voxel from the whole run's surface\n", worst);
    EXPECT_LT(worst, 1e-4);
}

// Where the result's band in floats does not fit a run that stops after its first pass, it is held in 16 bits between
// passes (BrickOptions::compact_band, a step of 2.4·10⁻⁴ voxel): only the closing reinitialisation reads it, and the
// surface stays within 10⁻³ voxel of the bricks in floats, the same inside and outside everywhere, every value the
// middle of a 16-bit step; the report says so; what the checkpoint reads is what the run returns; the blocks expected
// (the arrays' reservation) change nothing. (A second pass from the 16-bit band moved this scene's surface 0.01 voxel,
// at 96 voxels 0.12: the filters' choices amplify the change, which is why the plan keeps it to one pass.)
TEST(Bricks, ACompactBandHoldsTheFirstPassWithinSixteenBits) {
    const Mesh m = noisy_scene(0.05);
    const ScanConvertOptions scan = scan_at(64);
    const SmoothOptions opt = bilateral(2, 2.0f);
    const auto q = make_bvh_query(m);
    const WindingNumber wn(m);
    std::vector<float> seen;
    const SmoothCheckpoint stop = [&](const Volume& v) {
        seen = v.values;
        return false;
    };
    const auto run = [&](const BrickOptions& b, BrickReport* rep = nullptr) {
        return smooth_in_bricks(m, *q, &wn, scan, opt, b, rep, nullptr, nullptr, &stop);
    };
    const Volume floats = run(BrickOptions{.brick_voxels = 32});
    BrickReport rep;
    const Volume compact = run(BrickOptions{.brick_voxels = 32, .compact_band = true}, &rep);
    EXPECT_EQ(seen, compact.values);
    EXPECT_TRUE(rep.compact_band);
    EXPECT_EQ(rep.passes, 1);
    EXPECT_EQ(compact.block_table, floats.block_table);
    const auto [worst, signs] = surface_difference(floats, compact, 0.5);
    std::printf("bricks of 32, one pass, the band in 16 bits: %.3g voxel from the bricks in floats\n", worst);
    EXPECT_EQ(signs, 0u);
    EXPECT_GT(worst, 0.0);  // it was held in 16 bits
    EXPECT_LT(worst, 1e-3);
    const float step = 2.0f * compact.background / 65536.0f;
    double off_level = 0.0;
    for (const float x : compact.values) {
        const double at = double(x / step) - 0.5;
        off_level = std::max(off_level, std::abs(at - std::round(at)));
    }
    EXPECT_LT(off_level, 0.01);
    // the arrays' reservation changes nothing, too small or too large
    for (const std::size_t expected : {std::size_t(1), std::size_t(100000)}) {
        const Volume r = run(BrickOptions{.brick_voxels = 32, .compact_band = true, .expected_band_blocks = expected});
        EXPECT_EQ(r.values, compact.values) << expected;
    }
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

// A brick of many minutes (2048 voxels a side in large bricks) still moves the progress line and stops when asked:
// the bricks run here tick from within their window's engine and stop from within its scan too, and a stop asked for
// at the first tick inside the first brick ends the run there (Cancelled); bricks on threads stop through a flag the
// calling thread sets (a runner of the caller's gets none). Before, the line moved and a stop was heard only between
// bricks, and SIGTERM left such a run going for a quarter of an hour. The result does not depend on the ticks.
TEST(Bricks, TheyTickAndStopFromWithinABrick) {
    const Mesh m = noisy_scene(0.03);
    const ScanConvertOptions scan = scan_at(32);
    const SmoothOptions opt = bilateral(1, 1.5f);
    const BrickOptions b{.brick_voxels = 16};
    struct Recorder final : Progress {
        std::vector<double> seen;
        bool stop_inside = false;
        bool stopped = false;
        void progress(double f) override { seen.push_back(f); }
        bool should_stop() override { return stopped = stop_inside && !seen.empty() && seen.back() > 0.0; }
    };
    const auto q = make_bvh_query(m);
    const WindingNumber wn(m);
    BrickReport rep;
    Recorder r;
    const Volume ticked = smooth_in_bricks(m, *q, &wn, scan, opt, b, &rep, nullptr, &r);
    const double brick = 1.0 / rep.total();  // one brick's share of the line (one iteration)
    ASSERT_GT(rep.total(), 4);
    EXPECT_TRUE(std::is_sorted(r.seen.begin(), r.seen.end()));
    const auto inside = std::count_if(r.seen.begin(), r.seen.end(), [&](double f) {
        const double at = f / brick;
        return f < 1.0 && std::abs(at - std::round(at)) > 1e-9;
    });
    EXPECT_GT(inside, rep.bricks_run);  // within the bricks, not only between them
    EXPECT_EQ(ticked.values, smooth_in_bricks(m, *q, &wn, scan, opt, b).values);

    Recorder stop;
    stop.stop_inside = true;
    EXPECT_THROW(smooth_in_bricks(m, *q, &wn, scan, opt, b, nullptr, nullptr, &stop), Cancelled);
    ASSERT_TRUE(stop.stopped);
    EXPECT_LT(stop.seen.back(), brick);  // still in the first brick

    // bricks on threads of their own: the stop reaches them from the calling thread before any comes back
    struct AtOnce final : Progress {
        int ticks = 0;
        void progress(double) override { ++ticks; }
        bool should_stop() override { return true; }
    } at_once;
    EXPECT_THROW(smooth_in_bricks(m, *q, &wn, scan, opt, BrickOptions{.brick_voxels = 16, .concurrent = 2}, nullptr,
                                  nullptr, &at_once),
                 Cancelled);
    EXPECT_EQ(at_once.ticks, 0);

    // a runner of the caller's may run bricks on threads of its own: its context carries no progress
    bool carried = false;
    const BrickRunner mine = [&](const BrickContext& c, int count, const std::function<BrickJob(int)>& make,
                                 const std::function<void(BrickOutcome &&)>& take) {
        carried |= c.progress != nullptr;
        for (int i = 0; i < count; ++i) take(run_brick(c, make(i)));
    };
    Recorder quiet;
    EXPECT_EQ(smooth_in_bricks(m, *q, &wn, scan, opt, b, nullptr, nullptr, &quiet, nullptr, &mine).values,
              ticked.values);
    EXPECT_FALSE(carried);
}

// A runner that carries every brick as messages (as Python's Dask bricks do), building all the jobs of a pass before
// running any, and running them last to first: the result is the one run here, bit for bit, and the context goes
// once per run; so is a run of three bricks at once on threads. A runner that hands an outcome back out of order, or
// forgets one, is caught.
TEST(Bricks, BricksCarriedAsMessagesGiveTheRunHereBitForBit) {
    const Mesh m = noisy_scene(0.03);
    const ScanConvertOptions scan = scan_at(32);
    const SmoothOptions opt = bilateral(2, 1.5f);
    const BrickOptions b{.brick_voxels = 16};
    const auto q = make_bvh_query(m);
    const WindingNumber wn(m);
    BrickReport here_report;
    const Volume here = smooth_in_bricks(m, *q, &wn, scan, opt, b, &here_report);
    EXPECT_FALSE(here_report.elsewhere);

    std::vector<std::string> contexts;
    const BrickRunner messages = [&](const BrickContext& c, int count, const std::function<BrickJob(int)>& make,
                                     const std::function<void(BrickOutcome &&)>& take) {
        const std::string context = brick_context_message(c);
        if (contexts.empty() || contexts.back() != context) contexts.push_back(context);
        std::vector<std::string> jobs;
        for (int i = 0; i < count; ++i) jobs.push_back(brick_message(make(i)));
        // a worker: the context's mesh and its search of its own
        BrickContext there;
        Mesh mesh;
        brick_context_from_message(context, there, mesh);
        const auto query = make_bvh_query(mesh);
        const WindingNumber winding(mesh);
        there.query = query.get();
        there.wn = &winding;
        std::vector<std::string> outcomes(jobs.size());
        for (int i = count - 1; i >= 0; --i)
            outcomes[i] = brick_message(run_brick(there, brick_job_from_message(jobs[i])));
        for (const std::string& o : outcomes) take(brick_outcome_from_message(o));
    };
    BrickReport rep;
    SmoothReport sr;
    const Volume there = smooth_in_bricks(m, *q, &wn, scan, opt, b, &rep, &sr, nullptr, nullptr, &messages);
    EXPECT_TRUE(rep.elsewhere);
    EXPECT_EQ(rep.passes, here_report.passes);
    EXPECT_EQ(rep.bricks_run, here_report.bricks_run);
    EXPECT_GT(rep.total(), 8);
    EXPECT_EQ(contexts.size(), 1u);
    EXPECT_EQ(there.block_table, here.block_table);
    EXPECT_EQ(there.block_coords, here.block_coords);
    EXPECT_EQ(there.values, here.values);

    // three bricks at once on threads of their own: the same again
    BrickOptions at_once = b;
    at_once.concurrent = 3;
    const Volume threads = smooth_in_bricks(m, *q, &wn, scan, opt, at_once);
    EXPECT_EQ(threads.block_coords, here.block_coords);
    EXPECT_EQ(threads.values, here.values);
    at_once.concurrent = 0;
    EXPECT_THROW(smooth_in_bricks(m, *q, &wn, scan, opt, at_once), InvalidInput);

    const BrickRunner reversed = [](const BrickContext& c, int count, const std::function<BrickJob(int)>& make,
                                    const std::function<void(BrickOutcome &&)>& take) {
        for (int i = count - 1; i >= 0; --i) take(run_brick(c, make(i)));
    };
    EXPECT_THROW(smooth_in_bricks(m, *q, &wn, scan, opt, b, nullptr, nullptr, nullptr, nullptr, &reversed),
                 std::logic_error);
    const BrickRunner forgetful = [](const BrickContext& c, int count, const std::function<BrickJob(int)>& make,
                                     const std::function<void(BrickOutcome &&)>& take) {
        for (int i = 0; i + 1 < count; ++i) take(run_brick(c, make(i)));
    };
    EXPECT_THROW(smooth_in_bricks(m, *q, &wn, scan, opt, b, nullptr, nullptr, nullptr, nullptr, &forgetful),
                 std::logic_error);
}

// A message cut short, of another kind, or with a byte too many is refused with a line that says so; a message names
// the build it comes from.
TEST(Bricks, BadMessagesAreRefused) {
    const Mesh m = noisy_scene(0.0);
    BrickContext c;
    c.mesh = &m;
    c.grid = scan_grid(m, scan_at(32));
    c.engine = bilateral(1, 1.5f);
    const std::string context = brick_context_message(c);
    BrickContext back;
    Mesh mesh;
    brick_context_from_message(context, back, mesh);
    EXPECT_EQ(mesh.positions.size(), m.positions.size());
    EXPECT_EQ(mesh.triangles, m.triangles);
    EXPECT_EQ(back.grid.dims, c.grid.dims);
    EXPECT_EQ(back.engine.length_scale, 1.5f);
    EXPECT_THROW(brick_context_from_message(context.substr(0, context.size() - 1), back, mesh), InvalidInput);
    EXPECT_THROW(brick_context_from_message(context + "x", back, mesh), InvalidInput);

    BrickJob job;
    job.index = 3;
    job.lo = {2, 2, 2};
    job.hi = {4, 4, 4};
    job.window = BlockWindow{{0, 0, 0}, {6, 6, 6}};
    job.input = Volume(window_grid(c.grid, job.window), 8.0f);
    job.input.set(1, 2, 3, 0.25f);
    job.refit = BrickRefit{.whole_time = true, .replay_count = 2, .replay = {3, -2}, .explicit_replay = 7};
    const std::string message = brick_message(job);
    const BrickJob read = brick_job_from_message(message);
    EXPECT_EQ(read.index, 3);
    EXPECT_TRUE(read.refit.whole_time);
    EXPECT_EQ(read.refit.replay_count, 2);
    EXPECT_EQ(read.refit.replay, job.refit.replay);
    EXPECT_EQ(read.refit.explicit_probe, 0);
    EXPECT_EQ(read.refit.explicit_replay, 7);
    BrickJob replays = job;
    replays.refit.replay_count = kRefitSuperStepAttempts + 1;
    EXPECT_THROW(brick_job_from_message(brick_message(replays)), InvalidInput);
    replays = job;
    replays.refit.explicit_probe = -1;
    EXPECT_THROW(brick_job_from_message(brick_message(replays)), InvalidInput);
    EXPECT_EQ(read.input.values, job.input.values);
    EXPECT_EQ(read.input.block_table, job.input.block_table);
    try {
        brick_job_from_message(message.substr(0, message.size() / 2));
        ADD_FAILURE() << "a truncated job was read";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    }
    EXPECT_THROW(brick_outcome_from_message(message), InvalidInput);  // a job is not an outcome
    std::string other = message;
    other[4 + 8] ^= 1;  // the version string's first character (after the kind and its length): another build
    try {
        brick_job_from_message(other);
        ADD_FAILURE() << "a job of another build was read";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("same build"), std::string::npos) << e.what();
    }
}

// The whole run's refit checks, on D given: a refit that keeps its 6 super steps reads as such from its own record,
// and each check the refit makes (a step that doubles D, a patient stop, a last step that raises D, a value not
// finite, a record of another length) reads as one.
TEST(Bricks, TheRefitsChecksReadFromD) {
    const Mesh m = noisy_scene(0.03);
    SmoothOptions opt = bilateral(1, 1.5f);
    const auto q = make_bvh_query(m);
    Volume v = scan_convert(m, *q, scan_at(40));
    const SmoothReport r = smooth_volume(v, opt);
    ASSERT_EQ(r.iterations.size(), 1u);
    const SmoothIteration& it = r.iterations.front();
    ASSERT_EQ(it.refit_steps, kDefaultRefitSuperSteps) << "the scene's refit restarted";
    EXPECT_TRUE(super_steps_keep_every_step(it.refit_energy, opt));
    EXPECT_TRUE(it.refit_window_energy.empty());  // a window's D only under defer_volume_shift

    opt.refit_max_steps = 60;
    const std::vector<double> falling{8, 6, 5, 4.5, 4.2, 4.1, 4.0};
    EXPECT_TRUE(super_steps_keep_every_step(falling, opt));
    std::vector<double> d = falling;
    d[3] = 13;  // the third super step more than doubled D
    EXPECT_FALSE(super_steps_keep_every_step(d, opt));
    d = falling;
    d.back() = 4.2;  // the last super step raised D
    EXPECT_FALSE(super_steps_keep_every_step(d, opt));
    d = {8, 6, 6, 6, 6, 6, 6};  // no new low for longer than the patience
    EXPECT_FALSE(super_steps_keep_every_step(d, opt));
    // what the refit decides instead, and the time it keeps: super steps of 6/63, 12/63, ... of the 6 voxel² (60 steps
    // of 0.1)
    using Then = SuperStepDecision::Then;
    const double total = refit_time(opt), tau0 = total / 63;
    EXPECT_NEAR(total, 6.0, 1e-6);
    SuperStepDecision dec = decide_super_steps(falling, opt, total);
    EXPECT_EQ(dec.then, Then::KeepAll);
    EXPECT_EQ(dec.kept, 6);
    EXPECT_NEAR(dec.time_kept, total, 1e-12);
    d = falling;
    d[3] = 13;  // the third super step doubled D: it is undone and the rest starts again
    dec = decide_super_steps(d, opt, total);
    EXPECT_EQ(dec.then, Then::Restart);
    EXPECT_EQ(dec.kept, 2);
    EXPECT_NEAR(dec.time_kept, 3 * tau0, 1e-12);
    d = falling;
    d.back() = 4.2;  // the last one raised D: undone, and the refit ends
    dec = decide_super_steps(d, opt, total);
    EXPECT_EQ(dec.then, Then::Stop);
    EXPECT_EQ(dec.kept, 5);
    d = {8, 6, 6, 6, 6, 6, 6};  // no new low for 0.19 + 0.38 voxel² (the patience: 5 steps, 0.5): the third undone
    dec = decide_super_steps(d, opt, total);
    EXPECT_EQ(dec.then, Then::Stop);
    EXPECT_EQ(dec.kept, 2);
    d = {8, 9, 9, 9, 9, 9, 9};  // the first super step raised D and the patience undoes it: explicit steps next
    dec = decide_super_steps(d, opt, 8 * total);  // its first super step lasts 0.76 voxel²
    EXPECT_EQ(dec.then, Then::Restart);
    EXPECT_EQ(dec.kept, 0);
    EXPECT_EQ(dec.time_kept, 0.0);
    d = falling;
    d[2] = std::nan("");
    EXPECT_FALSE(super_steps_keep_every_step(d, opt));
    EXPECT_EQ(decide_super_steps(d, opt, total).then, Then::Unknown);
    d = falling;
    d.pop_back();
    EXPECT_FALSE(super_steps_keep_every_step(d, opt));
    // fewer values (windows whose super steps stopped where φ was no longer finite): the decision where it falls
    // within them
    dec = decide_super_steps({8, 6, 20}, opt, total);
    EXPECT_EQ(dec.then, Then::Restart);
    EXPECT_EQ(dec.kept, 1);
    EXPECT_EQ(decide_super_steps({8, 6, 5}, opt, total).then, Then::Unknown);
}

// The explicit steps after the super steps' restarts, on D given: D(φ_s) of each iterate of a probe that kept every
// step, then of the last. The patient stop (5 steps without a new low, for 60 refit steps) and the runaway (D at
// twice its low) each keep the steps before the one that stopped; a probe with no stop decides only if it ran every
// step the time left.
TEST(Bricks, TheExplicitStepsStopReadsFromD) {
    SmoothOptions opt = bilateral(1, 1.5f);
    opt.refit_max_steps = 60;
    EXPECT_EQ(refit_explicit_patience(opt), 5);
    using Then = ExplicitStepDecision::Then;
    // the last new low at s = 4; s = 9 is the fifth step without one: 8 steps kept
    ExplicitStepDecision e = decide_explicit_steps({10, 9, 8, 7.5, 7.4, 7.4, 7.45, 7.4, 7.42, 7.4, 7.3, 7.2}, opt, 58);
    EXPECT_EQ(e.then, Then::Keep);
    EXPECT_EQ(e.steps, 8);
    e = decide_explicit_steps({10, 9, 8, 17, 3}, opt, 58);  // D(φ_3) more than doubled the low: φ_2 kept
    EXPECT_EQ(e.then, Then::Keep);
    EXPECT_EQ(e.steps, 2);
    e = decide_explicit_steps({10, 9, 8, 7, 6}, opt, 58);  // no stop within the probe's 4 steps: a longer one
    EXPECT_EQ(e.then, Then::Longer);
    e = decide_explicit_steps({10, 9, 8, 7, 6}, opt, 4);  // the 4 steps the time left, all kept
    EXPECT_EQ(e.then, Then::Keep);
    EXPECT_EQ(e.steps, 4);
    e = decide_explicit_steps({10, 9, 8, 7, 17}, opt, 4);  // the end's D is not checked (the last step is kept)
    EXPECT_EQ(e.steps, 4);
    e = decide_explicit_steps({10, 9, 8, 7, 17}, opt, 5);  // unless a step follows: D(φ_4) stops it at φ_3
    EXPECT_EQ(e.steps, 3);
    EXPECT_EQ(decide_explicit_steps({10, std::nan(""), 8}, opt, 58).then, Then::Unknown);
    EXPECT_EQ(decide_explicit_steps({}, opt, 58).then, Then::Unknown);
    opt.refit_max_steps = 2000;
    EXPECT_EQ(refit_explicit_patience(opt), 100);
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
