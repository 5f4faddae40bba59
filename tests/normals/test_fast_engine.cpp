// Tests of the engine's speed-ups of the neighbourhood filters (issue 21), each against the slower
// way it replaces, on the same noisy volumes: the refit in Runge–Kutta–Legendre super steps
// against the explicit steps, the filtered normals carried off the surface by nearest sample
// against a filter pass at every closest point, and the thinned surface samples of a fine grid
// against all of them. Each must give the same surface (within a small fraction of a voxel) for
// far less work, counted, not timed (SmoothIteration::refit_evaluations, filter_points).

#include <gtest/gtest.h>

#include <algorithm>
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
using test::box_normal_error;
using test::box_sdf;
using test::BoxNormalError;
using test::make_volume;
using test::sphere_sdf;

/// Mean and largest |φ_a − φ_b| (voxels) over the grid samples within one voxel of a's surface.
struct PhiDifference {
    double mean = 0, max = 0;
};
PhiDifference phi_difference(const Volume& a, const Volume& b) {
    PhiDifference d;
    std::size_t n = 0;
    const double h = a.grid.voxel_size;
    for (int k = 0; k < a.grid.dims[2]; ++k)
        for (int j = 0; j < a.grid.dims[1]; ++j)
            for (int i = 0; i < a.grid.dims[0]; ++i) {
                const double va = a.value(i, j, k) / h;
                if (std::abs(va) >= 1.0) continue;
                const double e = std::abs(va - b.value(i, j, k) / h);
                d.mean += e;
                d.max = std::max(d.max, e);
                ++n;
            }
    if (n > 0) d.mean /= double(n);
    return d;
}

SmoothOptions bilateral(float length_scale) {
    SmoothOptions o;
    o.mode = SmoothMode::Bilateral;
    o.length_scale = length_scale;
    return o;
}

/// The noisy box of the filter tests: 0.3 voxel of noise per sample on a 40³ grid.
Volume noisy_box(double h = 1.0, std::uint32_t seed = 5u) {
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    Volume v = make_volume(int(std::lround(40 / h)), h, box_sdf(c, e));
    add_noise(v, 0.3, seed);
    return v;
}

TEST(FastEngine, SuperStepsFollowTheExplicitRefitForAFractionOfItsWork) {
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    const Volume v0 = noisy_box();
    Volume expl = v0, rkl = v0;
    SmoothOptions o = bilateral(5.0f);  // ℓ = 5 voxels, as at the automatic resolution: 350 steps
    o.refit_super_steps = 0;
    const SmoothReport re = smooth_volume(expl, o);
    o.refit_super_steps = kDefaultRefitSuperSteps;
    const SmoothReport rr = smooth_volume(rkl, o);
    ASSERT_EQ(re.iterations_run(), rr.iterations_run());
    int ne = 0, nr = 0;
    for (const SmoothIteration& it : re.iterations) ne += it.refit_evaluations;
    for (const SmoothIteration& it : rr.iterations) {
        nr += it.refit_evaluations;
        EXPECT_LE(it.refit_steps, kDefaultRefitSuperSteps);
    }
    const PhiDifference d = phi_difference(expl, rkl);
    const BoxNormalError ee = box_normal_error(extract_surface(expl), c, e, 2.5);
    const BoxNormalError er = box_normal_error(extract_surface(rkl), c, e, 2.5);
    const BoxNormalError e0 = box_normal_error(extract_surface(v0), c, e, 2.5);
    std::printf(
        "refit: explicit %d evaluations, super steps %d; |Δφ| mean %.4f max %.4f voxel; normal error "
        "(deg) near edges / on faces: noisy %.2f / %.2f, explicit %.2f / %.2f, super steps %.2f / %.2f\n",
        ne, nr, d.mean, d.max, e0.near_edges, e0.on_faces, ee.near_edges, ee.on_faces, er.near_edges, er.on_faces);
    EXPECT_LT(nr * 3, ne);    // a third of the work at most
    EXPECT_LT(d.mean, 0.02);  // the same surface (up to a few samples at the edges)...
    EXPECT_LT(d.max, 0.5);
    EXPECT_LT(std::abs(er.on_faces - ee.on_faces), 0.25);  // ...and the same quality
    EXPECT_LT(std::abs(er.near_edges - ee.near_edges), 0.5);
    EXPECT_LT(er.on_faces, 0.5 * e0.on_faces);
}

