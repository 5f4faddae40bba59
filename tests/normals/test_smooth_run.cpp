// Tests of how smooth_volume (lib/normals/smooth.h) runs: independence of the triangulation and of
// the thread count, the band and the φ it returns, the stop when a refit keeps no step,
// cancellation, bad input and the modes' defaults. The filters' results: test_smooth.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.h"
#include "core/mesh.h"
#include "core/progress.h"
#include "core/volume.h"
#include "normals/smooth.h"
#include "sdf/scan_convert.h"
#include "sdf/triangle_bvh.h"
#include "smooth_fixtures.h"
#include "volume_fixtures.h"

namespace normalflow {
namespace {

using namespace test;  // volume_fixtures.h, smooth_fixtures.h

// ------------------------------------------------------------------------------------------------
// Independence of the triangulation and of the thread count

/// A box with corners lo, hi, rotated about (1, 1, 1)/√3 by an angle, each face an n×n grid of
/// quads split along alternating (alternate = true) or identical diagonals.
Mesh rotated_box(const Vec3d& lo, const Vec3d& hi, int n, bool alternate, double angle) {
    Mesh m;
    const Vec3d ax = normalized(Vec3d(1, 1, 1));
    const Vec3d ctr = (lo + hi) * 0.5;
    auto rot = [&](const Vec3d& p) {  // Rodrigues
        const Vec3d d = p - ctr;
        const double cs = std::cos(angle), sn = std::sin(angle);
        return ctr + d * cs + cross(ax, d) * sn + ax * (dot(ax, d) * (1 - cs));
    };
    for (int f = 0; f < 6; ++f) {
        const int a = f / 2;  // normal axis
        const bool pos = f % 2 == 1;
        const int u = (a + 1) % 3, w = (a + 2) % 3;
        const std::uint32_t base = std::uint32_t(m.positions.size());
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i) {
                Vec3d p;
                p[a] = pos ? hi[a] : lo[a];
                p[u] = lo[u] + (hi[u] - lo[u]) * i / n;
                p[w] = lo[w] + (hi[w] - lo[w]) * j / n;
                m.positions.push_back(Vec3f(rot(p)));
            }
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const std::uint32_t v00 = base + std::uint32_t(j * (n + 1) + i), v10 = v00 + 1,
                                    v01 = v00 + std::uint32_t(n + 1), v11 = v01 + 1;
                // (u, w, a) is right-handed: counter-clockwise in (u, w) faces +a
                auto tri = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
                    m.triangles.push_back(pos ? Tri{x, y, z} : Tri{x, z, y});
                };
                if (alternate && (i + j) % 2 == 1) {
                    tri(v00, v10, v01);
                    tri(v10, v11, v01);
                } else {
                    tri(v00, v10, v11);
                    tri(v00, v11, v01);
                }
            }
    }
    return m;
}

TEST(SmoothVolume, SameShapeTriangulatedTwoWaysGivesTheSameResult) {
    const Vec3d lo(0, 0, 0), hi(1.0, 0.8, 0.6);
    const Mesh a = rotated_box(lo, hi, 1, false, 0.4);
    const Mesh b = rotated_box(lo, hi, 5, true, 0.4);
    ScanConvertOptions so;
    so.resolution = 40;
    so.half_width = 3.0f;
    Volume va = scan_convert(a, *make_bvh_query(a), so);
    Volume vb = scan_convert(b, *make_bvh_query(b), so);
    ASSERT_EQ(va.grid.dims, vb.grid.dims);
    for (const SmoothMode mode : {SmoothMode::Isotropic, SmoothMode::Anisotropic}) {
        Volume ra = va, rb = vb;
        smooth_volume(ra, options(mode, 3));
        smooth_volume(rb, options(mode, 3));
        const double h = ra.grid.voxel_size;
        double worst = 0.0;
        std::size_t near = 0;
        for (int k = 0; k < ra.grid.dims[2]; ++k)
            for (int j = 0; j < ra.grid.dims[1]; ++j)
                for (int i = 0; i < ra.grid.dims[0]; ++i) {
                    const double pa = ra.value(i, j, k) / h, pb = rb.value(i, j, k) / h;
                    if (std::min(std::abs(pa), std::abs(pb)) > 2.0) continue;
                    ++near;
                    worst = std::max(worst, std::abs(pa - pb));
                }
        std::printf("%s: two triangulations differ by at most %.4g voxel near the surface\n", to_string(mode), worst);
        EXPECT_GT(near, 1000u);
        EXPECT_LT(worst, 0.25) << to_string(mode);
    }
}

