// Sharp re-meshing (PipelineOptions::sharpen, `normalflow remesh`): a mesh scan-converted and extracted, the
// extraction's vertices moved onto the input's creases and corners. A box first (its corners and edges exact),
// then the clean fandisk against its marching-tetrahedra extraction, then options refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "io/cgal/repair.h"
#include "io/io.h"
#include "metrics/compare.h"
#include "pipeline/pipeline.h"
#include "remesh/decimate.h"
#include "sdf/sdf_test_meshes.h"

namespace normalflow {
namespace {

PipelineOptions remeshing(int resolution, bool sharpen) {
    PipelineOptions o;
    o.smoothing = false;
    o.connectivity = Connectivity::Remesh;
    o.scan.resolution = resolution;
    o.sharpen = sharpen;
    return o;
}

double nearest_vertex(const Mesh& m, const Vec3d& p) {
    double best = std::numeric_limits<double>::infinity();
    for (const Vec3f& v : m.positions) best = std::min(best, norm(Vec3d(v) - p));
    return best;
}

TEST(SharpRemesh, BoxCornersAreExactAndTheResultClosedManifoldAndFreeOfIntersections) {
    const Vec3d lo(-0.53, -0.41, -0.37), hi(0.47, 0.59, 0.43);
    // The grid starts at the bounding box's minimum corner, so the faces there would lie on grid planes (samples
    // exactly on the surface, where marching tetrahedra makes faces without area): a small cube beyond it moves
    // the grid off the box.
    const Mesh box = test::concat(test::box_mesh(lo, hi), test::box_mesh({-0.93, -0.87, -0.91}, {-0.83, -0.79, -0.80}));
    for (const bool sharpen : {false, true}) {
        const PipelineResult r = smooth_mesh(box, remeshing(40, sharpen));
        const double h = r.report.scan.grid.voxel_size;
        double worst = 0;
        for (int c = 0; c < 8; ++c)
            worst = std::max(
                worst, nearest_vertex(r.mesh, {c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z}) / h);
        if (sharpen) {
            EXPECT_LT(worst, 0.1);
            EXPECT_TRUE(r.report.sharpened);
            EXPECT_GT(r.report.sharpen.moved, 0u);
        } else {
            EXPECT_GT(worst, 0.3);  // marching tetrahedra cuts the corners
        }
        const MeshReport mr = mesh_report(r.mesh);
        EXPECT_TRUE(mr.closed && mr.manifold) << "sharpen " << sharpen;
        EXPECT_EQ(mr.components, 2u);
        EXPECT_EQ(count_self_intersections(r.mesh), 0u);
        // every vertex on the box within a tiny fraction of a voxel when sharpened (faces on the box's planes)
        if (sharpen) {
            double off = 0;
            for (const Vec3f& p : r.mesh.positions) {
                const Vec3d q(p);
                if (q.x < lo.x - 0.1) continue;  // the small cube
                const double d = std::min({std::abs(q.x - lo.x), std::abs(q.x - hi.x), std::abs(q.y - lo.y),
                                           std::abs(q.y - hi.y), std::abs(q.z - lo.z), std::abs(q.z - hi.z)});
                off = std::max(off, d / h);
            }
            EXPECT_LT(off, 0.1);
        }
    }
}

TEST(SharpRemesh, CleanFandiskHasUnderHalfTheNormalErrorWithUnderHalfTheTriangles) {
    const Mesh gt = read_mesh(std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf/fandisk_gt.ply");
    PipelineOptions full = remeshing(128, false);
    full.full_density = true;  // the extraction itself
    const PipelineResult plain = smooth_mesh(gt, full);
    PipelineOptions o = remeshing(128, true);
    o.max_error = 0.03 * plain.report.scan.grid.voxel_size;
    const PipelineResult sharp = smooth_mesh(gt, o);
    const double a0 = compare_meshes(plain.mesh, gt).distance.mean_normal_angle_deg;
    const double a1 = compare_meshes(sharp.mesh, gt).distance.mean_normal_angle_deg;
    EXPECT_LT(a1, 0.5 * a0) << "marching tetrahedra " << a0 << "°, sharpened and decimated " << a1 << "°";
    EXPECT_LT(sharp.mesh.triangles.size(), plain.mesh.triangles.size() / 2);
    const MeshReport mr = mesh_report(sharp.mesh);
    EXPECT_TRUE(mr.closed && mr.manifold);
    EXPECT_EQ(count_self_intersections(sharp.mesh), 0u);
}

TEST(SharpRemesh, RefusedWithSmoothingOrKeptConnectivity) {
    const Mesh box = test::box_mesh({0, 0, 0}, {1, 1, 1});
    PipelineOptions o = remeshing(24, true);
    o.smoothing = true;
    EXPECT_THROW(smooth_mesh(box, o), InvalidInput);
    o = remeshing(24, true);
    o.connectivity = Connectivity::Keep;
    EXPECT_THROW(smooth_mesh(box, o), InvalidInput);
}

TEST(SharpRemesh, SelfIntersectingPairsOfFlaggedFacesOnly) {
    Mesh m;  // triangles 0 and 1 cross, 2 is far away
    m.positions = {{0, 0, 0},     {2, 0, 0}, {0, 2, 0},  {0.5, 0.5, -1}, {0.5, 0.5, 1},
                   {1.5, 0.2, 0}, {9, 9, 9}, {10, 9, 9}, {9, 10, 9}};
    m.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
    using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;
    EXPECT_EQ(self_intersecting_pairs(m), (Pairs{{0, 1}}));
    const std::vector<char> first = {1, 0, 0}, both = {1, 1, 0}, far = {0, 0, 1};
    EXPECT_EQ(self_intersecting_pairs(m, &first), (Pairs{{0, 1}}));
    EXPECT_EQ(self_intersecting_pairs(m, &both), (Pairs{{0, 1}}));  // found once
    EXPECT_TRUE(self_intersecting_pairs(m, &far).empty());
}

/// The smallest inner angle (degrees) between two faces on a manifold edge: 180 for a flat mesh, near 0 where the
/// surface doubles back on itself.
double sharpest_fold_deg(const Mesh& m) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::size_t>> edges;
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = m.triangles[f][k], b = m.triangles[f][(k + 1) % 3];
            edges[{std::min(a, b), std::max(a, b)}].push_back(f);
        }
    double worst = 180;
    for (const auto& [e, faces] : edges) {
        if (faces.size() != 2) continue;
        const Vec3d n0 = normalized(face_area_vector(m, m.triangles[faces[0]]));
        const Vec3d n1 = normalized(face_area_vector(m, m.triangles[faces[1]]));
        worst = std::min(worst, 180 - std::acos(std::clamp(dot(n0, n1), -1.0, 1.0)) * 180 / 3.14159265358979);
    }
    return worst;
}

// The clean fandisk's sharpest crease is 87°. `remesh --max-error 0.0005` left two faces folded to 1.3-2°
// (tetrahedra there had a 0.02° dihedral angle): collapses that each turned their faces less than 60° folded an edge
// of their ring. Such folds are opened by edge flips now (unfold_by_flips). (Without sharpening, one fold of 1.3°
// is a face turned over against all three neighbours, which no single flip opens: not yet handled.)
TEST(SharpRemesh, DecimatedFandiskHasNoFoldTheInputLacks) {
    const Mesh gt = read_mesh(std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf/fandisk_gt.ply");
    ASSERT_GT(sharpest_fold_deg(gt), 80.0);
    PipelineOptions o = remeshing(0, true);  // the automatic resolution, as the tool runs it
    o.max_error = 0.0005;
    const PipelineResult r = smooth_mesh(gt, o);
    EXPECT_GT(sharpest_fold_deg(r.mesh), 15.0);
    EXPECT_EQ(r.report.output_self_intersections, 0);
}

// A mesh without folds is left as it is.
TEST(SharpRemesh, UnfoldLeavesAFoldFreeMeshAlone) {
    Mesh sphere = test::icosphere(1.0, 3);
    const Mesh before = sphere;
    EXPECT_EQ(unfold_by_flips(sphere, 30.0), 0u);
    EXPECT_EQ(sphere.triangles, before.triangles);
}

}  // namespace
}  // namespace normalflow
