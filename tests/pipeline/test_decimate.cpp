// Decimation: normalflow's quadric edge collapse (lib/remesh decimate_mesh_qem), meshoptimizer's
// simplifier (io/meshopt) and the pipeline's checked decimate_mesh, with CGAL's edge collapse as the
// fallback and the alternative.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <tbb/global_control.h>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "extract/extract_surface.h"
#include "extract/surface_attributes.h"
#include "io/cgal/repair.h"
#include "io/io.h"
#include "io/meshopt/decimate.h"
#include "metrics/surface_distance.h"
#include "pipeline/pipeline.h"
#include "remesh/decimate.h"
#include "sdf/closest_triangle.h"
#include "sdf/scan_convert.h"
#include "sdf/sdf_test_meshes.h"
#include "support/attributed_mesh.h"
#include "support/test_files.h"

namespace normalflow {
namespace {

using Key = std::tuple<float, float, float>;
Key key(const Vec3f& p) { return {p.x, p.y, p.z}; }

/// The positions of the vertices on open borders (edges of one face).
std::set<Key> border_vertices(const Mesh& m) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> count;
    for (const Tri& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t[k], b = t[(k + 1) % 3];
            ++count[{std::min(a, b), std::max(a, b)}];
        }
    std::set<Key> out;
    for (const auto& [e, n] : count)
        if (n == 1) {
            out.insert(key(m.positions[e.first]));
            out.insert(key(m.positions[e.second]));
        }
    return out;
}

/// A sphere scan-converted at `resolution` and extracted: a closed manifold re-mesh like the pipeline's.
Mesh extracted_sphere(int resolution) {
    const Mesh s = test::icosphere(1.0, 4);
    ScanConvertOptions so;
    so.resolution = resolution;
    return extract_surface(scan_convert(s, *make_bvh_query(s), so));
}

TEST(MeshoptDecimate, SphereReachesTheFaceCountClosedAndOnTheSphere) {
    Mesh m = test::icosphere(1.0, 5);  // 20480 faces
    const std::set<Key> before = [&] {
        std::set<Key> s;
        for (const Vec3f& p : m.positions) s.insert(key(p));
        return s;
    }();
    const Mesh input = m;
    const meshopt::DecimateReport r = meshopt::decimate_mesh(m, {.target_faces = 2000});
    EXPECT_EQ(r.faces_before, 20480u);
    EXPECT_EQ(r.faces_after, m.triangles.size());
    EXPECT_LE(r.faces_after, 2000u);
    EXPECT_GE(r.faces_after, 1800u);
    EXPECT_TRUE(r.reached_target);
    EXPECT_EQ(r.vertices_after, m.positions.size());
    const MeshReport mr = mesh_report(m);
    EXPECT_TRUE(mr.closed);
    EXPECT_TRUE(mr.manifold);
    EXPECT_EQ(mr.referenced_vertices, m.positions.size());  // compacted
    EXPECT_EQ(mr.euler_characteristic, 2);
    EXPECT_GT(mr.volume, 4.0);  // orientation kept (4/3 π = 4.19)
    // Collapses go onto existing vertices: every vertex is one of the input's, on the unit sphere.
    for (const Vec3f& p : m.positions) EXPECT_TRUE(before.count(key(p))) << p.x << " " << p.y << " " << p.z;
    const SampledDistance d = sampled_hausdorff(m, input, 3);
    EXPECT_GT(d.hausdorff, 0.0);
    EXPECT_LT(d.hausdorff, 0.02);  // 2000 faces on a unit sphere: chord error about 0.005
    EXPECT_GT(r.error, 0.0);
    EXPECT_LT(r.error, 0.05);
}

TEST(MeshoptDecimate, SurvivingVerticesKeepTheirAttributes) {
    Mesh m = test::attributed_sphere(4);  // 5120 faces
    const Mesh input = m;
    meshopt::decimate_mesh(m, {.target_faces = 500});
    ASSERT_LE(m.triangles.size(), 500u);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    ASSERT_EQ(m.colors.size(), m.positions.size());
    ASSERT_EQ(m.texcoords.size(), m.positions.size());
    std::map<Key, std::size_t> at;
    for (std::size_t i = 0; i < input.positions.size(); ++i) at[key(input.positions[i])] = i;
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        const auto it = at.find(key(m.positions[i]));
        ASSERT_NE(it, at.end());
        const std::size_t j = it->second;
        EXPECT_EQ(m.normals[i], input.normals[j]);
        EXPECT_EQ(m.colors[i], input.colors[j]);
        EXPECT_EQ(m.texcoords[i], input.texcoords[j]);
    }
}

