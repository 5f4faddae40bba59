// image_to_volume: dense images (binary masks, label maps, intensities) to signed distance volumes,
// with anisotropic spacing and rotated or reflected axes. Analytic cases: balls whose radius and normals
// are known everywhere.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/errors.h"
#include "extract/extract_surface.h"
#include "normals/smooth.h"
#include "sdf/image_to_volume.h"

namespace normalflow {
namespace {

/// An image of n[0] × n[1] × n[2] samples with the given axes and origin, value(world position).
template <class F>
ScalarImage make_image(std::array<int, 3> n, std::array<Vec3d, 3> axes, Vec3d origin, F value) {
    ScalarImage im;
    im.dims = n;
    im.axes = axes;
    im.origin = origin;
    im.values.resize(im.sample_count());
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i)
                im.values[std::size_t(i) + std::size_t(n[0]) * (std::size_t(j) + std::size_t(n[1]) * std::size_t(k))] =
                    float(value(origin + axes[0] * double(i) + axes[1] * double(j) + axes[2] * double(k)));
    return im;
}

Vec3d to_d(const Vec3f& p) { return {p.x, p.y, p.z}; }

/// Area-weighted mean and the maximum of |distance to centre − R| over the face centroids, and the
/// area-weighted mean angle (degrees) between face normals and the sphere's.
struct SphereError {
    double mean_radial = 0, max_radial = 0, normal_deg = 0;
};
SphereError sphere_error(const Mesh& m, const Vec3d& c, double R, const Placement& p = {}) {
    SphereError e;
    double area = 0;
    for (const auto& t : m.triangles) {
        const Vec3d a = p.point(to_d(m.positions[t[0]])), b = p.point(to_d(m.positions[t[1]])),
                    d = p.point(to_d(m.positions[t[2]]));
        Vec3d n = cross(b - a, d - a);
        const double A = 0.5 * norm(n);
        if (!(A > 0)) continue;
        n = n / norm(n);
        if (p.reflects()) n = n * -1.0;
        const Vec3d r = (a + b + d) / 3.0 - c;
        const double err = std::abs(norm(r) - R);
        e.mean_radial += A * err;
        e.max_radial = std::max(e.max_radial, err);
        e.normal_deg += A * std::acos(std::clamp(dot(n, r / norm(r)), -1.0, 1.0)) * 180 / std::numbers::pi;
        area += A;
    }
    e.mean_radial /= area;
    e.normal_deg /= area;
    return e;
}

ImageToVolumeOptions iso_options(double iso, bool negate) {
    ImageToVolumeOptions o;
    o.surface.iso = iso;
    o.surface.negate = negate;
    return o;
}

const std::array<Vec3d, 3> kUnitAxes{Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};

TEST(ImageToVolume, BallMaskSmoothedIsWithinHalfAVoxelAndTwoDegrees) {
    // The target: a binary mask of a ball at 128³; the mask's staircase is far off, isotropic
    // smoothing brings the surface within 0.5 voxel of the sphere and its normals within 2°.
    const Vec3d c{63.7, 64.2, 63.4};
    const double R = 40.3;
    const ScalarImage im = make_image({128, 128, 128}, kUnitAxes, {}, [&](Vec3d x) { return norm(x - c) < R ? 1 : 0; });
    ASSERT_EQ(binary_mask_label(im), 1.0);
    Volume v = image_to_volume(im, {.surface = {.label = 1.0}});
    EXPECT_EQ(v.grid.dims, im.dims);
    EXPECT_TRUE(v.grid.placement.is_identity());
    const SphereError mask = sphere_error(extract_surface(v), c, R);
    EXPECT_LE(mask.max_radial, 0.5 + 1e-3);  // the staircase: samples half a voxel from the mask's faces
    EXPECT_GT(mask.normal_deg, 15.0);
    SmoothOptions so;
    so.mode = SmoothMode::Isotropic;
    smooth_volume(v, so);
    const SphereError smooth = sphere_error(extract_surface(v), c, R);
    EXPECT_LT(smooth.max_radial, 0.5);
    EXPECT_LT(smooth.mean_radial, 0.1);
    EXPECT_LT(smooth.normal_deg, 2.0);
}

TEST(ImageToVolume, IntensitiesOfAnyScaleBecomeTheSameDistances) {
    // A smooth field, larger inside (negate), in two units: the distances do not depend on the scale and
    // are the ball's to a tenth of a voxel near the surface.
    const Vec3d c{20.2, 19.6, 20.5};
    const double R = 11.0;
    for (const double scale : {1.0, 1000.0}) {
        const ScalarImage im =
            make_image({40, 40, 40}, kUnitAxes, {}, [&](Vec3d x) { return scale * (R - norm(x - c)) + 7 * scale; });
        const Volume v = image_to_volume(im, iso_options(7 * scale, true));
        double near = 0, far = 0;  // worst errors within 1.5 voxels of the surface, and within 5
        for (int k = 0; k < 40; ++k)
            for (int j = 0; j < 40; ++j)
                for (int i = 0; i < 40; ++i) {
                    const double d = norm(Vec3d{double(i), double(j), double(k)} - c) - R;
                    const double err = std::abs(v.value(i, j, k) - d);
                    if (std::abs(d) < 1.5) near = std::max(near, err);
                    if (std::abs(d) < 5) far = std::max(far, err);
                }
        EXPECT_LT(near, 0.1) << "scale " << scale;
        EXPECT_LT(far, 0.35) << "scale " << scale;  // the first-order eikonal solution's error
    }
}

TEST(ImageToVolume, AnisotropicSpacingIsResampledInWorldUnits) {
    // z spacing 2.5: resampled to unit voxels, the ball lands where it is in the world.
    const Vec3d c{30.3, 29.8, 31.1}, origin{-4, 2, 5};
    const double R = 20.0;
    const ScalarImage im = make_image({64, 64, 26}, {Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 2.5}}, origin,
                                      [&](Vec3d x) { return norm(x - origin - c) < R ? 1 : 0; });
    const Volume v = image_to_volume(im, {.surface = {.label = 1.0}});
    EXPECT_EQ(v.grid.voxel_size, 1.0);
    EXPECT_EQ(v.grid.dims, (std::array<int, 3>{64, 64, 63}));  // 25 × 2.5 + 1
    EXPECT_EQ(v.grid.origin, origin);
    const SphereError e = sphere_error(extract_surface(v), origin + c, R);
    EXPECT_LT(e.mean_radial, 0.4);  // the coarse staircase along z, interpolated
    EXPECT_LT(e.max_radial, 1.3);   // half of 2.5, plus rounding
    // A chosen voxel size: half as many samples along each axis.
    const Volume coarse = image_to_volume(im, {.surface = {.label = 1.0}, .voxel_size = 2.0});
    EXPECT_EQ(coarse.grid.dims, (std::array<int, 3>{32, 32, 32}));
}