TEST(SmoothVolume, BitIdenticalWithOneAndTwoThreads) {
    const float robust = SmoothOptions{}.mu_robust;  // anisotropic with the fixed and the robust scale
    for (const auto& [mode, mu_robust] :
         {std::pair{SmoothMode::Isotropic, 0.0f}, std::pair{SmoothMode::Anisotropic, 0.0f},
          std::pair{SmoothMode::Anisotropic, robust}, std::pair{SmoothMode::HighBoost, 0.0f},
          std::pair{SmoothMode::MeanCurvature, 0.0f}}) {
        Volume v = make_volume(40, 1.0, box_sdf(Vec3d(20.3, 19.6, 20.2), Vec3d(11, 9, 10)));
        add_noise(v, 0.3, 3u);
        if (mu_robust > 0.0f) add_smooth_noise(v, 3.0, 3.0, 3u);  // noise that raises the robust scale
        Volume v1 = v, v2 = v;
        SmoothOptions o = options(mode, 2);
        o.second_order_term = mode == SmoothMode::Isotropic;
        o.mu_robust = mu_robust;  // the robust scale's quartile does not depend on the threads either
        o.threads = 1;
        const SmoothReport r1 = smooth_volume(v1, o);
        o.threads = 2;
        const SmoothReport r2 = smooth_volume(v2, o);
        ASSERT_EQ(v1.block_coords, v2.block_coords) << to_string(mode);
        ASSERT_EQ(v1.block_table, v2.block_table) << to_string(mode);
        ASSERT_EQ(v1.values.size(), v2.values.size());
        EXPECT_EQ(0, std::memcmp(v1.values.data(), v2.values.data(), v1.values.size() * sizeof(float)))
            << to_string(mode);
        ASSERT_EQ(r1.iterations.size(), r2.iterations.size()) << to_string(mode);
        for (std::size_t i = 0; i < r1.iterations.size(); ++i) {
            const SmoothIteration &a = r1.iterations[i], &b = r2.iterations[i];
            EXPECT_EQ(a.normal_energy, b.normal_energy) << to_string(mode);
            EXPECT_EQ(a.refit_energy, b.refit_energy) << to_string(mode);
            EXPECT_EQ(a.refit_energy_end, b.refit_energy_end) << to_string(mode);
            EXPECT_EQ(a.refit_steps, b.refit_steps) << to_string(mode);
            EXPECT_EQ(a.band_voxels, b.band_voxels) << to_string(mode);
            EXPECT_EQ(a.mu, b.mu) << to_string(mode);
        }
        if (mu_robust > 0.0f) {
            EXPECT_GT(r1.iterations.front().mu, o.mu);
        }
    }
}

// ------------------------------------------------------------------------------------------------
// Band, cancellation, bad input

TEST(SmoothVolume, BandFollowsTheSurfaceAndKeepsTheInvariant) {
    // MCF shrinks the sphere by several voxels: the band must move with it and stay consistent.
    const Vec3d c(24, 24, 24);
    Volume v = make_volume(48, 1.0, sphere_sdf(c, 15.0));
    SmoothOptions o = options(SmoothMode::MeanCurvature, 4);
    o.normal_steps = 41;  // odd: the step buffers must agree outside the active blocks
    smooth_volume(v, o);
    EXPECT_FLOAT_EQ(v.half_width, 8.0f);
    // no sample far inside the shrunken sphere (r ≈ sqrt(225 − 4·16.4) ≈ 12.6) is positive
    for (int k = 0; k < 48; ++k)
        for (int j = 0; j < 48; ++j)
            for (int i = 0; i < 48; ++i)
                if (norm(Vec3d(i, j, k) - c) < 9.0) {
                    ASSERT_LT(v.value(i, j, k), 0.0f) << i << " " << j << " " << k;
                }
    for (std::size_t b = 0; b < v.block_count(); ++b) {
        const auto& bc = v.block_coords[b];
        EXPECT_EQ(v.block_table[v.table_index(bc[0], bc[1], bc[2])], std::int32_t(b));
    }
    // tiles carry the right sign: centre inside, corners outside
    EXPECT_LT(v.value(24, 24, 24), 0.0f);
    EXPECT_GT(v.value(1, 1, 1), 0.0f);
    // φ is a signed distance near the surface: |∇φ| ≈ 1 on the samples within 3 voxels
    double worst = 0;
    for (int k = 4; k < 44; ++k)
        for (int j = 4; j < 44; ++j)
            for (int i = 4; i < 44; ++i) {
                if (std::abs(v.value(i, j, k)) > 3.0f) continue;
                const double gx = 0.5 * (v.value(i + 1, j, k) - v.value(i - 1, j, k));
                const double gy = 0.5 * (v.value(i, j + 1, k) - v.value(i, j - 1, k));
                const double gz = 0.5 * (v.value(i, j, k + 1) - v.value(i, j, k - 1));
                worst = std::max(worst, std::abs(std::sqrt(gx * gx + gy * gy + gz * gz) - 1.0));
            }
    EXPECT_LT(worst, 0.15);
}