TEST(MeshoptDecimate, OpenBordersStayWhereTheyAreUnlessUnlocked) {
    const Mesh sheet = test::sheet(1.0, 40);  // a flat open square, 3200 faces
    const std::set<Key> border = border_vertices(sheet);
    ASSERT_GT(border.size(), 100u);
    Mesh locked = sheet, free = sheet;
    meshopt::decimate_mesh(locked, {.target_faces = 400});
    meshopt::decimate_mesh(free, {.target_faces = 400, .lock_border = false});
    EXPECT_EQ(border_vertices(locked), border);  // every border vertex kept: the outline is unchanged
    EXPECT_LT(free.triangles.size(), locked.triangles.size());
    EXPECT_LT(border_vertices(free).size(), border.size());  // the flag is what kept them
}

TEST(MeshoptDecimate, SmallMeshesAndBadInput) {
    Mesh m = test::icosphere(1.0, 1);  // 80 faces
    const Mesh input = m;
    meshopt::decimate_mesh(m, {.target_faces = 80});
    EXPECT_EQ(m.triangles, input.triangles);
    EXPECT_EQ(m.positions, input.positions);
    EXPECT_THROW(meshopt::decimate_mesh(m, {.target_faces = 3}), InvalidInput);
    Mesh empty;
    EXPECT_THROW(meshopt::decimate_mesh(empty, {.target_faces = 10}), InvalidInput);
    Mesh bad = input;
    bad.triangles[0][1] = 1000;
    EXPECT_THROW(meshopt::decimate_mesh(bad, {.target_faces = 10}), InvalidInput);
    bad = input;
    bad.colors.resize(3);
    EXPECT_THROW(meshopt::decimate_mesh(bad, {.target_faces = 10}), InvalidInput);
}

// --- normalflow's quadric edge collapse ---

/// The cube [-1, 1]³ with each face an n×n grid of squares, each split in two; shared vertices.
Mesh grid_cube(int n) {
    Mesh m;
    std::map<std::tuple<int, int, int>, std::uint32_t> index;
    auto vertex = [&](int i, int j, int k) {  // integer coordinates in [0, n]
        const auto [it, added] = index.try_emplace({i, j, k}, std::uint32_t(m.positions.size()));
        if (added) m.positions.push_back(Vec3f(Vec3d(2.0 * i / n - 1, 2.0 * j / n - 1, 2.0 * k / n - 1)));
        return it->second;
    };
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side)
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) {
                    std::uint32_t q[4];
                    const int da[4] = {0, 1, 1, 0}, db[4] = {0, 0, 1, 1};
                    for (int c = 0; c < 4; ++c) {
                        int p[3];
                        p[axis] = side * n;
                        p[(axis + 1) % 3] = a + da[c];
                        p[(axis + 2) % 3] = b + db[c];
                        q[c] = vertex(p[0], p[1], p[2]);
                    }
                    if (side) {  // outward: the quad's normal along +axis for side 1, −axis for side 0
                        m.triangles.push_back({q[0], q[1], q[2]});
                        m.triangles.push_back({q[0], q[2], q[3]});
                    } else {
                        m.triangles.push_back({q[0], q[2], q[1]});
                        m.triangles.push_back({q[0], q[3], q[2]});
                    }
                }
    return m;
}

