#pragma once
/// \file volume_constraint.h
/// Keeping the enclosed volume through a refit: a uniform shift of φ, the level-set counterpart
/// of the centroid and volume restoration mesh filters apply after their vertex update.

#include <algorithm>
#include <array>
#include <cmath>

#include "normals/stages/stage.h"

namespace normalflow::engine {

/// The volume inside the zero level over the active samples, voxels: Σ clamp(0.5 − φ, 0, 1)
/// (each sample a unit cell, the surface crossing it linearly). Only differences are meaningful:
/// samples outside the active mask are not counted. Summed per block, then in block order.
double active_volume(const Band& band);

/// active_volume over the active samples of the blocks lo <= (bi, bj, bk) < hi (block coordinates of the band's
/// grid) only, and the slope of that volume against a uniform shift of φ (the samples within half a voxel of the
/// surface): a brick's share of the whole surface's (smooth_in_bricks).
void window_volume(const Band& band, const std::array<int, 3>& lo, const std::array<int, 3>& hi, double& volume,
                   double& slope);

/// A sample's share of the volume inside the surface (φ in voxels): 1 inside, 0 outside, linear over the half voxel
/// either side of the surface: the piecewise-linear volume that active_volume sums and restore_volume restores.
inline float inside_share(float phi) { return std::clamp(0.5f - phi, 0.0f, 1.0f); }
/// Whether a sample's share changes with a uniform shift of φ (the volume's slope counts it).
inline bool on_slope(float phi) { return std::abs(phi) < 0.5f; }

/// Newton steps restore_volume takes (and smooth_in_bricks after it, over the whole surface).
inline constexpr int kVolumeNewtonSteps = 2;

/// Shifts φ on every allocated sample by one constant so that active_volume(band) comes back to
/// `target` (kVolumeNewtonSteps Newton steps on the piecewise-linear volume; none when no sample is within half
/// a voxel of the surface). Returns the shift, voxels (positive: the surface moved outwards).
float restore_volume(Band& band, double target);

}  // namespace normalflow::engine
