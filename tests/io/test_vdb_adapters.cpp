// In-memory adapters between Volume and OpenVDB grids (issue 23): OpenVDB's own level sets become volumes
// with the right surface, and a volume goes to a FloatGrid and back unchanged, placement included.
#include <gtest/gtest.h>

#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <cmath>
#include <numbers>

#include "core/errors.h"
#include "extract/extract_surface.h"
#include "io/openvdb/vdb_adapters.h"

namespace normalflow {
namespace {

const Vec3d kCentre{0.3, -0.1, 0.2};
constexpr float kRadius = 2.0f, kVoxel = 0.05f;

openvdb::FloatGrid::Ptr sphere() {
    openvdb::initialize();
    return openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        kRadius, openvdb::Vec3f(float(kCentre.x), float(kCentre.y), float(kCentre.z)), kVoxel, 3.0f);
}

/// The largest |distance to the centre − r| over the vertices of v's extracted surface, placed in the world.
double radial_error(const Volume& v, double r) {
    const Mesh m = extract_surface(v);
    EXPECT_GT(m.triangles.size(), 1000u);
    double worst = 0;
    for (const Vec3f& p : m.positions)
        worst = std::max(worst, std::abs(norm(v.grid.placement.point(Vec3d{p.x, p.y, p.z}) - kCentre) - r));
    return worst;
}

TEST(VdbAdapters, OpenVdbsLevelSetSphereBecomesTheSameSurface) {
    const openvdb::FloatGrid::Ptr g = sphere();
    const openvdb::Index64 active = g->activeVoxelCount();
    const Volume v = from_openvdb(*g);
    EXPECT_EQ(g->activeVoxelCount(), active);  // the grid is left as it was
    EXPECT_NEAR(v.grid.voxel_size, kVoxel, 1e-7);
    EXPECT_TRUE(v.grid.placement.is_identity());
    EXPECT_LT(radial_error(v, kRadius), 0.1 * kVoxel);  // exact distances: only the extraction's chord error
}

TEST(VdbAdapters, AVolumeGoesToAGridAndBackUnchangedWithItsPlacement) {
    Volume v = from_openvdb(*sphere());
    const double a = std::numbers::pi / 5;  // turned about z and reflected in z
    v.grid.placement.rotation = {Vec3d{std::cos(a), std::sin(a), 0}, Vec3d{-std::sin(a), std::cos(a), 0},
                                 Vec3d{0, 0, -1}};
    v.grid.placement.translation = {1.5, -2.0, 0.25};
    const openvdb::FloatGrid::Ptr g = to_openvdb(v);
    EXPECT_EQ(g->getGridClass(), openvdb::GRID_LEVEL_SET);
    // OpenVDB's transform puts our sample (3, 4, 5) where the placement does
    const openvdb::Vec3d w = g->transform().indexToWorld(openvdb::Vec3d(3, 4, 5));
    const Vec3d want = v.grid.placement.point(v.grid.world(Vec3d{3, 4, 5}));
    EXPECT_LT(norm(Vec3d{w[0], w[1], w[2]} - want), 1e-9);
    const Volume back = from_openvdb(*g);
    EXPECT_EQ(back.grid.dims, v.grid.dims);
    for (int c = 0; c < 3; ++c) EXPECT_LT(norm(back.grid.placement.rotation[c] - v.grid.placement.rotation[c]), 1e-9);
    for (int k = 0; k < v.grid.dims[2]; k += 3)
        for (int j = 0; j < v.grid.dims[1]; j += 3)
            for (int i = 0; i < v.grid.dims[0]; i += 3) {
                const Vec3d p = v.grid.placement.point(v.grid.world(Vec3d{double(i), double(j), double(k)}));
                const Vec3d q = back.grid.placement.point(back.grid.world(Vec3d{double(i), double(j), double(k)}));
                ASSERT_LT(norm(p - q), 1e-9);
                ASSERT_EQ(back.value(i, j, k), v.value(i, j, k)) << i << " " << j << " " << k;
            }
}

TEST(VdbAdapters, AFogVolumeIsTakenAtItsHalfLevel) {
    openvdb::FloatGrid::Ptr fog = sphere();
    openvdb::tools::sdfToFogVolume(*fog);  // 0 outside, rising to 1 a band's width inside
    const Volume v = from_openvdb(*fog);
    EXPECT_LT(radial_error(v, kRadius - 1.5 * kVoxel), 0.6 * kVoxel);  // the 0.5 level: half the 3-voxel band in
}

TEST(VdbAdapters, EmptyAndShearedGridsAreRefused) {
    openvdb::initialize();
    const openvdb::FloatGrid::Ptr empty = openvdb::FloatGrid::create(1.0f);
    EXPECT_THROW(from_openvdb(*empty, "mine"), InvalidInput);
    const openvdb::FloatGrid::Ptr g = sphere();
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    m(1, 0) = 0.5;  // the y axis leans towards x
    g->setTransform(openvdb::math::Transform::createLinearTransform(m));
    try {
        from_openvdb(*g, "mine");
        ADD_FAILURE() << "a sheared transform was accepted";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("mine: grid transform is"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace normalflow