TEST(QuadricDecimate, CubeKeepsItsCornersAndEdgesExactly) {
    // The quadric of a corner has rank 3 (three planes) and of an edge rank 2: the collapses leave the
    // 8 corners where they are and every vertex on the cube's surface, on its edges where it was.
    Mesh m = grid_cube(24);  // 6912 faces
    ASSERT_TRUE(mesh_report(m).closed && mesh_report(m).manifold);
    ASSERT_GT(mesh_report(m).volume, 0.0);
    const QemReport r = decimate_mesh_qem(m, {.target_faces = 100});
    EXPECT_LE(r.faces_after, 100u);
    EXPECT_TRUE(r.reached_target);
    const MeshReport mr = mesh_report(m);
    EXPECT_TRUE(mr.closed);
    EXPECT_TRUE(mr.manifold);
    EXPECT_EQ(mr.euler_characteristic, 2);
    EXPECT_EQ(mr.degenerate_faces, 0u);
    EXPECT_NEAR(mr.volume, 8.0, 1e-4);  // nothing cut off
    int corners = 0;
    for (const Vec3f& p : m.positions) {
        const double ax = std::abs(p.x), ay = std::abs(p.y), az = std::abs(p.z);
        EXPECT_NEAR(std::max({ax, ay, az}), 1.0, 1e-6);  // on the surface
        corners += ax == 1.0 && ay == 1.0 && az == 1.0;
    }
    EXPECT_EQ(corners, 8);
    EXPECT_LT(r.max_error, 1e-6);
}

TEST(QuadricDecimate, SphereStaysOnTheSphereAndManifold) {
    Mesh m = test::icosphere(1.0, 5);  // 20480 faces
    const Mesh input = m;
    const QemReport r = decimate_mesh_qem(m, {.target_faces = 2000});
    EXPECT_EQ(r.faces_before, 20480u);
    EXPECT_LE(r.faces_after, 2000u);
    EXPECT_GE(r.faces_after, 1990u);  // two faces per collapse
    EXPECT_EQ(r.faces_after, m.triangles.size());
    EXPECT_EQ(r.collapses, (20480u - r.faces_after) / 2);
    const MeshReport mr = mesh_report(m);
    EXPECT_TRUE(mr.closed && mr.manifold);
    EXPECT_EQ(mr.euler_characteristic, 2);
    EXPECT_EQ(mr.referenced_vertices, m.positions.size());
    EXPECT_GT(mr.volume, 4.0);
    for (const Vec3f& p : m.positions) EXPECT_NEAR(norm(Vec3d(p)), 1.0, 0.01);
    const SampledDistance d = sampled_hausdorff(m, input, 3);
    EXPECT_LT(d.hausdorff, 0.02);
    EXPECT_GT(r.max_error, 0.0);
    EXPECT_LT(r.max_error, 0.02);
}

TEST(QuadricDecimate, TorusKeepsItsGenusAndDecimationIsDeterministic) {
    const Mesh t = test::torus_mesh(1.0, 0.3, 120, 60);  // genus 1, 14400 faces
    Mesh a = t, b = t;
    decimate_mesh_qem(a, {.target_faces = 600});
    decimate_mesh_qem(b, {.target_faces = 600});
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.triangles, b.triangles);
    const MeshReport mr = mesh_report(a);
    EXPECT_TRUE(mr.closed && mr.manifold);
    EXPECT_EQ(mr.euler_characteristic, 0);
    EXPECT_LE(a.triangles.size(), 600u);
    // A tetrahedron is as far as a closed component goes.
    Mesh tiny = test::icosphere(1.0, 0);  // 20 faces
    decimate_mesh_qem(tiny, {.target_faces = 4});
    const MeshReport tr = mesh_report(tiny);
    EXPECT_TRUE(tr.closed && tr.manifold);
    EXPECT_GE(tiny.triangles.size(), 4u);
    EXPECT_EQ(tr.euler_characteristic, 2);
}

