// Tests of lib/metrics/compare.h: each metric on a case with a known answer, then real models, then bad input.
#include "metrics/compare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <utility>

#include "core/errors.h"
#include "metric_test_meshes.h"
#include "metrics/noise.h"

namespace normalflow {
namespace {

CompareOptions fast_options() {
    CompareOptions o;
    o.sampling.samples = 20000;
    return o;
}

TEST(CompareMeshes, SphereVsScaledSphere) {
    const Mesh ref = test::icosphere(1.0, 4);
    const Mesh cand = test::scaled(ref, 1.05);
    const MeshComparison c = compare_meshes(cand, ref, fast_options());
    const double chord = test::sphere_chord_error(ref, 1.0);  // ~1.2e-3 at level 4
    EXPECT_NEAR(c.distance.hausdorff, 0.05, 1.1 * chord);
    EXPECT_NEAR(c.distance.mean, 0.05, 1.1 * chord);
    EXPECT_NEAR(c.distance.rms, 0.05, 1.1 * chord);
    EXPECT_LT(c.distance.mean_normal_angle_deg, 1.0);
    EXPECT_NEAR(c.reference_diagonal, norm(bounding_box(ref).size()), 1e-12);
    EXPECT_NEAR(c.hausdorff_relative, c.distance.hausdorff / c.reference_diagonal, 1e-15);
    // Scaling by s multiplies areas by s^2 and volumes by s^3, exactly up to float rounding.
    EXPECT_NEAR(c.area_change, 1.05 * 1.05 - 1, 1e-5);
    EXPECT_NEAR(c.volume_change, 1.05 * 1.05 * 1.05 - 1, 1e-5);
    EXPECT_EQ(c.components_candidate, 1u);
    EXPECT_TRUE(c.closed_candidate);
    EXPECT_TRUE(c.manifold_candidate);
    EXPECT_EQ(c.crease.feature_edges, 0u);  // a sphere has no creases
    EXPECT_DOUBLE_EQ(c.crease.fraction, 1.0);
}

TEST(CompareMeshes, CubeAreaVolumeAndSelf) {
    const Mesh cube = test::subdivided_cube(8);
    const MeshComparison c = compare_meshes(cube, cube, fast_options());
    EXPECT_NEAR(c.area_reference, 24.0, 1e-9);
    EXPECT_NEAR(c.volume_reference, 8.0, 1e-9);
    EXPECT_NEAR(c.distance.hausdorff, 0.0, 1e-6);
    EXPECT_DOUBLE_EQ(c.area_change, 0.0);
    EXPECT_DOUBLE_EQ(c.volume_change, 0.0);
    EXPECT_EQ(c.crease.feature_edges, 12u * 8u);
    EXPECT_NEAR(c.crease.feature_length, 24.0, 1e-5);
    EXPECT_NEAR(c.crease.fraction, 1.0, 1e-12);
    EXPECT_NEAR(c.crease.mean_angle_deg, 90.0, 1e-4);
}

TEST(CompareMeshes, ComponentsAndOpenMeshes) {
    const Mesh two = test::concat(test::icosphere(1.0, 2), test::icosphere(1.0, 2, {3, 0, 0}));
    const MeshComparison c = compare_meshes(two, test::icosphere(1.0, 2), fast_options());
    EXPECT_EQ(c.components_candidate, 2u);
    EXPECT_EQ(c.components_reference, 1u);
    EXPECT_NEAR(c.volume_change, 1.0, 1e-5);  // twice the volume
    const Mesh sheet = test::sheet(1.0, 4);
    const MeshComparison s = compare_meshes(sheet, sheet, fast_options());
    EXPECT_FALSE(s.closed_candidate);
    EXPECT_FALSE(s.warnings.empty());
}

TEST(CreasePreservation, SharpCubeKeepsRoundedCubeLoses) {
    const Mesh cube = test::subdivided_cube(8);
    const Mesh rounded = test::rounded_cube(40, 0.4);
    const CreasePreservation r = crease_preservation(rounded, cube);
    EXPECT_NEAR(r.feature_length, 24.0, 1e-5);
    EXPECT_LT(r.fraction, 0.05);
    EXPECT_LT(r.mean_angle_deg, 20.0);
    // A differently triangulated sharp cube keeps every crease.
    const CreasePreservation s = crease_preservation(test::subdivided_cube(13), cube);
    EXPECT_NEAR(s.fraction, 1.0, 1e-12);
    // Noise does not make a rounded cube sharp, nor a sharp one rounded (the sides are averaged).
    Mesh noisy_sharp = test::subdivided_cube(40);
    NoiseOptions no;
    no.sigma = 0.3;
    add_noise(noisy_sharp, no);
    EXPECT_GT(crease_preservation(noisy_sharp, cube).fraction, 0.9);
    Mesh noisy_round = rounded;
    add_noise(noisy_round, no);
    EXPECT_LT(crease_preservation(noisy_round, cube).fraction, 0.2);
}

TEST(CreasePreservation, ThresholdDecidesFeatureEdges) {
    const Mesh cube = test::subdivided_cube(4);
    CreaseOptions o;
    o.angle_deg = 95.0;  // cube edges are 90°: none is a feature
    const CreasePreservation r = crease_preservation(cube, cube, o);
    EXPECT_EQ(r.feature_edges, 0u);
    EXPECT_DOUBLE_EQ(r.fraction, 1.0);
}

TEST(CompareMeshes, NoisySphereDistancesFollowSigma) {
    // Noise of sigma along the normals: the pooled mean distance is below sigma·sqrt(2/pi) (the
    // half-normal mean) but of its order; the largest deviation is a few sigma.
    Mesh ref = test::icosphere(1.0, 4);
    Mesh noisy = ref;
    NoiseOptions no;
    no.sigma = 0.3;
    const NoiseReport nr = add_noise(noisy, no);
    const MeshComparison c = compare_meshes(noisy, ref, fast_options());
    EXPECT_GT(c.distance.mean, 0.2 * nr.sigma_world);
    EXPECT_LT(c.distance.mean, 0.8 * nr.sigma_world);
    EXPECT_GT(c.distance.hausdorff, 2.0 * nr.sigma_world);
    EXPECT_GT(c.distance.mean_normal_angle_deg, 5.0);
}

// correspondence_errors: face i against face i, vertex i against vertex i.

TEST(CorrespondenceErrors, MeshAgainstItselfIsZero) {
    const Mesh m = test::icosphere(1.0, 3);
    EXPECT_EQ(correspondence_mismatch(m, m), "");
    const CorrespondenceErrors e = correspondence_errors(m, m);
    EXPECT_EQ(e.faces, m.triangles.size());
    EXPECT_EQ(e.degenerate_faces, 0u);
    EXPECT_EQ(e.vertices, m.positions.size());
    EXPECT_EQ(e.mean_face_angle_deg, 0.0);
    EXPECT_EQ(e.max_face_angle_deg, 0.0);
    EXPECT_EQ(e.mean_vertex_distance, 0.0);
    EXPECT_EQ(e.max_vertex_distance, 0.0);
    EXPECT_NEAR(e.reference_diagonal, norm(bounding_box(m).size()), 1e-12);
}

TEST(CorrespondenceErrors, TranslationMovesEveryVertexByItsLengthAndTurnsNoFace) {
    const Mesh ref = test::icosphere(1.0, 3);
    Mesh cand = ref;
    const Vec3d t{0.3, -0.4, 1.2};  // |t| = 1.3
    for (Vec3f& p : cand.positions) p = Vec3f(Vec3d(p) + t);
    const CorrespondenceErrors e = correspondence_errors(cand, ref);
    EXPECT_LT(e.mean_face_angle_deg, 1e-3);  // float rounding of the shifted positions only
    EXPECT_LT(e.max_face_angle_deg, 1e-2);
    EXPECT_NEAR(e.mean_vertex_distance, 1.3, 1e-6);
    EXPECT_NEAR(e.max_vertex_distance, 1.3, 1e-6);
    EXPECT_NEAR(e.mean_vertex_distance_relative, 1.3 / e.reference_diagonal, 1e-6);
    EXPECT_NEAR(e.max_vertex_distance_relative, 1.3 / e.reference_diagonal, 1e-6);
}

TEST(CorrespondenceErrors, OneLiftedCornerOfTheUnitBox) {
    // Unit box, 12 triangles; corner 7 = (1, 1, 1) lifted to (1, 1, 2). Its four side triangles stay in
    // their planes x = 1 and y = 1 (same normals); the two top triangles (4, 5, 7) and (4, 7, 6) get
    // normals (0, −1, 1) and (−1, 0, 1): 45° each. Unweighted mean over faces: 2 · 45 / 12 = 7.5°
    // (area-weighted it would be 2 · 45 · 0.707 / 6.41 ≈ 9.9°). One vertex of 8 moved by 1: mean 1/8.
    const Mesh ref = test::box_mesh({0, 0, 0}, {1, 1, 1});
    Mesh cand = ref;
    ASSERT_EQ(cand.positions[7], Vec3f(1, 1, 1));
    cand.positions[7] = Vec3f(1, 1, 2);
    const CorrespondenceErrors e = correspondence_errors(cand, ref);
    EXPECT_EQ(e.faces, 12u);
    EXPECT_NEAR(e.mean_face_angle_deg, 7.5, 1e-12);
    EXPECT_NEAR(e.max_face_angle_deg, 45.0, 1e-12);
    EXPECT_EQ(e.vertices, 8u);
    EXPECT_NEAR(e.mean_vertex_distance, 0.125, 1e-15);
    EXPECT_NEAR(e.max_vertex_distance, 1.0, 1e-15);
    EXPECT_NEAR(e.reference_diagonal, std::sqrt(3.0), 1e-12);
    EXPECT_NEAR(e.mean_vertex_distance_relative, 0.125 / std::sqrt(3.0), 1e-12);
    // The candidate as reference: now the reference's top triangles are the tilted ones, same angles.
    EXPECT_NEAR(correspondence_errors(ref, cand).mean_face_angle_deg, 7.5, 1e-12);
    // Reversed normals are 180° (atan2 stays exact there). Mirroring x → 1 − x turns every normal n into
    // −(−n.x, n.y, n.z): the faces x = 0 and x = 1 swap sides and keep their normals, the 8 others reverse.
    // Mean 8 · 180 / 12 = 120°.
    Mesh mirrored = ref;
    for (Vec3f& p : mirrored.positions) p.x = 1 - p.x;
    const CorrespondenceErrors f = correspondence_errors(mirrored, ref);
    EXPECT_NEAR(f.mean_face_angle_deg, 120.0, 1e-12);
    EXPECT_NEAR(f.max_face_angle_deg, 180.0, 1e-12);
}

TEST(CorrespondenceErrors, DegenerateFacesAreSkippedAndCounted) {
    Mesh ref = test::box_mesh({0, 0, 0}, {1, 1, 1});
    ref.positions.push_back(Vec3f(0.5f, 0.5f, 0.5f));  // vertex 8, inside
    ref.triangles.push_back({0, 1, 8});                // a real triangle in the reference...
    ref.triangles.push_back({2, 2, 3});                // ...and one with a repeated index in both
    Mesh cand = ref;
    cand.positions[8] = Vec3f(0.5f, 0, 0);  // ...collinear with 0 and 1 in the candidate: zero area
    cand.positions[7] = Vec3f(1, 1, 2);     // the 45° lift of OneLiftedCornerOfTheUnitBox
    const CorrespondenceErrors e = correspondence_errors(cand, ref);
    EXPECT_EQ(e.degenerate_faces, 2u);
    EXPECT_EQ(e.faces, 12u);
    EXPECT_NEAR(e.mean_face_angle_deg, 7.5, 1e-12);  // over the 12 good faces only
    EXPECT_EQ(e.vertices, 9u);
    EXPECT_NEAR(e.mean_vertex_distance, (1.0 + std::sqrt(0.5)) / 9, 1e-7);  // corner 7 by 1, vertex 8 by |(0, .5, .5)|
    // compare_meshes reports them as a warning.
    CompareOptions o = fast_options();
    o.correspondence = true;
    const MeshComparison c = compare_meshes(cand, ref, o);
    ASSERT_TRUE(c.correspondence.has_value());
    EXPECT_EQ(c.correspondence->degenerate_faces, 2u);
    bool warned = false;
    for (const std::string& w : c.warnings) warned |= w.find("2 degenerate triangles") != std::string::npos;
    EXPECT_TRUE(warned);
}

TEST(CorrespondenceErrors, MismatchedMeshesAreRefusedByName) {
    const Mesh ref = test::box_mesh({0, 0, 0}, {1, 1, 1});
    auto message = [&](const Mesh& cand) {
        try {
            correspondence_errors(cand, ref);
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string("no exception");
    };
    Mesh more_vertices = ref;
    more_vertices.positions.push_back(Vec3f(2, 2, 2));
    EXPECT_EQ(message(more_vertices), "correspondence_errors: candidate has 9 vertices, reference 8");
    Mesh fewer_triangles = ref;
    fewer_triangles.triangles.pop_back();
    EXPECT_EQ(message(fewer_triangles), "correspondence_errors: candidate has 11 triangles, reference 12");
    Mesh reordered = ref;
    std::swap(reordered.triangles[5][1], reordered.triangles[5][2]);
    EXPECT_EQ(message(reordered),
              "correspondence_errors: triangle 5 differs: candidate (0, 4, 5), reference (0, 5, 4)");
    EXPECT_EQ(correspondence_mismatch(reordered, ref), "triangle 5 differs: candidate (0, 4, 5), reference (0, 5, 4)");
    EXPECT_THROW(correspondence_errors(Mesh{}, Mesh{}), InvalidInput);  // no triangles
    Mesh bad = ref, bad_ref = ref;
    bad.triangles[0][0] = bad_ref.triangles[0][0] = 99;
    EXPECT_THROW(correspondence_errors(bad, bad_ref), InvalidInput);  // same lists, out of range
    // compare_meshes refuses before measuring anything, and only when asked for the correspondence.
    CompareOptions o = fast_options();
    EXPECT_FALSE(compare_meshes(fewer_triangles, ref, o).correspondence.has_value());
    o.correspondence = true;
    try {
        compare_meshes(fewer_triangles, ref, o);
        FAIL() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_STREQ(e.what(), "compare_meshes: candidate has 11 triangles, reference 12");
    }
    EXPECT_NEAR(compare_meshes(ref, ref, o).correspondence->mean_face_angle_deg, 0.0, 0.0);
}

TEST(CompareMeshes, BadInput) {
    const Mesh cube = test::subdivided_cube(2);
    EXPECT_THROW(compare_meshes(Mesh{}, cube), InvalidInput);
    EXPECT_THROW(compare_meshes(cube, Mesh{}), InvalidInput);
    Mesh bad = cube;
    bad.triangles[0][0] = 999;
    try {
        compare_meshes(bad, cube);
        FAIL() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("candidate"), std::string::npos) << e.what();
    }
    CreaseOptions o;
    o.angle_deg = 0;
    EXPECT_THROW(crease_preservation(cube, cube, o), InvalidInput);
    o = {};
    o.radius_relative = -1;
    EXPECT_THROW(crease_preservation(cube, cube, o), InvalidInput);
}

}  // namespace
}  // namespace normalflow