TEST(SmoothVolume, ReturnedPhiIsTheDistanceOutToTheHalfWidth) {
    // Between main iterations the engine keeps φ exact only as far as an iteration reads it
    // (active_band + 3 voxels); the φ it returns must be the distance out to the half width (8).
    const Vec3d c(24, 24, 24);
    const double r = 12.0;
    Volume v = make_volume(48, 1.0, sphere_sdf(c, r));
    smooth_volume(v, options(SmoothMode::Isotropic, 2));
    const RadialStats st = radial_stats(v, c);
    ASSERT_LT(st.max_deviation, 0.2);
    double worst = 0;
    std::size_t far = 0;
    for (int k = 0; k < 48; ++k)
        for (int j = 0; j < 48; ++j)
            for (int i = 0; i < 48; ++i) {
                const float p = v.value(i, j, k);
                if (std::abs(p) < 5.0f || std::abs(p) >= 8.0f) continue;
                const double d = norm(Vec3d(i, j, k) - c) - st.mean_radius;
                if (std::abs(d) >= 7.8) continue;  // the far edge of the band: φ is clamped at 8
                worst = std::max(worst, std::abs(double(p) - d));
                far += std::abs(d) > 7.0;
            }
    EXPECT_GT(far, 1000u);
    EXPECT_LT(worst, 0.5);  // the first-order Godunov distance of a sphere: 0.42 here
}

/// The Godunov upwind solution of |∇u| = 1 (h = 1) from the six neighbours' distances, as the
/// reinitialisation's update computes it: from the smaller neighbour per axis, the 1-, 2- or 3-D root.
double godunov(double ax, double ay, double az) {
    double a[3] = {ax, ay, az};
    std::sort(a, a + 3);
    double d = a[0] + 1.0;
    if (d > a[1]) d = 0.5 * (a[0] + a[1] + std::sqrt(std::max(2.0 - (a[0] - a[1]) * (a[0] - a[1]), 0.0)));
    if (d > a[2]) {
        const double s = a[0] + a[1] + a[2], q = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
        d = (s + std::sqrt(std::max(s * s - 3.0 * (q - 1.0), 0.0))) / 3.0;
    }
    return d;
}

/// The largest |φ − min(Godunov update of its neighbours, 8)| over the samples off the interface
/// inside the grid (voxel units, h = 1); checked: how many of them have |φ| < 7.5.
double eikonal_residual(const Volume& v, std::size_t* checked) {
    double worst = 0;
    *checked = 0;
    const auto& d = v.grid.dims;
    for (int k = 1; k < d[2] - 1; ++k)
        for (int j = 1; j < d[1] - 1; ++j)
            for (int i = 1; i < d[0] - 1; ++i) {
                const float p = v.value(i, j, k);
                const float nb[6] = {v.value(i - 1, j, k), v.value(i + 1, j, k), v.value(i, j - 1, k),
                                     v.value(i, j + 1, k), v.value(i, j, k - 1), v.value(i, j, k + 1)};
                bool interface = false;
                for (const float o : nb) interface |= (o < 0.0f) != (p < 0.0f);
                if (interface) continue;
                const double u =
                    godunov(std::min(std::abs(nb[0]), std::abs(nb[1])), std::min(std::abs(nb[2]), std::abs(nb[3])),
                            std::min(std::abs(nb[4]), std::abs(nb[5])));
                worst = std::max(worst, std::abs(double(std::abs(p)) - std::min(u, 8.0)));
                *checked += std::abs(p) < 7.5f;
            }
    return worst;
}