TEST(QuadricDecimate, TheThreadCountDoesNotChangeTheResult) {
    // Each pass costs edges in parallel and makes its collapses in parallel: on an extraction (many
    // passes, thousands of collapses in each) 1, 2 and 4 threads give the same mesh, bit for bit.
    const Mesh input = extracted_sphere(96);
    ASSERT_GT(input.triangles.size(), 50000u);
    std::vector<Mesh> out;
    for (const int threads : {1, 2, 4}) {
        const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
        Mesh m = input;
        const QemReport r = decimate_mesh_qem(m, {.target_faces = 3000});
        EXPECT_TRUE(r.reached_target);
        out.push_back(std::move(m));
    }
    for (std::size_t k = 1; k < out.size(); ++k) {
        EXPECT_EQ(out[k].positions, out[0].positions);
        EXPECT_EQ(out[k].triangles, out[0].triangles);
    }
    const MeshReport mr = mesh_report(out[0]);
    EXPECT_TRUE(mr.closed && mr.manifold);
    EXPECT_EQ(mr.euler_characteristic, 2);
}

TEST(QuadricDecimate, OpenBordersStayAndAttributesFollowTheirVertices) {
    const Mesh sheet = test::sheet(1.0, 40);  // a flat open square, 3200 faces
    const std::set<Key> border = border_vertices(sheet);
    Mesh m = sheet;
    decimate_mesh_qem(m, {.target_faces = 400});
    EXPECT_LE(m.triangles.size(), 400u);
    EXPECT_EQ(border_vertices(m), border);
    for (const Vec3f& p : m.positions) EXPECT_EQ(p.z, 0.0f);
    Mesh s = test::attributed_sphere(4);
    const Mesh input = s;
    decimate_mesh_qem(s, {.target_faces = 500});
    ASSERT_EQ(s.colors.size(), s.positions.size());
    ASSERT_EQ(s.texcoords.size(), s.positions.size());
    ASSERT_EQ(s.normals.size(), s.positions.size());
    // each kept vertex carries the attributes of an input vertex within an edge or two of it
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        double bd = 1e300;
        for (std::size_t j = 0; j < input.positions.size(); ++j)
            bd = std::min(bd, squared_norm(Vec3d(input.positions[j]) - Vec3d(s.positions[i])));
        EXPECT_LT(std::sqrt(bd), 0.3);
        bool found = false;
        for (std::size_t j = 0; j < input.positions.size() && !found; ++j)
            found = input.colors[j] == s.colors[i] && input.texcoords[j] == s.texcoords[i] &&
                    input.normals[j] == s.normals[i];
        EXPECT_TRUE(found) << i;
    }
}

TEST(QuadricDecimate, BadInputThrows) {
    Mesh m = test::icosphere(1.0, 1);
    EXPECT_THROW(decimate_mesh_qem(m, {.target_faces = 3}), InvalidInput);
    EXPECT_THROW(decimate_mesh_qem(m, {.target_faces = 10, .max_normal_change_deg = 0}), InvalidInput);
    EXPECT_THROW(decimate_mesh_qem(m, {.target_faces = 10, .min_quality = 1.0}), InvalidInput);
    Mesh empty;
    EXPECT_THROW(decimate_mesh_qem(empty, {.target_faces = 10}), InvalidInput);
    Mesh bad = m;
    bad.triangles[0][0] = 999;
    EXPECT_THROW(decimate_mesh_qem(bad, {.target_faces = 10}), InvalidInput);
}

TEST(DecimateMesh, AutoRunsTheQuadricCollapseAndChecksTheResult) {
    Mesh m = extracted_sphere(64);
    const std::size_t faces = m.triangles.size();
    ASSERT_GT(faces, 20000u);
    const DecimationReport r = decimate_mesh(m, 3000);
    EXPECT_EQ(r.decimator, "quadric");
    EXPECT_EQ(r.fallback, "");
    EXPECT_EQ(r.faces_before, faces);
    EXPECT_EQ(r.faces_after, m.triangles.size());
    EXPECT_LE(r.faces_after, 3000u);
    EXPECT_GE(r.faces_after, 2700u);
    EXPECT_TRUE(r.closed);
    EXPECT_TRUE(r.manifold);
    EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
#ifdef NORMALFLOW_TEST_HAS_CGAL
    EXPECT_EQ(r.self_intersections, 0);
#else
    EXPECT_EQ(r.self_intersections, -1);
#endif
    const MeshReport mr = mesh_report(m);
    EXPECT_TRUE(mr.closed && mr.manifold);
    // The distance is measured, not estimated: within the 3000-face chord error of the sphere's
    // re-mesh (voxel 2/64 ≈ 0.03).
    EXPECT_GT(r.hausdorff, 0.0);
    EXPECT_LT(r.hausdorff, 0.03);
    EXPECT_EQ(r.hausdorff, std::max(r.result_to_input, r.input_to_result));
    EXPECT_GE(r.seconds, r.seconds_decimate);
}

