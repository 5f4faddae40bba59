// Tests of trim_to_footprint (lib/remesh/trim_to_footprint.h) on an analytic case: the sphere
// extracted from a volume, trimmed to a sphere with a hole (the open input). The pipeline tests run it
// on real open scans (tests/pipeline).

#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "remesh/trim_to_footprint.h"
#include "sdf/closest_triangle.h"
#include "sdf/sdf_test_meshes.h"

namespace normalflow {
namespace {

/// The icosphere less the faces whose centroids lie below z = cut.
Mesh cut_sphere(double r, int levels, double cut) {
    const Mesh full = test::icosphere(r, levels);
    Mesh m;
    m.positions = full.positions;
    for (const Tri& t : full.triangles)
        if ((full.positions[t[0]].z + full.positions[t[1]].z + full.positions[t[2]].z) / 3.0 > cut)
            m.triangles.push_back(t);
    return m;
}

TEST(TrimToFootprint, SphereTrimmedToTheHoledInputHasItsHole) {
    const Mesh input = cut_sphere(1.0, 4, -0.5);
    Mesh surface = test::icosphere(1.002, 5);  // the "extracted" closed surface, a little off the input
    surface.colors.assign(surface.positions.size(), Rgba8{1, 2, 3, 4});
    const double h = 0.03;
    const TrimReport rep = trim_to_footprint(surface, input, *make_bvh_query(input), h, 3 * h);
    const MeshReport r = mesh_report(surface);
    EXPECT_EQ(r.boundary_loops, 1u);
    EXPECT_EQ(r.components, 1u);
    EXPECT_TRUE(r.manifold);
    EXPECT_GT(rep.faces_removed, 0u);
    // what is left is the input's footprint: nothing below the cut by more than the tolerance, and the
    // area of the input's within a few percent
    for (const Vec3f& p : surface.positions) EXPECT_GT(p.z, -0.5 - 0.1);
    EXPECT_NEAR(r.area, mesh_report(input).area, 0.05 * mesh_report(input).area);
    // the attributes follow the vertices
    EXPECT_EQ(surface.colors.size(), surface.positions.size());
}

TEST(TrimToFootprint, ClosedInputOrNearSurfaceLosesNothing) {
    const Mesh input = test::icosphere(1.0, 3);
    Mesh surface = test::icosphere(1.01, 3);
    const Mesh before = surface;
    trim_to_footprint(surface, input, *make_bvh_query(input), 0.05, 0.15);
    EXPECT_EQ(surface.triangles, before.triangles);
}

TEST(TrimToFootprint, BadDistancesThrow) {
    const Mesh input = cut_sphere(1.0, 2, -0.5);
    Mesh surface = test::icosphere(1.0, 2);
    const auto q = make_bvh_query(input);
    EXPECT_THROW(trim_to_footprint(surface, input, *q, 0.0, 1.0), InvalidInput);
    EXPECT_THROW(trim_to_footprint(surface, input, *q, 0.2, 0.1), InvalidInput);
    EXPECT_THROW(trim_to_footprint(surface, input, *q, 0.1, std::nan("")), InvalidInput);
}

}  // namespace
}  // namespace normalflow
