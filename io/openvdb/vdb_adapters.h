#pragma once
/// \file vdb_adapters.h
/// In-memory adapters between normalflow's Volume and OpenVDB grids, without a file: for an application
/// that holds OpenVDB grids already (Houdini, Blender, a VFX pipeline). This header includes OpenVDB's:
/// the application compiles and links against OpenVDB itself (Debian libopenvdb-dev, the version this
/// build of normalflow::openvdb was built with). vdb_io.h reads and writes the same grids as files.

#include <openvdb/openvdb.h>

#include <string>

#include "core/volume.h"

namespace normalflow {

/// The level set of v as a new FloatGrid: what write_vdb writes (named "surface", class GRID_LEVEL_SET,
/// background v.background, v's blocks as leaves with |φ| < background active, inside tiles as inactive
/// −background tiles, pruned; the transform from v.grid and its placement).
/// \throw InvalidInput (Volume::check) for a volume that breaks its invariants.
openvdb::FloatGrid::Ptr to_openvdb(const Volume& v);

/// A filtered normal map (smooth_volume's normal_map, on v's grid) as a new Vec3SGrid "normals": unit
/// vectors in world space, covariant and normalised, active where the map is defined; v's transform.
/// \throw InvalidInput for a normal map that is not on v's grid or breaks the Volume invariants.
openvdb::Vec3SGrid::Ptr to_openvdb(const NormalMap& normals, const Volume& v);

/// A FloatGrid as a Volume: what read_vdb returns for the same grid in a file (a level set copied exactly,
/// a fog volume rebuilt as the level set of its 0.5 iso-surface, the transform's rotation as the grid's
/// placement). The grid is not changed (the conversion works on a copy of its tree).
/// \throw InvalidInput "who: ..." for a grid read_vdb refuses (an empty grid, a non-uniform, sheared or
///        non-linear transform, a non-positive background, NaN/Inf values, an extent too large).
Volume from_openvdb(const openvdb::FloatGrid& grid, const std::string& who = "from_openvdb");

}  // namespace normalflow