#ifdef NORMALFLOW_TEST_HAS_CGAL
TEST(DecimateMesh, CgalOnRequestAndBothWithinTheSameDistance) {
    const Mesh input = extracted_sphere(64);
    Mesh a = input, b = input;
    const DecimationReport ra = decimate_mesh(a, 3000, Decimator::Quadric);
    const DecimationReport rb = decimate_mesh(b, 3000, Decimator::Cgal);
    EXPECT_EQ(ra.decimator, "quadric");
    EXPECT_EQ(rb.decimator, "cgal");
    EXPECT_TRUE(rb.closed && rb.manifold);
    EXPECT_EQ(rb.self_intersections, 0);
    EXPECT_LE(rb.faces_after, 3000u);
    // Same face budget, same surface: the quadric collapse is as close as CGAL's or closer.
    EXPECT_LE(ra.hausdorff, 1.1 * rb.hausdorff);
}
#endif

#ifdef NORMALFLOW_TEST_HAS_CGAL
// The folded cortex at a coarse grid decimated to 1,500 faces: the quadric collapse alone leaves pairs
// of faces through each other (measured: 3); Auto repairs them or decimates again with CGAL, and hands
// back no more than the quadric collapse left (at this ratio CGAL's own result has more), with a warning
// where any remain.
TEST(DecimateMesh, AutoLeavesNoMoreSelfIntersectionsThanTheQuadricCollapse) {
    const std::string path = std::string(NORMALFLOW_TEST_DATA) + "/medical/brainmesh_icbm152_lh.ply";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared/data missing";
    const Mesh brain = read_mesh(path);
    ScanConvertOptions so;
    so.resolution = 96;
    const Mesh ext = extract_surface(scan_convert(brain, *make_bvh_query(brain), so));
    Mesh q = ext, a = ext;
    const DecimationReport rq = decimate_mesh(q, 1500, Decimator::Quadric);
    EXPECT_EQ(rq.decimator, "quadric");
    EXPECT_TRUE(rq.closed && rq.manifold);
    ASSERT_GT(rq.self_intersections, 0) << "the premise: this decimation folds the surface through itself";
    const DecimationReport ra = decimate_mesh(a, 1500);
    EXPECT_TRUE(ra.closed && ra.manifold);
    EXPECT_TRUE(ra.repaired_self_intersections > 0 || !ra.fallback.empty());
    EXPECT_LE(ra.self_intersections, rq.self_intersections);
    EXPECT_EQ(count_self_intersections(a), std::size_t(ra.self_intersections));
    EXPECT_EQ(ra.self_intersections > 0, !ra.warnings.empty());
    EXPECT_LE(a.triangles.size(), 1500u);
}
#endif

TEST(DecimateMesh, BadInputThrows) {
    Mesh m = test::icosphere(1.0, 2);
    EXPECT_THROW(decimate_mesh(m, 3), InvalidInput);
    Mesh empty;
    EXPECT_THROW(decimate_mesh(empty, 100), InvalidInput);
}

// --- tangent planes (Hermite data) and the error bound ---

/// A closed mesh scan-converted at `resolution`, extracted, with the field's normals: what the pipeline
/// decimates. h receives the voxel size.
Mesh extracted_with_normals(const Mesh& s, int resolution, double& h) {
    ScanConvertOptions so;
    so.resolution = resolution;
    const Volume v = scan_convert(s, *make_bvh_query(s), so);
    h = v.grid.voxel_size;
    Mesh m = extract_surface(v);
    set_volume_normals(m, v);
    return m;
}