TEST(FastEngine, SuperStepsKeepASphere) {
    // A clean sphere through two main iterations: the super steps keep its radius and its shape
    // as the explicit steps do (a wrong coefficient would blow it up or shrink it).
    const Vec3d c(24.3, 23.8, 24.1);
    const Volume v0 = make_volume(48, 1.0, sphere_sdf(c, 14.0));
    const double r0 = test::equivalent_radius(v0);
    double r[2], dev[2];
    for (int k = 0; k < 2; ++k) {
        Volume v = v0;
        SmoothOptions o = bilateral(4.0f);
        o.iterations = 2;
        o.refit_super_steps = k == 0 ? 0 : kDefaultRefitSuperSteps;
        smooth_volume(v, o);
        r[k] = test::equivalent_radius(v);
        dev[k] = test::radial_stats(v, c).max_deviation;
    }
    std::printf("sphere r %.4f: explicit refit r %.4f, max radial deviation %.4f; super steps r %.4f, %.4f\n", r0, r[0],
                dev[0], r[1], dev[1]);
    EXPECT_LT(std::abs(r[1] - r0), 0.05);
    EXPECT_LT(std::abs(r[1] - r[0]), 0.01);
    EXPECT_LT(dev[1], dev[0] + 0.05);
    EXPECT_LT(dev[1], 0.3);
}

TEST(FastEngine, NearestSampleExtensionMatchesTheGather) {
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    const Volume v0 = noisy_box(1.0, 9u);
    Volume gather = v0, nearest = v0;
    SmoothOptions o = bilateral(4.0f);
    o.extend_by_gather = true;
    smooth_volume(gather, o);
    o.extend_by_gather = false;
    smooth_volume(nearest, o);
    const PhiDifference d = phi_difference(gather, nearest);
    const BoxNormalError eg = box_normal_error(extract_surface(gather), c, e, 2.5);
    const BoxNormalError en = box_normal_error(extract_surface(nearest), c, e, 2.5);
    std::printf(
        "extension: |Δφ| mean %.4f max %.4f voxel; normal error near edges / on faces: gather %.2f / %.2f, "
        "nearest %.2f / %.2f\n",
        d.mean, d.max, eg.near_edges, eg.on_faces, en.near_edges, en.on_faces);
    EXPECT_LT(d.mean, 0.03);
    EXPECT_LT(std::abs(en.on_faces - eg.on_faces), 0.25);
    EXPECT_LT(std::abs(en.near_edges - eg.near_edges), 0.5);
}

TEST(FastEngine, ThinnedSamplesOfAFineGridGiveTheSameSurface) {
    // The noisy box at h = 1/2 with a length scale of 5 world units (10 voxels): every second shell
    // sample along each axis is filtered, about a quarter of them, and the surface is the one all
    // of them give.
    const Vec3d c(20.3, 19.6, 20.2), e(11, 9, 10);
    const Volume v0 = noisy_box(0.5, 13u);
    Volume all = v0, thin = v0;
    SmoothOptions o = bilateral(10.0f);
    o.iterations = 1;
    o.thin_samples = false;
    const SmoothReport ra = smooth_volume(all, o);
    o.thin_samples = true;
    const SmoothReport rt = smooth_volume(thin, o);
    const std::size_t na = ra.iterations[0].filter_points, nt = rt.iterations[0].filter_points;
    const PhiDifference d = phi_difference(all, thin);
    const BoxNormalError ea = box_normal_error(extract_surface(all), c, e, 2.5);
    const BoxNormalError et = box_normal_error(extract_surface(thin), c, e, 2.5);
    std::printf(
        "thinned samples: %zu of %zu; |Δφ| mean %.4f max %.4f voxel; normal error near edges / on faces: "
        "all %.2f / %.2f, thinned %.2f / %.2f\n",
        nt, na, d.mean, d.max, ea.near_edges, ea.on_faces, et.near_edges, et.on_faces);
    EXPECT_GT(nt * 6, na);  // about a quarter (the shell is twice as thick, a quarter of its columns)
    EXPECT_LT(nt * 3, na);
    EXPECT_LT(d.mean, 0.06);  // voxels of h/2
    EXPECT_LT(std::abs(et.on_faces - ea.on_faces), 0.25);
    EXPECT_LT(std::abs(et.near_edges - ea.near_edges), 0.5);
}

