#pragma once
/// \file image_to_volume.h
/// From a dense scalar image (a CT or MRI scan, a probability map, a segmentation's label map, a
/// binary mask) to normalflow's volume: a narrow-band signed distance on isotropic voxels, placed in
/// the image's world. What the readers of io/formats (NRRD, NIfTI) return, and how the pipeline turns
/// it into what the engine smooths.

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include "core/progress.h"
#include "core/vec.h"
#include "core/volume.h"

namespace normalflow {

/// A dense 3-D scalar image as a volume file holds it: sample (i, j, k) has the value
/// values[i + dims[0] * (j + dims[1] * k)] and sits in the world at origin + i·axes[0] + j·axes[1] +
/// k·axes[2]. The axes carry the spacing (their lengths) and the orientation (their directions); they
/// need not be of equal length, and must be orthogonal for image_to_volume.
struct ScalarImage {
    std::array<int, 3> dims{0, 0, 0};
    std::vector<float> values;
    Vec3d origin;
    std::array<Vec3d, 3> axes{Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};

    std::size_t sample_count() const { return std::size_t(dims[0]) * std::size_t(dims[1]) * std::size_t(dims[2]); }
    float at(int i, int j, int k) const {
        return values[std::size_t(i) + std::size_t(dims[0]) * (std::size_t(j) + std::size_t(dims[1]) * std::size_t(k))];
    }
};

/// What the image's values mean: where the surface is, and which side is inside.
struct ImageSurface {
    /// The surface is {value == iso}, inside where value < iso (a signed distance, negative inside),
    /// or where value > iso with negate (an intensity, a density, a probability).
    double iso = 0.0;
    bool negate = false;
    /// A label map: inside is {value == label} (any other value is outside); iso and negate are then
    /// not used. The surface is the 0.5 level of the label's indicator, interpolated trilinearly.
    std::optional<double> label;
};

/// How image_to_volume builds the volume.
struct ImageToVolumeOptions {
    ImageSurface surface;
    /// World units, >= 0: the voxel size of the volume; 0: the image's smallest spacing. The image is
    /// resampled (trilinearly) when its spacing is not this in every direction.
    double voxel_size = 0.0;
};

/// The Placement of a grid whose axes point along `axes` (orthogonal, any lengths; callers check both),
/// with translation `origin`: the unit directions made orthonormal to rounding (Gram–Schmidt: the first
/// axis kept, the second made orthogonal to it, the third their cross product turned to the axes' own
/// handedness, so a left-handed frame stays a reflection). What image and volume readers place their
/// grids by.
Placement placement_from_axes(const std::array<Vec3d, 3>& axes, const Vec3d& origin);

/// Checks an image: dims >= 1, values.size() == dims product, finite values, origin and axes, axes of
/// non-zero length and orthogonal (within 1e-4 of a right angle).
/// \throw InvalidInput "who: ..." naming the problem.
void check_image(const ScalarImage& image, const char* who);

/// Turns an image into a narrow-band signed distance volume (world units, negative inside) of the surface
/// options.surface names.
///
/// Method: the image's value f becomes a field F that is negative inside (F = f − iso, iso − f with
/// negate, 0.5 − [f == label] for a label); F is resampled trilinearly onto an isotropic grid of
/// voxel size options.voxel_size in the image's own frame (skipped when the spacing already is that);
/// then F is made a signed distance: samples next to a sign change take F/|∇F| bounded by the distance to
/// the crossings along the axes (so a binary mask's samples lie half a voxel from its staircase), the
/// others the eikonal solution from them (the engine's reinitialisation).
/// Placement: the grid's frame is the image's, its axes directions as Placement::rotation (with a
/// reflection where the image's axes are left-handed) and its first sample's world position as the
/// translation; an axis-aligned image with positive axes keeps the identity placement and its origin.
/// \throw InvalidInput for a bad image (check_image) or options, or an image that holds no surface
///        (every sample on one side).
/// The result's band is 8 voxels each side (half_width 8), exact distances throughout.
/// Cost: O(samples of the image + samples of the grid); memory: the grid's dense field as floats
/// once, then the band. Deterministic; threads (TBB) do not change the result.
Volume image_to_volume(const ScalarImage& image, const ImageToVolumeOptions& options = {},
                       Progress* progress = nullptr);

/// Whether an image is a binary mask: exactly two distinct values, one of them 0. Returns the other
/// value (the label of the inside), else nothing. Cost: one pass.
std::optional<double> binary_mask_label(const ScalarImage& image);

}  // namespace normalflow