TEST(SmoothVolume, ReturnedPhiIsTheFixedPointOfTheEikonalUpdate) {
    // Every sample off the interface must hold what the Godunov update gives from its neighbours,
    // capped at the half width: a distance that a front failed to carry across a block boundary
    // (a block not recomputed after its neighbour changed) is left too large and shows here.
    // A box and a sphere apart, in a grid of 9 blocks per axis, after a main iteration moved them.
    const int n = 72;
    const test::Sdf box = box_sdf(Vec3d(24, 26, 30), Vec3d(13, 10, 16));
    const test::Sdf ball = sphere_sdf(Vec3d(52, 47, 41), 12.5);
    Volume v = make_volume(n, 1.0, [&](const Vec3d& p) { return std::min(box(p), ball(p)); });
    add_noise(v, 0.3, 7);
    smooth_volume(v, options(SmoothMode::Isotropic, 1));
    std::size_t checked = 0;
    const double worst = eikonal_residual(v, &checked);
    EXPECT_GT(checked, 50000u);
    EXPECT_LT(worst, 5e-3);  // the passes stop when no sample moves by more than 1e-3 (0.00095 here)
}

class StopAfter : public Progress {
public:
    explicit StopAfter(int n) : n_(n) {}
    void progress(double f) override {
        ++calls;
        EXPECT_GE(f, last);
        EXPECT_LE(f, 1.0);
        last = f;
    }
    bool should_stop() override {
        ++asks;
        return asks > n_;
    }
    int calls = 0, asks = 0;
    double last = 0;

private:
    int n_;
};

TEST(SmoothVolume, StopsWhenARefitKeepsNoStepAndTheResultIsThatOfMoreIterations) {
    // The paper's live conductance at µ = 0.1 on strong noise: g ≈ 0 wherever the noise bends the
    // normals, so the normal loop hardly moves them and the refit's first step raises D. That
    // iteration leaves φ as it found it, so the next would repeat it exactly: smooth_volume stops.
    Volume noisy = make_volume(40, 1.0, sphere_sdf(Vec3d(20.2, 19.8, 20.1), 12.0));
    add_noise(noisy, 1.0, 5u);
    SmoothOptions o = options(SmoothMode::Anisotropic, 3);
    o.conductance_presmooth_steps = 0;
    o.mu_robust = 0.0f;
    Volume a = noisy;
    const SmoothReport ra = smooth_volume(a, o);
    ASSERT_TRUE(ra.stopped_unchanged);
    ASSERT_LT(ra.iterations_run(), 3);
    EXPECT_EQ(ra.iterations.back().refit_steps, 0);
    // asking for more iterations changes nothing, bit for bit
    o.iterations = 7;
    Volume b = noisy;
    const SmoothReport rb = smooth_volume(b, o);
    EXPECT_EQ(rb.iterations_run(), ra.iterations_run());
    EXPECT_EQ(b.values, a.values);
    // and the returned φ is the finished band: the distance out to the half width (8), as after a
    // full run (a stop in the first iteration returns the φ of the set-up, reinitialised that far)
    EXPECT_EQ(a.half_width, 8.0f);
    std::size_t checked = 0;
    EXPECT_LT(eikonal_residual(a, &checked), 5e-3);
    EXPECT_GT(checked, 10000u);
    // a run whose refits move φ goes on to the end (the sphere tests of test_smooth.cpp: 5 of 5)
    Volume c = noisy;
    const SmoothReport rc = smooth_volume(c, options(SmoothMode::Isotropic, 3));
    EXPECT_FALSE(rc.stopped_unchanged);
    EXPECT_EQ(rc.iterations_run(), 3);
}