// A volume that is a window of a larger grid (smooth_in_bricks) runs as that grid would when SmoothOptions::sample_origin
// says where it lies: the noisy box, and the same box 1,024 voxels further along x in a longer grid, give the same φ
// bit for bit. In the window's own coordinates its surface points round differently from the larger grid's (here
// about 16 voxels from sample 0 against 1,040), and φ would differ (fandisk at 512 in bricks of 256: up to 0.09
// voxel on its surface).
TEST(FastEngine, AWindowTakesItsPointsInItsGridsCoordinates) {
    constexpr int kOffsetBlocks = 128;
    const Volume v0 = noisy_box(1.0, 7u);
    Grid far_grid = v0.grid;
    far_grid.dims[0] += kOffsetBlocks * kBlockDim;
    far_grid.origin.x -= kOffsetBlocks * kBlockDim * v0.grid.voxel_size;
    Volume far(far_grid, v0.half_width);
    for (int k = 0; k < v0.block_dims[2]; ++k)
        for (int j = 0; j < v0.block_dims[1]; ++j)
            for (int i = 0; i < v0.block_dims[0]; ++i) {
                const std::int32_t s = v0.block_table[v0.table_index(i, j, k)];
                if (s < 0) {
                    far.block_table[far.table_index(i + kOffsetBlocks, j, k)] = s;
                    continue;
                }
                std::copy_n(v0.block_values(s), kBlockVoxels,
                            far.block_values(far.allocate_block(i + kOffsetBlocks, j, k)));
            }
    SmoothOptions o = bilateral(4.0f);
    o.iterations = 1;
    smooth_volume(far, o);
    const auto differing = [&](const Volume& v) {
        std::size_t n = 0;
        for (int k = 0; k < v.grid.dims[2]; ++k)
            for (int j = 0; j < v.grid.dims[1]; ++j)
                for (int i = 0; i < v.grid.dims[0]; ++i)
                    n += v.value(i, j, k) != far.value(i + kOffsetBlocks * kBlockDim, j, k);
        return n;
    };
    Volume own = v0, window = v0;
    smooth_volume(own, o);
    o.sample_origin = {kOffsetBlocks * kBlockDim, 0, 0};
    smooth_volume(window, o);
    const std::size_t own_differs = differing(own);
    std::printf(
        "a window in its own coordinates: %zu samples differ from the larger grid's; in the larger grid's: %zu\n",
        own_differs, differing(window));
    EXPECT_EQ(differing(window), 0u);
    EXPECT_GT(own_differs, 0u);  // the test sees the rounding it is about
}

TEST(FastEngine, SpeedUpsDoNotDependOnTheThreads) {
    // The default path (super steps, nearest extension) and the thinned samples, bit for bit.
    for (const float ell : {4.0f, 10.0f}) {
        const Volume v = noisy_box(ell > 5.0f ? 0.5 : 1.0, 3u);
        Volume v1 = v, v2 = v;
        SmoothOptions o = bilateral(ell);
        o.iterations = 1;
        o.threads = 1;
        smooth_volume(v1, o);
        o.threads = 2;
        smooth_volume(v2, o);
        ASSERT_EQ(v1.values.size(), v2.values.size());
        EXPECT_EQ(0, std::memcmp(v1.values.data(), v2.values.data(), v1.values.size() * sizeof(float))) << ell;
    }
}

