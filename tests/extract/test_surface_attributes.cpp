// Tests of lib/extract/surface_attributes.h: vertex normals from a volume and from faces, and colours
// carried to a new mesh by closest point. Analytic cases (a sphere's normals are radial; a colour
// that is a linear function of position is reproduced), then properties (seams, thread count).

#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/errors.h"
#include "extract/surface_attributes.h"
#include "normals/volume_fixtures.h"
#include "sdf/closest_triangle.h"
#include "sdf/sdf_test_meshes.h"

namespace normalflow {
namespace {

double angle_deg(const Vec3d& a, const Vec3d& b) {
    return std::atan2(norm(cross(a, b)), dot(a, b)) * 180 / std::numbers::pi;
}

/// The largest angle between m's normals and the radial direction from c.
double worst_radial_error(const Mesh& m, const Vec3d& c) {
    double worst = 0;
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        worst = std::max(worst, angle_deg(Vec3d(m.normals[i]), Vec3d(m.positions[i]) - c));
    return worst;
}

TEST(SurfaceAttributes, VolumeNormalsOfASphereAreRadialAndUnit) {
    const Vec3d c(1.6, 1.6, 1.6);
    const Volume v = test::make_volume(64, 0.05, test::sphere_sdf(c, 1.0));
    Mesh m = test::icosphere(1.0, 3, c);
    set_volume_normals(m, v);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (const Vec3f& n : m.normals) EXPECT_NEAR(norm(Vec3d(n)), 1.0, 1e-5);
    // central differences of an exact distance, trilinearly blended: a fraction of a degree
    EXPECT_LT(worst_radial_error(m, c), 0.5);
    // outward: the inside sphere's normals point away from the centre too (φ grows outward)
    Mesh inner = test::icosphere(0.97, 2, c);  // within a voxel: the differences see no clamped sample
    set_volume_normals(inner, v);
    EXPECT_LT(worst_radial_error(inner, c), 0.5);
}

TEST(SurfaceAttributes, VolumeNormalsAreZeroOutsideTheBandAndIndependentOfThreads) {
    const Vec3d c(1.6, 1.6, 1.6);
    const Volume v = test::make_volume(64, 0.05, test::sphere_sdf(c, 1.0));
    Mesh far = test::icosphere(0.2, 1, c);  // 0.8 inside: far beyond a 3-voxel band
    set_volume_normals(far, v);
    for (const Vec3f& n : far.normals) EXPECT_EQ(n, (Vec3f{0, 0, 0}));
    Mesh a = test::icosphere(1.02, 4, c), b = a;
    tbb::task_arena(1).execute([&] { set_volume_normals(a, v); });
    tbb::task_arena(2).execute([&] { set_volume_normals(b, v); });
    EXPECT_EQ(a.normals, b.normals);
}

TEST(SurfaceAttributes, FaceNormalsApproachTheSphereAndSeamsShareOne) {
    Mesh m = test::icosphere(1.0, 4);
    // a seam: vertex 0 split into a copy used by its first face
    m.positions.push_back(m.positions[0]);
    const auto copy = std::uint32_t(m.positions.size() - 1);
    for (Tri& t : m.triangles)
        if (t[0] == 0 || t[1] == 0 || t[2] == 0) {
            for (auto& i : t)
                if (i == 0) i = copy;
            break;
        }
    set_face_normals(m);
    EXPECT_LT(worst_radial_error(m, Vec3d(0, 0, 0)), 1.0);  // level 4: faces span ~4 degrees
    EXPECT_EQ(m.normals[0], m.normals[copy]);
    // and without the seam handling each side would see only part of the fan: check that it matters
    Mesh lone;
    lone.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {0, -1, 0}, {0, 0, 1}};
    lone.triangles = {{0, 1, 2}, {3, 4, 5}};
    set_face_normals(lone);
    EXPECT_EQ(lone.normals[0], lone.normals[3]);
    EXPECT_GT(angle_deg(Vec3d(lone.normals[0]), Vec3d(0, 0, 1)), 10.0);
}

TEST(SurfaceAttributes, TransferredColoursFollowALinearRamp) {
    // red = 255 (x + 1) / 2 on a fine sphere; a coarser sphere inside it gets the ramp back, up to
    // the tessellation of the source and rounding
    Mesh src = test::icosphere(1.0, 5);
    for (const Vec3f& p : src.positions)
        src.colors.push_back(Rgba8{std::uint8_t(std::lround(127.5 * (p.x + 1))), 7, 200, 255});
    Mesh dst = test::icosphere(0.99, 3);
    transfer_colors(dst, src, *make_bvh_query(src));
    ASSERT_EQ(dst.colors.size(), dst.positions.size());
    double worst = 0;
    for (std::size_t i = 0; i < dst.positions.size(); ++i) {
        const Vec3d p = Vec3d(dst.positions[i]) / 0.99;
        worst = std::max(worst, std::abs(double(dst.colors[i][0]) - 127.5 * (p.x + 1)));
        EXPECT_EQ(dst.colors[i][1], 7);
        EXPECT_EQ(dst.colors[i][2], 200);
    }
    EXPECT_LT(worst, 2.0);
    // a source without colours leaves the target as it was
    Mesh plain = test::icosphere(1.0, 1);
    transfer_colors(plain, test::icosphere(1.0, 2), *make_bvh_query(test::icosphere(1.0, 2)));
    EXPECT_FALSE(plain.has_colors());
}

TEST(SurfaceAttributes, BadInputThrows) {
    Mesh m = test::icosphere(1.0, 1);
    m.triangles[0][1] = 999;
    EXPECT_THROW(set_face_normals(m), InvalidInput);
    const Volume v = test::make_volume(16, 0.2, test::sphere_sdf(Vec3d(1.6, 1.6, 1.6), 1.0));
    EXPECT_THROW(set_volume_normals(m, v), InvalidInput);
}

}  // namespace
}  // namespace normalflow