TEST(SmoothVolume, ACheckpointThatGoesOnChangesNothingAndOneThatStopsEndsTheRunThere) {
    Volume noisy = make_volume(40, 1.0, sphere_sdf(Vec3d(20.2, 19.8, 20.1), 12.0));
    add_noise(noisy, 0.3, 7u);
    const SmoothOptions o = options(SmoothMode::Bilateral, 3);
    Volume plain = noisy;
    const SmoothReport rp = smooth_volume(plain, o);
    ASSERT_EQ(rp.iterations_run(), 3);
    // asked after iterations 1 and 2 (not after the last), each time with the surface moved by the run so far
    int asked = 0;
    std::vector<Volume> seen;
    const SmoothCheckpoint go_on = [&](const Volume& v) {
        ++asked;
        seen.push_back(v);
        return true;
    };
    Volume a = noisy;
    const SmoothReport ra = smooth_volume(a, o, nullptr, nullptr, &go_on);
    EXPECT_EQ(asked, 2);
    EXPECT_EQ(ra.iterations_run(), 3);
    EXPECT_FALSE(ra.stopped_at_checkpoint);
    EXPECT_EQ(a.values, plain.values);  // bit for bit the run without it
    EXPECT_EQ(a.block_table, plain.block_table);
    ASSERT_EQ(seen.size(), 2u);
    EXPECT_NE(seen[0].values, seen[1].values);
    // one that stops after the first iteration: that iteration's surface, reinitialised out to the half width as any
    // run returns it. A one-iteration run reinitialises once where this one did twice (for the checkpoint, then out
    // to the half width), and each reinitialisation moves the interface samples a little: within a few hundredths of
    // a voxel
    const SmoothCheckpoint stop = [](const Volume&) { return false; };
    Volume b = noisy;
    const SmoothReport rb = smooth_volume(b, o, nullptr, nullptr, &stop);
    EXPECT_EQ(rb.iterations_run(), 1);
    EXPECT_TRUE(rb.stopped_at_checkpoint);
    EXPECT_EQ(b.half_width, 8.0f);
    std::size_t checked = 0;
    EXPECT_LT(eikonal_residual(b, &checked), 5e-3);
    EXPECT_GT(checked, 10000u);
    SmoothOptions one = o;
    one.iterations = 1;
    Volume c = noisy;
    smooth_volume(c, one);
    // the largest difference from c where c's surface is within 2 voxels
    const auto near_surface_diff = [&c](const Volume& other) {
        double d = 0.0;
        for (int k = 0; k < 40; ++k)
            for (int j = 0; j < 40; ++j)
                for (int i = 0; i < 40; ++i)
                    if (std::abs(c.value(i, j, k)) < 2.0)
                        d = std::max(d, double(std::abs(other.value(i, j, k) - c.value(i, j, k))));
        return d;
    };
    const double near_diff = near_surface_diff(b);
    EXPECT_LT(near_diff, 0.05);
    // and the one-iteration surface differs from the three-iteration one (the stop did stop)
    const double moved = near_surface_diff(plain);
    EXPECT_GT(moved, 0.1);
}

TEST(SmoothVolume, CancelStopsPromptlyAndThrowsCancelled) {
    Volume v = make_volume(48, 1.0, sphere_sdf(Vec3d(24, 24, 24), 14.0));
    StopAfter p(3);
    EXPECT_THROW(smooth_volume(v, options(SmoothMode::Anisotropic, 50), &p), Cancelled);
    EXPECT_EQ(p.asks, 4);  // no more work once it asked to stop
    StopAfter never(1 << 30);
    Volume w = make_volume(32, 1.0, sphere_sdf(Vec3d(16, 16, 16), 9.0));
    smooth_volume(w, options(SmoothMode::Isotropic, 2), &never);
    EXPECT_GT(never.calls, 50);
    EXPECT_DOUBLE_EQ(never.last, 1.0);
}

TEST(SmoothVolume, NaNInInputIsAClearError) {
    Volume v = make_volume(32, 1.0, sphere_sdf(Vec3d(16, 16, 16), 9.0));
    v.values[100] = std::numeric_limits<float>::quiet_NaN();
    try {
        smooth_volume(v);
        FAIL() << "no exception";
    } catch (const NumericalError& e) {
        EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos) << e.what();
    }
}