TEST(FastEngine, SuperStepsThatRunAwayFallBackToExplicitSteps) {
    // Few, long super steps on heavy noise (0.6 voxel) and long refit times: a single super step
    // of the whole time goes non-finite (which used to end the run with an error), two of them
    // raise D in the first (which used to leave φ as it was). The refit then takes explicit steps
    // from the last super step that held: it always does something, D ends below its start, and
    // the default (6 growing super steps) needs no fallback.
    for (const float ell : {8.0f, 12.0f})
        for (const int n : {1, 2, kDefaultRefitSuperSteps}) {
            Volume v = make_volume(40, 1.0, box_sdf(Vec3d(20.3, 19.6, 20.2), Vec3d(11, 9, 10)));
            add_noise(v, 0.6, 21u);
            SmoothOptions o = bilateral(ell);
            o.refit_super_steps = n;
            o.iterations = 1;
            SmoothReport r;
            ASSERT_NO_THROW(r = smooth_volume(v, o)) << n << " super steps, ell " << ell;
            const SmoothIteration& it = r.iterations[0];
            std::printf("ell %.0f, %d super steps: D %.1f -> %.1f, %d kept, %d evaluations\n", ell, n,
                        it.refit_energy_start(), it.refit_energy_end, it.refit_steps, it.refit_evaluations);
            EXPECT_GT(it.refit_steps, 0) << n << " super steps, ell " << ell;
            EXPECT_LT(it.refit_energy_end, 0.7 * it.refit_energy_start()) << n << " super steps, ell " << ell;
            if (n == kDefaultRefitSuperSteps) {
                EXPECT_LE(it.refit_steps, n);  // no explicit fallback
            }
        }
}

// The refit's decisions can be made from D alone and replayed (what smooth_in_bricks does with the bricks' D summed):
// a refit that keeps every super step whatever D does records D where the refit checks it, decide_super_steps reads
// the decision from it, and a run that replays it (and keeps every super step of the attempt after) gives φ bit for
// bit the run that decided by itself. Long refit times on heavy noise make the refit undo super steps; lengths where
// the whole run goes on in explicit steps are left out (those are not replayed).
TEST(FastEngine, TheRefitsDecisionsReadFromDAndReplayedAreItsOwn) {
    using Then = SuperStepDecision::Then;
    int replayed = 0, restarts = 0, stops = 0;
    struct Case {
        int super_steps;
        float ell;
        double noise;
    };
    // the first two undo a super step and go on in super steps, the third goes on in explicit steps, the default keeps
    // every super step
    for (const Case k :
         {Case{2, 4.0f, 0.6}, Case{2, 3.0f, 0.8}, Case{2, 8.0f, 0.6}, Case{kDefaultRefitSuperSteps, 8.0f, 0.6}}) {
        const int steps = k.super_steps;
        const float ell = k.ell;
        const double noise = k.noise;
        const std::uint32_t seed = 21u;
        Volume v = make_volume(40, 1.0, box_sdf(Vec3d(20.3, 19.6, 20.2), Vec3d(11, 9, 10)));
        add_noise(v, noise, seed);
        SmoothOptions o = bilateral(ell);
        o.iterations = 1;
        o.refit_super_steps = steps;
        Volume own = v;
        const SmoothReport r = smooth_volume(own, o);
        SmoothOptions f = o;
        f.refit_whole_time = true;
        double left = refit_time(f);
        const std::size_t n = std::size_t(f.refit_super_steps) + 1;
        bool done = false;
        for (int attempt = 0; attempt < kRefitSuperStepAttempts && !done; ++attempt) {
            Volume x = v;
            const SmoothReport rx = smooth_volume(x, f);
            const std::vector<double>& all = rx.iterations[0].refit_energy;
            ASSERT_GE(all.size(), n);
            const std::vector<double> d(all.end() - std::ptrdiff_t(n), all.end());
            const SuperStepDecision dec = decide_super_steps(d, f, left);
            std::printf("%d steps ell %.0f noise %.2f attempt %d: then %d kept %d (own run: %d steps kept)\n", steps,
                        ell, noise, attempt, int(dec.then), dec.kept, r.iterations[0].refit_steps);
            ASSERT_NE(dec.then, Then::Unknown);
            if (dec.then == Then::KeepAll) {
                EXPECT_EQ(x.values, own.values) << "ell " << ell << " seed " << seed;
                EXPECT_EQ(x.block_table, own.block_table);
                replayed += attempt > 0;
                done = true;
                break;
            }
            if (dec.then == Then::Restart && (dec.time_kept == 0.0 || attempt + 1 == kRefitSuperStepAttempts)) {
                EXPECT_GT(r.iterations[0].refit_steps, f.refit_super_steps);  // it went on in explicit steps
                done = true;
                break;
            }
            (dec.then == Then::Stop ? stops : restarts) += 1;
            f.refit_replay[std::size_t(f.refit_replay_count++)] = dec.then == Then::Stop ? -dec.kept - 1 : dec.kept;
            left -= dec.time_kept;
            if (dec.then == Then::Stop || !(left > 0.5 * refit_step_dt(f))) {
                Volume y = v;
                smooth_volume(y, f);
                EXPECT_EQ(y.values, own.values) << "ell " << ell << " seed " << seed;
                ++replayed;
                done = true;
            }
        }
    }
    std::printf("%d runs replayed (%d restarts, %d stops)\n", replayed, restarts, stops);
    EXPECT_EQ(restarts, 2);
    EXPECT_EQ(replayed, 2);
    Volume v = make_volume(24, 1.0, sphere_sdf(Vec3d(12, 12, 12), 6.0));
    SmoothOptions o = bilateral(4.0f);
    o.refit_replay_count = kRefitSuperStepAttempts + 1;
    EXPECT_THROW(smooth_volume(v, o), InvalidInput);
}