/// The distance from p to the nearest vertex of m.
double nearest_vertex(const Mesh& m, const Vec3d& p) {
    double best = 1e300;
    for (const Vec3f& q : m.positions) best = std::min(best, norm(Vec3d(q) - p));
    return best;
}

TEST(TangentPlanes, ExtractedCubeShrinksWithoutLosingItsCorners) {
    // Flat faces merge at no cost: the cube's extraction drops to a few percent of its faces. The field's
    // normals are rounded within a voxel of an edge (outside a convex corner φ is the distance to it), so
    // the corners stay where the extraction bevelled them: no further, not closer (measured: the
    // nearest vertex 1.03 voxel from a corner, against 1.07 in the extraction).
    const Vec3d lo(-0.73, -0.61, -0.52), hi(0.67, 0.59, 0.81);  // corners off the grid
    double h = 0;
    const Mesh cube = extracted_with_normals(test::box_mesh(lo, hi), 48, h);
    Mesh m = cube;
    const QemReport r = decimate_mesh_qem(m, {.max_error = 0.02 * h, .tangent_planes = true});
    EXPECT_TRUE(r.reached_target);
    EXPECT_LE(r.max_error, 0.02 * h * (1 + 1e-9));
    EXPECT_LT(m.triangles.size(), cube.triangles.size() / 20);
    for (int k = 0; k < 8; ++k) {
        const Vec3d corner(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
        EXPECT_LT(nearest_vertex(m, corner), nearest_vertex(cube, corner) + 0.25 * h) << k;
    }
    for (const Vec3f& p : m.positions)  // every vertex on the box, within the extraction's accuracy
        EXPECT_LT(std::abs(test::box_sdf(Vec3d(p), lo, hi)), 0.5 * h);
    const MeshReport mr = mesh_report(m);
    EXPECT_TRUE(mr.closed && mr.manifold);
    EXPECT_EQ(mr.euler_characteristic, 2);
}

TEST(TangentPlanes, ErrorBoundAdaptsTheSphereAndKeepsItAccurate) {
    double h = 0;
    const Mesh sphere = extracted_with_normals(test::icosphere(1.0, 6), 64, h);
    auto radial = [](const Mesh& m) {  // largest |‖p‖ − 1| over the vertices and face centroids
        double worst = 0;
        for (const Tri& t : m.triangles) {
            const Vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
            worst = std::max({worst, std::abs(norm(a) - 1), std::abs(norm((a + b + c) / 3.0) - 1)});
        }
        return worst;
    };
    const double extracted = radial(sphere);
    std::size_t previous = 0;
    for (double e : {0.1, 0.03, 0.01}) {  // tighter bound, more faces, closer to the sphere
        Mesh m = sphere;
        const QemReport r = decimate_mesh_qem(m, {.max_error = e * h, .tangent_planes = true});
        EXPECT_LE(r.max_error, e * h * (1 + 1e-9));
        EXPECT_GT(m.triangles.size(), previous) << e;
        previous = m.triangles.size();
        EXPECT_LT(m.triangles.size(), sphere.triangles.size() / 4) << e;
        EXPECT_LT(radial(m), extracted + 4 * e * h) << e;
        EXPECT_TRUE(mesh_report(m).closed && mesh_report(m).manifold);
    }
}

TEST(TangentPlanes, BadOptionsThrow) {
    Mesh m = test::icosphere(1.0, 2);
    EXPECT_THROW(decimate_mesh_qem(m, {.target_faces = 0}), InvalidInput);  // no stop at all
    EXPECT_THROW(decimate_mesh_qem(m, {.max_error = -1.0}), InvalidInput);
    EXPECT_THROW(decimate_mesh_qem(m, {.max_error = 0.1, .tangent_planes = true}), InvalidInput);  // no normals
    EXPECT_THROW(decimate_mesh(m, {.max_error = 0.1, .decimator = Decimator::Meshoptimizer}), InvalidInput);
    EXPECT_THROW(decimate_mesh(m, {.target_faces = 0}), InvalidInput);
}

TEST(TangentPlanes, PipelineDecimatesWithinTheErrorBound) {
    // volume_to_mesh with max_error: an adaptive mesh, checked like a face-count decimation.
    const Mesh box = test::box_mesh({-0.73, -0.61, -0.52}, {0.67, 0.59, 0.81});
    PipelineOptions o;
    o.smoothing = false;
    o.scan.resolution = 48;
    o.full_density = true;
    const Volume v = mesh_to_volume(box, o);
    const Mesh dense = volume_to_mesh(v, o);
    o.full_density = false;  // an explicit max_error wins over the compact default
    o.max_error = 0.02 * v.grid.voxel_size;
    PipelineReport r;
    const Mesh m = volume_to_mesh(v, o, &r);
    ASSERT_TRUE(r.decimated);
    EXPECT_FALSE(r.compacted);
    EXPECT_EQ(r.decimate.decimator, "quadric");
    EXPECT_EQ(r.decimate.faces_before, dense.triangles.size());
    EXPECT_EQ(r.decimate.faces_after, m.triangles.size());
    EXPECT_LT(m.triangles.size(), dense.triangles.size() / 20);
    EXPECT_TRUE(r.decimate.closed && r.decimate.manifold);
#ifdef NORMALFLOW_TEST_HAS_CGAL
    EXPECT_EQ(r.decimate.self_intersections, 0);
#endif
    EXPECT_EQ(m.normals.size(), m.positions.size());
    // closer to the true box than the dense extraction, by the mean normal angle
    const SurfaceDistance dd = surface_distance(dense, box), dm = surface_distance(m, box);
    EXPECT_LT(dm.mean_normal_angle_deg, dd.mean_normal_angle_deg);
    o.connectivity = Connectivity::Keep;
    EXPECT_THROW(validate(o), InvalidInput);
}

#ifdef NORMALFLOW_TEST_CLI
// smooth --target-faces and cleanup --target-faces decimate with the quadric collapse by default and say so.
TEST(DecimateMesh, CliReportsTheDecimator) {
    test::TempDir dir;
    const std::string in = dir / "sphere.ply", out = dir / "out.ply", json = dir / "r.json";
    write_mesh(in, test::icosphere(1.0, 4));
    const std::string cli = NORMALFLOW_TEST_CLI;
    auto run = [&](const std::string& args) {
        const std::string cmd = cli + " " + args + " --json > " + json;
        EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
        return test::slurp(json);
    };
    std::string j = run("smooth " + in + " " + out + " --resolution 48 --iterations 1 --target-faces 1500");
    EXPECT_NE(j.find("\"decimator\":\"quadric\""), std::string::npos) << j;
    EXPECT_LE(read_mesh(out).triangles.size(), 1500u);
#ifdef NORMALFLOW_TEST_HAS_CGAL
    j = run("cleanup " + in + " " + out + " --target-faces 1000");
    EXPECT_NE(j.find("\"decimator\":\"quadric\""), std::string::npos) << j;
    EXPECT_LE(read_mesh(out).triangles.size(), 1000u);
    {  // a soup (every face its own three vertices, as STL files are) is welded first
        Mesh soup;
        const Mesh sphere = test::icosphere(1.0, 4);
        for (const Tri& t : sphere.triangles) {
            const auto base = std::uint32_t(soup.positions.size());
            for (int c = 0; c < 3; ++c) soup.positions.push_back(sphere.positions[t[c]]);
            soup.triangles.push_back({base, base + 1, base + 2});
        }
        const std::string soup_path = dir / "soup.ply";
        write_mesh(soup_path, soup);
        j = run("cleanup " + soup_path + " " + out + " --target-faces 1000");
        const Mesh r = read_mesh(out);
        EXPECT_LE(r.triangles.size(), 1000u) << j;
        EXPECT_TRUE(mesh_report(r).closed && mesh_report(r).manifold);
    }
    j = run("cleanup " + in + " " + out + " --target-faces 1000 --decimator cgal");
    EXPECT_NE(j.find("\"decimator\":\"cgal\""), std::string::npos) << j;
    EXPECT_LE(read_mesh(out).triangles.size(), 1000u);
#endif
    j = run("smooth " + in + " " + out + " --resolution 48 --iterations 1 --connectivity remesh --max-error 0.002");
    EXPECT_NE(j.find("\"decimate\""), std::string::npos) << j;
    EXPECT_LT(read_mesh(out).triangles.size(), 20000u);
    {  // extract takes the same decimation
        const std::string vdb = dir / "sphere.vdb";
        const std::string vox = cli + " voxelize " + in + " " + vdb + " --resolution 48 --quiet";
        ASSERT_EQ(std::system(vox.c_str()), 0);
        j = run("extract " + vdb + " " + out + " --max-error 0.001");
        EXPECT_NE(j.find("\"decimator\":\"quadric\""), std::string::npos) << j;
        const Mesh e = read_mesh(out);
        EXPECT_TRUE(mesh_report(e).closed && mesh_report(e).manifold);
    }
    const std::string bad = cli + " cleanup " + in + " " + out + " --target-faces 100 --decimator fast 2>/dev/null";
    EXPECT_NE(std::system(bad.c_str()), 0);
}
#endif

}  // namespace
}  // namespace normalflow