TEST(SmoothVolume, OptionsOutOfRangeThrowInvalidInput) {
    const Volume v0 = make_volume(32, 1.0, sphere_sdf(Vec3d(16, 16, 16), 9.0));
    auto expect_bad = [&](auto&& set, const char* field) {
        SmoothOptions o;
        set(o);
        Volume v = v0;
        try {
            smooth_volume(v, o);
            ADD_FAILURE() << field << ": no exception";
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
        }
        EXPECT_EQ(v.values, v0.values) << field << ": volume changed";
    };
    const float nan = std::numeric_limits<float>::quiet_NaN();
    expect_bad([](SmoothOptions& o) { o.iterations = -1; }, "iterations");
    expect_bad([](SmoothOptions& o) { o.normal_steps = -1; }, "normal_steps");
    expect_bad([](SmoothOptions& o) { o.mu = 0.0f; }, "mu");
    expect_bad([&](SmoothOptions& o) { o.mu = nan; }, "mu");
    expect_bad([](SmoothOptions& o) { o.alpha = -1.0f; }, "alpha");
    expect_bad([](SmoothOptions& o) { o.normal_dt = 0.0f; }, "normal_dt");
    expect_bad([](SmoothOptions& o) { o.refit_dt = -0.1f; }, "refit_dt");
    expect_bad([](SmoothOptions& o) { o.refit_max_steps = -1; }, "refit_max_steps");
    expect_bad([](SmoothOptions& o) { o.refit_tolerance = -1.0; }, "refit_tolerance");
    expect_bad([](SmoothOptions& o) { o.conductance_presmooth_steps = -1; }, "conductance_presmooth_steps");
    expect_bad([](SmoothOptions& o) { o.mu_robust = -1.0f; }, "mu_robust");
    expect_bad([](SmoothOptions& o) { o.active_band = 1.0f; }, "active_band");
    expect_bad([](SmoothOptions& o) { o.active_band = 6.0f; }, "active_band");
    expect_bad([](SmoothOptions& o) { o.threads = -1; }, "threads");
    // a volume whose arrays disagree
    Volume broken = v0;
    broken.values.pop_back();
    EXPECT_THROW(smooth_volume(broken), InvalidInput);
}

TEST(SmoothVolume, ZeroIterationsRunsTheModesDefault) {
    // iterations = 0 (the default) runs default_iterations(mode): anisotropic needs twice the
    // isotropic count (its robust µ takes several iterations to come down, docs/history/benchmarks-2026.md)
    EXPECT_EQ(default_iterations(SmoothMode::Anisotropic), 16);
    EXPECT_EQ(default_iterations(SmoothMode::Isotropic), 8);
    EXPECT_EQ(default_iterations(SmoothMode::MeanCurvature), 8);
    EXPECT_EQ(SmoothOptions{}.iterations, 0);
    for (const SmoothMode mode : {SmoothMode::Anisotropic, SmoothMode::Isotropic}) {
        Volume v = make_volume(20, 1.0, sphere_sdf(Vec3d(10.2, 9.9, 10.1), 5.0));
        SmoothOptions o = options(mode, 0);
        o.normal_steps = 1;
        o.refit_max_steps = 1;
        const SmoothReport rep = smooth_volume(v, o);
        EXPECT_EQ(rep.iterations_run(), default_iterations(mode)) << to_string(mode);
    }
}

TEST(SmoothVolume, LargeTimeStepsAreClampedWithAWarning) {
    Volume v = make_volume(32, 1.0, sphere_sdf(Vec3d(16, 16, 16), 9.0));
    const double r0 = equivalent_radius(v);
    SmoothOptions o = options(SmoothMode::Isotropic, 1);
    o.normal_dt = 1.0f;
    o.refit_dt = 1.0f;
    const SmoothReport rep = smooth_volume(v, o);
    EXPECT_EQ(rep.warnings.size(), 2u);
    EXPECT_LT(std::abs(equivalent_radius(v) - r0), 0.05);  // stable
}

TEST(SmoothVolume, VolumeWithoutSurfaceIsReturnedUnchanged) {
    Grid g;
    g.dims = {16, 16, 16};
    Volume v(g, 3.0f);
    v.allocate_block(0, 0, 0);
    const Volume before = v;
    const SmoothReport rep = smooth_volume(v);
    EXPECT_EQ(rep.iterations_run(), 0);
    EXPECT_FALSE(rep.warnings.empty());
    EXPECT_EQ(v.values, before.values);
}

}  // namespace
}  // namespace normalflow
