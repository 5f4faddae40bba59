// Tests of sharpen_mesh (lib/remesh/sharpen.h): an extraction's vertices moved onto the creases and corners of
// the surface it approximates. Known answers first (a box and an octahedron get their corners back within a small
// fraction of a voxel), then properties (a sphere is not made worse, moves are bounded, faces never turn, the
// thread count does not matter), then bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "extract/extract_surface.h"
#include "remesh/sharpen.h"
#include "sdf/closest_triangle.h"
#include "sdf/scan_convert.h"
#include "sdf/sdf_test_meshes.h"

namespace normalflow {
namespace {

struct Extraction {
    Volume volume;
    Mesh mesh;
};

Extraction extract(const Mesh& m, int resolution) {
    ScanConvertOptions o;
    o.resolution = resolution;
    const auto q = make_bvh_query(m);
    Extraction e;
    e.volume = scan_convert(m, *q, o);
    e.mesh = extract_surface(e.volume);
    return e;
}

/// The distance from p to the nearest vertex of m.
double nearest_vertex(const Mesh& m, const Vec3d& p) {
    double best = std::numeric_limits<double>::infinity();
    for (const Vec3f& v : m.positions) best = std::min(best, norm(Vec3d(v) - p));
    return best;
}

/// The largest distance of a corner to its nearest vertex, in voxels.
double worst_corner(const Mesh& m, const std::vector<Vec3d>& corners, double h) {
    double worst = 0;
    for (const Vec3d& c : corners) worst = std::max(worst, nearest_vertex(m, c) / h);
    return worst;
}

/// An octahedron of radius r about c.
Mesh octahedron(double r, const Vec3d& c) {
    Mesh m;
    for (const Vec3d& d :
         {Vec3d(r, 0, 0), Vec3d(-r, 0, 0), Vec3d(0, r, 0), Vec3d(0, -r, 0), Vec3d(0, 0, r), Vec3d(0, 0, -r)})
        m.positions.push_back(Vec3f(c + d));
    m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    return m;
}

TEST(Sharpen, BoxCornersComeBackWithinATenthOfAVoxel) {
    const Mesh box = test::box_mesh({-0.53, -0.41, -0.37}, {0.47, 0.59, 0.43});
    // the grid starts at the bounding box's corner: a small cube beyond it puts the box's faces off the grid planes
    Extraction e = extract(test::concat(box, test::box_mesh({-0.93, -0.87, -0.91}, {-0.83, -0.79, -0.80})), 48);
    const double h = e.volume.grid.voxel_size;
    std::vector<Vec3d> corners;
    for (int c = 0; c < 8; ++c) corners.push_back({c & 1 ? 0.47 : -0.53, c & 2 ? 0.59 : -0.41, c & 4 ? 0.43 : -0.37});
    const double before = worst_corner(e.mesh, corners, h);
    EXPECT_GT(before, 0.3);  // marching tetrahedra cuts the corners
    const auto q = make_bvh_query(box);
    Mesh s = e.mesh;
    SharpenOptions o;
    o.max_move = 1.5 * h;
    const SharpenReport r = sharpen_mesh(s, mesh_probe(box, *q), o);
    EXPECT_LT(worst_corner(s, corners, h), 0.1) << "before: " << before;
    EXPECT_GT(r.moved, 0u);
    EXPECT_LE(r.max_move, o.max_move * (1 + 1e-9));
    // the same faces: still closed and manifold
    ASSERT_EQ(s.triangles, e.mesh.triangles);
    const MeshReport mr = mesh_report(s);
    EXPECT_TRUE(mr.closed && mr.manifold)
        << mr.boundary_edges << " boundary edges, " << mr.non_manifold_edges << " non-manifold edges, "
        << mr.non_manifold_vertices << " non-manifold vertices, " << mr.degenerate_faces << " degenerate faces";
    for (const Tri& t : s.triangles) {  // no face with area turned by 120° or more
        const Vec3d a = face_area_vector(s, t), b = face_area_vector(e.mesh, t);
        if (norm(b) > 1e-6 * o.max_move * o.max_move) {
            EXPECT_GT(dot(a, b), -0.5 * norm(a) * norm(b));
        }
    }
}

TEST(Sharpen, OctahedronCornersComeBackWithinATenthOfAVoxel) {
    const Mesh oct = octahedron(0.6, {0.013, 0.027, -0.019});
    // the grid starts at the bounding box's corner: a small cube beyond it puts the octahedron's corners off the grid
    Extraction e = extract(test::concat(oct, test::box_mesh({-0.93, -0.87, -0.91}, {-0.83, -0.79, -0.80})), 52);
    const double h = e.volume.grid.voxel_size;
    std::vector<Vec3d> corners;
    for (const Vec3f& p : oct.positions) corners.push_back(Vec3d(p));
    const double before = worst_corner(e.mesh, corners, h);
    EXPECT_GT(before, 0.3);
    const auto q = make_bvh_query(oct);
    SharpenOptions o;
    o.max_move = 1.5 * h;
    sharpen_mesh(e.mesh, mesh_probe(oct, *q), o);
    EXPECT_LT(worst_corner(e.mesh, corners, h), 0.1) << "before: " << before;
}

TEST(Sharpen, ASphereIsNotMadeWorseAndTheVolumeProbeWorksToo) {
    const Mesh sphere = test::icosphere(0.8, 5);
    Extraction e = extract(sphere, 40);
    const auto radial = [](const Mesh& m) {
        double worst = 0;
        for (const Vec3f& p : m.positions) worst = std::max(worst, std::abs(norm(Vec3d(p)) - 0.8));
        return worst;
    };
    const double before = radial(e.mesh);
    for (int probe = 0; probe < 2; ++probe) {
        Mesh s = e.mesh;
        SharpenOptions o;
        o.max_move = e.volume.grid.voxel_size;
        const auto q = make_bvh_query(sphere);
        sharpen_mesh(s, probe ? volume_probe(e.volume) : mesh_probe(sphere, *q), o);
        EXPECT_LE(radial(s), before + 0.05 * e.volume.grid.voxel_size) << "probe " << probe;
    }
}

TEST(Sharpen, MovesAreBoundedAndTheThreadCountDoesNotMatter) {
    const Mesh box = test::box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5});
    Extraction e = extract(box, 24);
    // a probe that points far away: every vertex stops at max_move
    const SurfaceProbe far = [](const Vec3d& p, Vec3d& q, Vec3d& n) {
        q = p + Vec3d(10, 0, 0);
        n = Vec3d(1, 0, 0);
        return true;
    };
    SharpenOptions o;
    o.max_move = 0.25 * e.volume.grid.voxel_size;
    Mesh s = e.mesh;
    const SharpenReport r = sharpen_mesh(s, far, o);
    EXPECT_LE(r.max_move, o.max_move * (1 + 1e-9));
    for (std::size_t i = 0; i < s.positions.size(); ++i)
        EXPECT_LE(norm(Vec3d(s.positions[i]) - Vec3d(e.mesh.positions[i])), o.max_move * 1.0001);
    const auto q = make_bvh_query(box);
    Mesh a = e.mesh, b = e.mesh;
    o.max_move = e.volume.grid.voxel_size;
    o.threads = 1;
    sharpen_mesh(a, mesh_probe(box, *q), o);
    o.threads = 2;
    sharpen_mesh(b, mesh_probe(box, *q), o);
    EXPECT_EQ(a.positions, b.positions);
}

TEST(Sharpen, BadOptionsAreRefused) {
    Mesh m = test::icosphere(1.0, 1);
    const SurfaceProbe none = [](const Vec3d&, Vec3d&, Vec3d&) { return false; };
    SharpenOptions o;
    EXPECT_THROW(sharpen_mesh(m, none, o), InvalidInput);  // max_move 0
    o.max_move = 0.1;
    o.iterations = 0;
    EXPECT_THROW(sharpen_mesh(m, none, o), InvalidInput);
    o.iterations = 1;
    o.truncation = 1.0;
    EXPECT_THROW(sharpen_mesh(m, none, o), InvalidInput);
    o.truncation = 0.05;
    const Mesh before = m;
    EXPECT_NO_THROW(sharpen_mesh(m, none, o));  // nothing to go by: nothing moves
    EXPECT_EQ(m.positions, before.positions);
}

}  // namespace
}  // namespace normalflow