namespace normalflow {
namespace {

// Two faces that touch at distinct vertices with the same position: no intersection once welded (they share the
// vertex), one as written (a reader of the file sees the surface pinch there). The check of normalflow's outputs.
TEST(SelfIntersections, AsWrittenCountsFacesTouchingAtCoincidentVertices) {
#ifdef NORMALFLOW_TEST_HAS_CGAL
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {-1, 0, 0.5f}, {0, -1, 0.5f}};
    m.triangles = {{0, 1, 2}, {3, 4, 5}};
    EXPECT_EQ(count_self_intersections(m), 0u);
    EXPECT_EQ(count_self_intersections_as_written(m), 1u);
    m.positions[3] = {0, 0, 0.25f};  // apart: neither counts
    EXPECT_EQ(count_self_intersections_as_written(m), 0u);
#else
    GTEST_SKIP() << "needs CGAL";
#endif
}

// The normal bound: every face of the result within the bound of the surface's normals at its corners (or no worse
// than it started), on a sphere whose normals are exact; fewer faces with a looser bound; none of it without normals.
TEST(TangentPlanes, NormalDeviationBoundHolds) {
    Mesh sphere = test::icosphere(1.0, 5);
    for (const Vec3f& p : sphere.positions) sphere.normals.push_back(Vec3f(normalized(Vec3d(p))));
    auto worst = [](const Mesh& m) {
        double w = 0;
        for (const Tri& t : m.triangles) {
            const Vec3d n = normalized(face_area_vector(m, t));
            for (const std::uint32_t v : t)
                w = std::max(w, std::acos(std::clamp(dot(n, normalized(Vec3d(m.normals[v]))), -1.0, 1.0)) * 180 /
                                    3.14159265358979);
        }
        return w;
    };
    const double start = worst(sphere);
    std::size_t faces[2];
    for (const int k : {0, 1}) {
        const double bound = k == 0 ? 4.0 : 12.0;
        Mesh m = sphere;
        decimate_mesh_qem(m, {.max_error = 0.05, .tangent_planes = true, .max_normal_deviation_deg = bound});
        EXPECT_LE(worst(m), std::max(bound, start) + 1e-6) << bound;
        faces[k] = m.triangles.size();
    }
    EXPECT_LT(faces[1], faces[0] / 2);
    EXPECT_LT(faces[0], sphere.triangles.size() / 2);  // the bound still lets it decimate
    Mesh bare = test::icosphere(1.0, 2);
    EXPECT_THROW(decimate_mesh_qem(bare, {.max_error = 0.1, .max_normal_deviation_deg = 4}), InvalidInput);
}

}  // namespace
}  // namespace normalflow
