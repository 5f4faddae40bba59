#pragma once
/// \file vdb_io.h
/// Reading and writing OpenVDB (.vdb) files (OpenVDB 10, MPL-2.0). OpenVDB types stay in the .cpp.

#include <string>

#include "core/volume.h"

namespace normalflow {

/// Reads the first FloatGrid of a .vdb file into a sparse Volume.
///
/// Level sets (and grids of unknown class, taken as signed distances, negative inside) are copied
/// exactly: every VDB leaf becomes a stored 8^3 block with its 512 values, every other block a tile
/// whose sign is the grid's value there; background = the grid's background, half_width =
/// background / h. Fog volumes (density, larger inside) are first rebuilt as a level set of the
/// 0.5 iso-surface with a half width of 3 voxels (openvdb::tools::levelSetRebuild).
/// The grid extent is the normalflow_dims metadata written by write_vdb, else the bounding box of
/// all leaves and active values, with its minimum rounded down to a multiple of 8 (so leaves map
/// onto blocks). The transform must be linear with a uniform positive scale h and orthogonal axes: an
/// axis-aligned one gives the grid's origin in world units; a rotated or reflected one gives the grid's
/// frame (origin = h × the extent's first index) and its Placement (the axes' directions, the world
/// position of index (0, 0, 0)).
///
/// \throw IoError if the file cannot be opened; InvalidInput naming the file for: not a VDB file,
///        truncated or corrupt data, no float grid, an empty grid, a non-uniform / sheared /
///        non-linear transform, a non-positive background, NaN/Inf values, or an extent too large;
///        IoError if OpenVDB crashes on the file. The file is read by OpenVDB in a forked child
///        (io/util/isolate.h) that sends back the grid's tiles and leaves; this process rebuilds it.
///        The volume read passes Volume::check.
/// Cost: O(#leaves * 512 + #blocks of the extent). Call of openvdb::initialize() once (call_once).
Volume read_vdb(const std::string& path);

/// Writes v as a .vdb file holding one FloatGrid named "surface", class GRID_LEVEL_SET, background
/// v.background, a linear transform with voxel size h and translation v.grid.origin (so index
/// (i, j, k) is our sample (i, j, k)) — rotated and translated by v.grid.placement when it is not the
/// identity, so the grid lies where its file of origin said, metadata normalflow_dims and normalflow_half_width.
/// Stored blocks become leaves (values with |phi| < background active), inside tiles become
/// inactive -background tiles; the tree is then pruned. Written atomically (temporary file + rename).
/// \throw InvalidInput (Volume::check) if v breaks its invariants (empty grid, non-positive voxel
///        size or background, inconsistent blocks, ...); NumericalError for a NaN/Inf sample; IoError
///        if the file cannot be written.
/// With normals (the engine's filtered normal map, smooth_volume's normal_map, on v's grid), a second grid
/// "normals": a Vec3SGrid of unit vectors in world space (covariant, normalised), active where the map is
/// defined.
void write_vdb(const std::string& path, const Volume& v, const NormalMap* normals = nullptr);

}  // namespace normalflow