TEST(ImageToVolume, RotatedAndReflectedAxesArePlacedInTheWorld) {
    // Axes turned by 30° about z, with z reversed (a left-handed frame, as many scanners write): the volume
    // is computed in the image's frame and its placement maps it back onto the world's ball.
    const double a = std::numbers::pi / 6, h = 0.8;
    const std::array<Vec3d, 3> axes{Vec3d{std::cos(a), std::sin(a), 0} * h, Vec3d{-std::sin(a), std::cos(a), 0} * h,
                                    Vec3d{0, 0, -h}};
    const Vec3d origin{-10, -12, 30};
    const Vec3d c = origin + axes[0] * 24.3 + axes[1] * 25.1 + axes[2] * 23.7;  // a world point inside the grid
    const double R = 14.0;
    const ScalarImage im = make_image({50, 50, 50}, axes, origin, [&](Vec3d x) { return norm(x - c) - R; });
    const Volume v = image_to_volume(im);
    const Placement& p = v.grid.placement;
    ASSERT_FALSE(p.is_identity());
    EXPECT_TRUE(p.reflects());
    // Every sample is where the image says.
    for (const std::array<int, 3> s : {std::array<int, 3>{0, 0, 0}, {49, 0, 0}, {3, 17, 42}, {49, 49, 49}}) {
        const Vec3d want = origin + axes[0] * double(s[0]) + axes[1] * double(s[1]) + axes[2] * double(s[2]);
        const Vec3d got = p.point(v.grid.world(Vec3d{double(s[0]), double(s[1]), double(s[2])}));
        EXPECT_LT(norm(got - want), 1e-9);
    }
    const SphereError e = sphere_error(extract_surface(v), c, R, p);
    EXPECT_LT(e.max_radial, 0.05 * R);
    EXPECT_LT(e.normal_deg, 3.0);  // the faces, turned over by the reflection, face out
}

TEST(ImageToVolume, ALabelMapGivesTheSurfaceOfOneLabel) {
    // Labels 0 (background), 3 and 5: two balls; label 5 gives the second ball only.
    const Vec3d c3{12, 16, 16}, c5{28, 16, 16};
    const ScalarImage im = make_image({40, 32, 32}, kUnitAxes, {}, [&](Vec3d x) {
        return norm(x - c3) < 6 ? 3 : norm(x - c5) < 7 ? 5 : 0;
    });
    EXPECT_FALSE(binary_mask_label(im));
    const Volume v = image_to_volume(im, {.surface = {.label = 5.0}});
    EXPECT_LT(v.value(28, 16, 16), -5.0);  // the centre of ball 5, 7 voxels deep
    EXPECT_GT(v.value(12, 16, 16), 5.0);   // ball 3 is outside
    const SphereError e = sphere_error(extract_surface(v), c5, 7);
    EXPECT_LT(e.max_radial, 0.6);
}

TEST(ImageToVolume, BadImagesAreRefusedWithTheReason) {
    ScalarImage im = make_image({8, 8, 8}, kUnitAxes, {}, [](Vec3d) { return 1.0; });
    const auto message = [](auto f) {
        try {
            f();
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string("no exception");
    };
    EXPECT_NE(message([&] { image_to_volume(im, {.surface = {.label = 1.0}}); }).find("holds no surface"),
              std::string::npos);
    EXPECT_NE(message([&] { image_to_volume(im, iso_options(0.5, false)); }).find("holds no surface"),
              std::string::npos);
    ScalarImage sheared = im;
    sheared.axes[1] = Vec3d{0.5, 1, 0};
    EXPECT_NE(message([&] { image_to_volume(sheared); }).find("not orthogonal"), std::string::npos);
    ScalarImage short_values = im;
    short_values.values.pop_back();
    EXPECT_NE(message([&] { image_to_volume(short_values); }).find("values"), std::string::npos);
    ScalarImage nan = im;
    nan.values[5] = std::nanf("");
    EXPECT_NE(message([&] { image_to_volume(nan); }).find("sample 5"), std::string::npos);
    EXPECT_NE(message([&] {
                  ImageToVolumeOptions o;
                  o.voxel_size = -1;
                  image_to_volume(im, o);
                  ;
              }).find("voxel_size"),
              std::string::npos);
    // binary masks: two values, one of them 0
    ScalarImage two = im;
    two.values[3] = 0;
    EXPECT_EQ(binary_mask_label(two), 1.0);
    two.values[4] = 2;
    EXPECT_FALSE(binary_mask_label(two));
    EXPECT_FALSE(binary_mask_label(im));
}

}  // namespace
}  // namespace normalflow
