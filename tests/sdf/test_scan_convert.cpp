// Tests for lib/sdf/scan_convert.h: accuracy against closed forms, signs of dirty meshes, open
// sheets, determinism, sparsity, bad input.
#include "sdf/scan_convert.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include "core/errors.h"
#include "sdf/winding_number.h"
#include "sdf_test_meshes.h"

namespace normalflow {
namespace {

ScanConvertOptions at(int resolution, float half_width = 3.0f, int threads = 0) {
    ScanConvertOptions o;
    o.resolution = resolution;
    o.half_width = half_width;
    o.threads = threads;
    return o;
}

// Largest |phi − exact| over every band sample (|phi| < background), and the number of band samples.
template <class Exact>
std::pair<double, std::size_t> band_error(const Volume& v, Exact&& exact) {
    double e = 0;
    std::size_t n = 0;
    test::for_each_block_sample(v, [&](int i, int j, int k, float phi) {
        if (std::abs(phi) >= v.background) return;
        ++n;
        e = std::max(e, std::abs(double(phi) - exact(v.grid.world(Vec3d(i, j, k)))));
    });
    return {e, n};
}

// The invariant of Volume: every sample with |exact| < band (minus a margin for the mesh's error)
// lies in an allocated block and has the right sign, checked on the whole grid.
template <class Exact>
void expect_band_complete_and_signs(const Volume& v, Exact&& exact, double margin) {
    std::size_t missing = 0, wrong_sign = 0;
    const double band = v.background;
    for (int k = 0; k < v.grid.dims[2]; ++k)
        for (int j = 0; j < v.grid.dims[1]; ++j)
            for (int i = 0; i < v.grid.dims[0]; ++i) {
                const double e = exact(v.grid.world(Vec3d(i, j, k)));
                const float phi = v.value(i, j, k);
                if (std::abs(e) < band - margin && v.block_of(i, j, k) < 0) ++missing;
                if (std::abs(e) > margin && (e < 0) != (phi < 0)) ++wrong_sign;
            }
    EXPECT_EQ(missing, 0u);
    EXPECT_EQ(wrong_sign, 0u);
}

TEST(ScanConvert, SphereMatchesTheClosedFormWithinChordError) {
    const Mesh m = test::icosphere(1.0, 4);
    const double chord = test::sphere_chord_error(m, 1.0);
    const auto q = make_bvh_query(m);
    ScanConvertReport rep;
    const Volume v = scan_convert(m, *q, at(48), &rep);
    const double h = v.grid.voxel_size;
    EXPECT_NEAR(h, 2.0 / 48, 1e-12);
    const auto sdf = [](const Vec3d& p) { return norm(p) - 1.0; };
    const auto [err, n] = band_error(v, sdf);
    EXPECT_GT(n, 1000u);
    EXPECT_NEAR(double(n), double(rep.band_voxels), 1e-3 * double(n));  // d < band vs float |phi| < band
    EXPECT_LT(err, chord + 1e-3 * h);
    expect_band_complete_and_signs(v, sdf, chord + 1e-3 * h);
    EXPECT_EQ(rep.uncertain_sign, 0u);
    EXPECT_TRUE(rep.warnings.empty());
}

TEST(ScanConvert, BoxIsExactUpToFloatRounding) {
    // A box mesh has no chord error: the band matches the closed form to float precision.
    const Vec3d lo{-0.3, -0.5, -0.2}, hi{0.7, 0.4, 0.9};
    const Mesh m = test::box_mesh(lo, hi);
    const auto q = make_bvh_query(m);
    const Volume v = scan_convert(m, *q, at(40, 4.0f));
    const auto sdf = [&](const Vec3d& p) { return test::box_sdf(p, lo, hi); };
    const auto [err, n] = band_error(v, sdf);
    EXPECT_GT(n, 1000u);
    EXPECT_LT(err, 1e-3 * v.grid.voxel_size);
    expect_band_complete_and_signs(v, sdf, 1e-3 * v.grid.voxel_size);
}

TEST(ScanConvert, TorusMatchesTheClosedFormWithinChordError) {
    const double R = 1.0, r = 0.35;
    const int nu = 96, nv = 48;
    const Mesh m = test::torus_mesh(R, r, nu, nv);
    // Chord error of a (nu × nv) torus: sagitta of the minor circle plus that of the major circle at
    // the outer equator (a bound on the distance from the surface to the mesh).
    const double chord = r * (1 - std::cos(std::numbers::pi / nv)) + (R + r) * (1 - std::cos(std::numbers::pi / nu));
    const auto q = make_bvh_query(m);
    const Volume v = scan_convert(m, *q, at(48));
    const auto sdf = [&](const Vec3d& p) { return test::torus_sdf(p, R, r); };
    const auto [err, n] = band_error(v, sdf);
    EXPECT_GT(n, 1000u);
    EXPECT_LT(err, chord + 1e-3 * v.grid.voxel_size);
    expect_band_complete_and_signs(v, sdf, chord + 1e-3 * v.grid.voxel_size);
}

TEST(ScanConvert, IdenticalForOneAndTwoThreads) {
    const Mesh m = test::concat(test::torus_mesh(1.0, 0.3, 48, 24), test::icosphere(0.4, 3, {0, 0, 0.1}));
    const auto q = make_bvh_query(m);
    ScanConvertReport r1, r2;
    const Volume a = scan_convert(m, *q, at(40, 3.0f, 1), &r1);
    const Volume b = scan_convert(m, *q, at(40, 3.0f, 2), &r2);
    EXPECT_EQ(a.block_table, b.block_table);
    EXPECT_EQ(a.block_coords, b.block_coords);
    EXPECT_EQ(a.values, b.values);
    EXPECT_EQ(r1.band_voxels, r2.band_voxels);
    EXPECT_EQ(r1.uncertain_sign, r2.uncertain_sign);
}

// Every window of a partition of the grid into bricks, scanned alone, holds what the whole scan holds in its blocks:
// the same values bit for bit where a block is allocated in either, the same tile sign elsewhere (a hollow ball,
// whose cavity and shell rows start inside some windows, a torus and a box).
TEST(ScanConvert, AWindowHoldsWhatTheWholeScanHoldsInItsBlocks) {
    Mesh m = test::concat(test::icosphere(1.0, 3), test::flipped(test::icosphere(0.5, 3)));
    Mesh torus = test::torus_mesh(0.6, 0.2, 32, 16);
    for (auto& p : torus.positions) p += Vec3f(0.3f, 0.2f, 1.5f);
    m = test::concat(m, torus);
    m = test::concat(m, test::box_mesh({1.2, -0.6, -0.6}, {2.4, 0.6, 0.6}));
    const auto q = make_bvh_query(m);
    const ScanConvertOptions o = at(96, 3.0f, 2);
    const Volume whole = scan_convert(m, *q, o);
    const Grid grid = scan_grid(m, o);
    ASSERT_EQ(grid.dims, whole.grid.dims);
    const WindingNumber wn(m);
    constexpr int kBrick = 3;  // blocks per window side: many windows start inside the ball or the box
    std::size_t windows = 0, samples = 0, differing = 0, inside_starts = 0;
    for (int bk = 0; bk < whole.block_dims[2]; bk += kBrick)
        for (int bj = 0; bj < whole.block_dims[1]; bj += kBrick)
            for (int bi = 0; bi < whole.block_dims[0]; bi += kBrick) {
                BlockWindow w;
                w.lo = {bi, bj, bk};
                for (int a = 0; a < 3; ++a) w.hi[a] = std::min(w.lo[a] + kBrick, whole.block_dims[a]);
                const Volume part = scan_convert_window(m, *q, &wn, grid, w, o);
                ++windows;
                for (int a = 0; a < 3; ++a) ASSERT_EQ(part.block_dims[a], w.hi[a] - w.lo[a]);
                if (w.lo[0] > 0) {
                    // Rows whose first block is an inside tile.
                    for (int rk = w.lo[2]; rk < w.hi[2]; ++rk)
                        for (int rj = w.lo[1]; rj < w.hi[1]; ++rj)
                            inside_starts += whole.block_table[whole.table_index(w.lo[0], rj, rk)] == kBlockInside;
                }
                for (int k = 0; k < part.grid.dims[2]; ++k)
                    for (int j = 0; j < part.grid.dims[1]; ++j)
                        for (int i = 0; i < part.grid.dims[0]; ++i) {
                            const float a = part.value(i, j, k);
                            const float b = whole.value(i + w.lo[0] * 8, j + w.lo[1] * 8, k + w.lo[2] * 8);
                            ++samples;
                            differing += a != b;
                        }
            }
    EXPECT_GT(windows, 50u);
    EXPECT_GT(inside_starts, 0u);  // the case the row's first winding number is there for
    EXPECT_EQ(samples, whole.grid.sample_count());
    EXPECT_EQ(differing, 0u);
    // A window outside the grid's blocks is refused.
    BlockWindow bad;
    bad.hi = {whole.block_dims[0] + 1, 1, 1};
    EXPECT_THROW(scan_convert_window(m, *q, &wn, grid, bad, o), InvalidInput);
}

// The same on an open mesh (a hemisphere open towards +x, the rows' direction): the whole scan's rows run on through
// the opening with the sign they had, where the winding number says otherwise, so a window's rows start with the
// sign the whole scan's rows carry there, not with the winding number. Each window (3 blocks a side, 1 of halo)
// holds the whole scan's blocks inside its halo: the same allocation (conflict blocks included), values and tile
// signs. The rows the winding number at their first block would have started otherwise are counted (202): the case
// this is for; started so, they left other tiles and conflict blocks than the whole scan (iron.ply: 264 rows at 256).
TEST(ScanConvert, AWindowOfAnOpenMeshHoldsWhatTheWholeScanHolds) {
    const Mesh ball = test::icosphere(1.0, 3);
    Mesh m;
    m.positions = ball.positions;
    for (const Tri& t : ball.triangles)
        if (ball.positions[t[0]][0] + ball.positions[t[1]][0] + ball.positions[t[2]][0] < 0.0f)
            m.triangles.push_back(t);
    const auto q = make_bvh_query(m);
    const ScanConvertOptions o = at(128, 3.0f, 2);
    ScanConvertReport rep;
    const Volume whole = scan_convert(m, *q, o, &rep);
    ASSERT_GT(rep.tile_conflict_blocks, 0u) << "the hole leaves no conflict to check";
    const Grid grid = scan_grid(m, o);
    const WindingNumber wn(m);
    constexpr int kBrick = 3, kHalo = 1;
    std::size_t blocks = 0, differing = 0, winding_differs = 0;
    for (int bk = 0; bk < whole.block_dims[2]; bk += kBrick)
        for (int bj = 0; bj < whole.block_dims[1]; bj += kBrick)
            for (int bi = 0; bi < whole.block_dims[0]; bi += kBrick) {
                const std::array<int, 3> lo{bi, bj, bk};
                BlockWindow w;
                for (int a = 0; a < 3; ++a) {
                    w.lo[a] = std::max(0, lo[a] - kHalo);
                    w.hi[a] = std::min(lo[a] + kBrick + kHalo, whole.block_dims[a]);
                }
                const Volume part = scan_convert_window(m, *q, &wn, grid, w, o);
                for (int rk = w.lo[2]; rk < w.hi[2] && w.lo[0] > 0; ++rk)
                    for (int rj = w.lo[1]; rj < w.hi[1]; ++rj) {
                        const std::int32_t t = whole.block_table[whole.table_index(w.lo[0], rj, rk)];
                        if (t >= 0) continue;
                        const Vec3d cen = grid.world(Vec3d(w.lo[0] * 8 + 3.5, rj * 8 + 3.5, rk * 8 + 3.5));
                        winding_differs += (wn(cen) > 0.5) != (t == kBlockInside);
                    }
                for (int k = lo[2]; k < std::min(lo[2] + kBrick, whole.block_dims[2]); ++k)
                    for (int j = lo[1]; j < std::min(lo[1] + kBrick, whole.block_dims[1]); ++j)
                        for (int i = lo[0]; i < std::min(lo[0] + kBrick, whole.block_dims[0]); ++i) {
                            ++blocks;
                            const std::int32_t a = whole.block_table[whole.table_index(i, j, k)];
                            const std::int32_t b =
                                part.block_table[part.table_index(i - w.lo[0], j - w.lo[1], k - w.lo[2])];
                            if ((a >= 0) != (b >= 0) || (a < 0 && a != b)) {
                                ++differing;
                                continue;
                            }
                            if (a >= 0 && !std::equal(whole.block_values(a), whole.block_values(a) + kBlockVoxels,
                                                      part.block_values(b)))
                                ++differing;
                        }
            }
    EXPECT_EQ(blocks, whole.block_table.size());
    EXPECT_GT(winding_differs, 0u);
    EXPECT_EQ(differing, 0u);
}

TEST(ScanConvert, MemoryGrowsWithTheSurfaceNotTheVolume) {
    // Doubling the resolution multiplies the band by about 4 (surface area in voxels), not 8.
    const Mesh m = test::icosphere(1.0, 4);
    const auto q = make_bvh_query(m);
    ScanConvertReport r32, r64, r128;
    scan_convert(m, *q, at(24), &r32);
    scan_convert(m, *q, at(48), &r64);
    scan_convert(m, *q, at(96), &r128);
    const double a = double(r64.band_voxels) / double(r32.band_voxels);
    const double b = double(r128.band_voxels) / double(r64.band_voxels);
    std::printf("band voxels 24/48/96: %zu %zu %zu (ratios %.2f %.2f)\n", r32.band_voxels, r64.band_voxels,
                r128.band_voxels, a, b);
    EXPECT_GT(a, 3.5);
    EXPECT_LT(a, 4.6);
    EXPECT_GT(b, 3.5);
    EXPECT_LT(b, 4.6);
    EXPECT_LT(double(r128.blocks) / double(r64.blocks), 4.6);
}

TEST(ScanConvert, SmallHolesKeepTheClosedSign) {
    // Remove the faces of an icosphere that lie within a small cap (hole diameter < 2 voxels): away
    // from the hole every sample has the sign of the closed sphere.
    const Mesh closed = test::icosphere(1.0, 4);
    Mesh holed = closed;
    std::vector<Tri> kept;
    for (const Tri& t : closed.triangles) {
        Vec3d c;
        for (int i = 0; i < 3; ++i) c += Vec3d(closed.positions[t[i]]);
        c = c / 3.0;
        if (!(c.z > 0.995) && !(c.x > 0.995)) kept.push_back(t);  // two holes, radius ~0.1
    }
    ASSERT_LT(kept.size(), closed.triangles.size());
    holed.triangles = kept;
    const auto q = make_bvh_query(holed);
    ScanConvertReport rep;
    const Volume v = scan_convert(holed, *q, at(24), &rep);  // h = 2/24 = 0.083: holes < 2 voxels
    std::size_t wrong = 0, checked = 0;
    for (int k = 0; k < v.grid.dims[2]; ++k)
        for (int j = 0; j < v.grid.dims[1]; ++j)
            for (int i = 0; i < v.grid.dims[0]; ++i) {
                const Vec3d p = v.grid.world(Vec3d(i, j, k));
                if (norm(p - Vec3d{0, 0, 1}) < 0.3 || norm(p - Vec3d{1, 0, 0}) < 0.3) continue;
                if (std::abs(norm(p) - 1.0) < 0.01) continue;
                ++checked;
                if ((v.value(i, j, k) < 0) != (norm(p) < 1.0)) ++wrong;
            }
    EXPECT_GT(checked, 10000u);
    EXPECT_EQ(wrong, 0u);
    // Said once, as what it means for the volume.
    EXPECT_GT(rep.uncertain_sign + rep.tile_conflict_blocks, 0u);
    ASSERT_EQ(rep.warnings.size(), 1u);
    EXPECT_EQ(rep.warnings[0], rep.open_mesh_warning);
    EXPECT_NE(rep.open_mesh_warning.find("the mesh is open (holes or boundaries): the volume is closed across them"),
              std::string::npos)
        << rep.open_mesh_warning;
}

TEST(ScanConvert, NestedShellsComponentsAndDuplicates) {
    // A hollow ball (outer sphere, inner reversed) with a duplicated face, plus a far box.
    Mesh m = test::concat(test::icosphere(1.0, 3), test::flipped(test::icosphere(0.5, 3)));
    m.triangles.push_back(m.triangles[0]);
    m = test::concat(m, test::box_mesh({2, -0.3, -0.3}, {2.6, 0.3, 0.3}));
    const auto q = make_bvh_query(m);
    const Volume v = scan_convert(m, *q, at(64));
    const auto sign_at = [&](Vec3d p) {
        const Vec3d ijk = v.grid.index(p);
        return v.value(int(std::lround(ijk.x)), int(std::lround(ijk.y)), int(std::lround(ijk.z)));
    };
    EXPECT_GT(sign_at({0, 0, 0}), 0);     // in the cavity
    EXPECT_LT(sign_at({0.75, 0, 0}), 0);  // in the shell
    EXPECT_GT(sign_at({1.5, 0, 0}), 0);   // between
    EXPECT_LT(sign_at({2.3, 0, 0}), 0);   // in the box
    EXPECT_GT(sign_at({0, 1.3, 0}), 0);
}

TEST(ScanConvert, OpenSheetThrowsUnlessShell) {
    const Mesh s = test::sheet(1.0, 8);
    const auto q = make_bvh_query(s);
    try {
        scan_convert(s, *q, at(32));
        FAIL() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("encloses no volume"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("shell"), std::string::npos) << e.what();
    }
    ScanConvertOptions o = at(32);
    o.shell_thickness = 0.1;
    const Volume v = scan_convert(s, *q, o);
    // phi = |z| − 0.05 over the interior of the sheet.
    const auto sdf = [](const Vec3d& p) { return std::abs(p.z) - 0.05; };
    double e = 0;
    test::for_each_block_sample(v, [&](int i, int j, int k, float phi) {
        const Vec3d p = v.grid.world(Vec3d(i, j, k));
        if (std::abs(phi) < v.background && std::abs(p.x) < 0.9 && std::abs(p.y) < 0.9)
            e = std::max(e, std::abs(phi - sdf(p)));
    });
    EXPECT_LT(e, 1e-5);
    EXPECT_LT(v.value(v.grid.dims[0] / 2, v.grid.dims[1] / 2, int(std::lround(v.grid.index({0, 0, 0}).z))), 0);
}

TEST(ScanConvert, AgreesWithBruteForceDistances) {
    const Mesh m = test::torus_mesh(1.0, 0.3, 24, 12);
    const auto bvh = make_bvh_query(m);
    const auto brute = make_brute_force_query(m);
    const Volume a = scan_convert(m, *bvh, at(24)), b = scan_convert(m, *brute, at(24));
    EXPECT_EQ(a.values, b.values);
}

TEST(ScanConvert, BadInput) {
    const Mesh m = test::icosphere(1.0, 1);
    const auto q = make_bvh_query(m);
    EXPECT_THROW(scan_convert(Mesh{}, *q), InvalidInput);
    EXPECT_THROW(scan_convert(m, *q, at(0)), InvalidInput);
    EXPECT_THROW(scan_convert(m, *q, at(16, 0.5f)), InvalidInput);
    ScanConvertOptions o = at(16);
    o.voxel_size = -1;
    EXPECT_THROW(scan_convert(m, *q, o), InvalidInput);
    o = at(16);
    o.shell_thickness = std::nan("");
    EXPECT_THROW(scan_convert(m, *q, o), InvalidInput);
    Mesh bad = m;
    bad.positions[0].x = std::numeric_limits<float>::infinity();
    EXPECT_THROW(scan_convert(bad, *q), InvalidInput);
    bad = m;
    bad.triangles.push_back({0, 1, 1000});
    EXPECT_THROW(scan_convert(bad, *q), InvalidInput);
    // Inside-out: encloses nothing with positive winding number.
    const Mesh inv = test::flipped(m);
    const auto qi = make_bvh_query(inv);
    EXPECT_THROW(scan_convert(inv, *qi, at(16)), InvalidInput);
}

}  // namespace
}  // namespace normalflow
