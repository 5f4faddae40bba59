// Tests of lib/metrics/compare.h: each metric on a case with a known answer, then real models, then bad input.
#include "metrics/compare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

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