// A held border (a brick's window) gives way over its zone: the surface beside the layer that does not move moves less
// (the refit still carries the zone's pull inwards, as far as it reaches); the held layer itself stays as it was.
TEST(FastEngine, AHeldBorderGivesWayOverItsZone) {
    Volume v = make_volume(40, 1.0, box_sdf(Vec3d(20.3, 19.6, 20.2), Vec3d(11, 9, 10)));
    add_noise(v, 0.6, 21u);
    SmoothOptions o = bilateral(4.0f);
    o.iterations = 1;
    o.final_reinitialise = false;
    o.reinitialise_input = false;  // φ as the refit leaves it, from the scan's
    o.preserve_volume = false;
    o.fixed_lo = {12, 0, 0};  // x < 12 held: the box's sides run on past it
    Volume held = v, zoned = v;
    smooth_volume(held, o);
    o.fixed_zone = 8;
    smooth_volume(zoned, o);
    // the mean move of the samples within a voxel of the surface, by their distance from the held layer
    const auto moved = [&](const Volume& after, int x0, int x1) {
        double sum = 0;
        int n = 0;
        for (int k = 0; k < 40; ++k)
            for (int j = 0; j < 40; ++j)
                for (int i = x0; i < x1; ++i)
                    if (std::abs(v.value(i, j, k)) < 1.0) {
                        sum += std::abs(after.value(i, j, k) - v.value(i, j, k));
                        ++n;
                    }
        return sum / std::max(n, 1);
    };
    EXPECT_EQ(moved(held, 0, 12), 0.0);
    EXPECT_EQ(moved(zoned, 0, 12), 0.0);
    const double next_held = moved(held, 12, 13), next_zoned = moved(zoned, 12, 13);
    std::printf("beside the held layer: %.3f voxel held, %.3f with the zone; further on %.3f and %.3f\n", next_held,
                next_zoned, moved(held, 24, 28), moved(zoned, 24, 28));
    EXPECT_GT(next_held, 0.1);
    EXPECT_LT(next_zoned, 0.7 * next_held);
    o.fixed_zone = -1;
    EXPECT_THROW(smooth_volume(zoned, o), InvalidInput);
}

TEST(FastEngine, NegativeSuperStepsAreRefused) {
    Volume v = make_volume(24, 1.0, sphere_sdf(Vec3d(12, 12, 12), 6.0));
    SmoothOptions o = bilateral(4.0f);
    o.refit_super_steps = -1;
    EXPECT_THROW(smooth_volume(v, o), InvalidInput);
}

}  // namespace
}  // namespace normalflow
