#pragma once
/// \file io.h
/// Reading and writing meshes and volumes by file extension, over whatever adapters this build
/// has (formats always; Draco for .drc/.gltf/.glb reading; OpenVDB for .vdb).
///
/// Every writer writes to a temporary file beside the target and renames it into place only
/// when complete, so a failed run never leaves a partial file and never damages an existing one.
/// Every error is thrown (IoError for the file system, InvalidInput for bad contents) with a
/// message that names the file and the problem.

#include <array>
#include <optional>
#include <string>

#include "core/mesh.h"
#include "core/volume.h"
#include "io/util/read_info.h"      // ReadInfo
#include "io/util/write_options.h"  // WriteOptions, DracoOptions

namespace normalflow {

enum class MeshFormat { Unknown, Obj, Ply, Off, Stl, Gltf, Glb, Drc };

/// The format implied by path's extension (case-insensitive); Unknown if none matches.
MeshFormat mesh_format_from_path(const std::string& path);

/// Reads a mesh as a polygon soup: every face is kept (polygons are split into a triangle fan),
/// points are not merged, orientation is not changed.
/// \throw IoError if the file cannot be opened or read; InvalidInput for unknown extensions and bad
///        contents (truncation, garbage, NaN/Inf coordinates, indices out of range, faces with < 3
///        corners, no faces).
Mesh read_mesh(const std::string& path, ReadInfo* info = nullptr);

/// Writes m in the format implied by path's extension, atomically (temporary file + rename):
/// .obj/.off, .ply/.stl (opt.binary), .drc (write_drc with opt.draco; needs Draco) and .glb: a plain
/// GLB (write_glb) by default; with opt.glb = GlbEncoding::Draco, in builds with Draco, a
/// KHR_draco_mesh_compression GLB (write_draco_glb with opt.draco). Callers need not dispatch on the
/// extension themselves.
/// \throw InvalidInput for unknown extensions, .gltf, .drc without Draco, invalid meshes or Draco
///        options out of range; IoError if the file cannot be written.
void write_mesh(const std::string& path, const Mesh& m, const WriteOptions& opt = {});

/// True for the volume files read_volume reads: .vdb, .nrrd, .nhdr, .nii and .nii.gz.
bool is_volume_path(const std::string& path);
/// True for the volume files write_volume writes: .vdb and .nrrd.
bool is_volume_output_path(const std::string& path);
/// True for .vdb paths (case-insensitive).
bool is_vdb_path(const std::string& path);

/// Reads a signed distance volume from .nrrd or .vdb (the first float grid): read_volume with no VolumeInput.
Volume read_volume(const std::string& path);

/// How read_volume reads the values of a dense volume file (.nrrd, .nhdr, .nii, .nii.gz): the command
/// line's --iso, --label, --negate and --voxel-size.
struct VolumeInput {
    /// A scalar image (CT, MRI, a probability or a density): the surface is {value == iso}, inside where the
    /// value is above it, as isosurface tools take it (negate: below it).
    std::optional<double> iso;
    std::optional<double> label;  ///< a label map: the surface of {value == label} (ImageSurface::label)
    /// Flips the inside: with iso, inside is below it; without, the file's signed distance is positive inside.
    bool negate = false;
    double voxel_size = 0;  ///< > 0: resample to this voxel size (world units); 0: the smallest spacing
};

/// What read_volume found and did.
struct VolumeReadInfo {
    std::string format;                      ///< "nrrd", "nifti" or "vdb"
    std::array<int, 3> dims{0, 0, 0};        ///< the file's samples along its axes
    std::array<double, 3> spacing{0, 0, 0};  ///< the file's spacing along its axes, world units
    std::string surface;                     ///< how the values were read: "signed distance", "iso 0.5", "label 3", ...
    bool resampled = false;                  ///< resampled to isotropic voxels (image_to_volume)
    bool placed = false;                     ///< rotated or reflected axes: the grid carries a Placement
};

/// Reads a volume file as a narrow-band signed distance volume, negative inside.
/// - .vdb: the first float grid (read_vdb): a level set as it is, a fog volume at its 0.5 level.
///   VolumeInput must be empty (a level set has its surface already).
/// - .nrrd, .nhdr, .nii, .nii.gz: a dense image (read_nrrd_image, read_nifti), made a signed distance
///   by image_to_volume with in.iso (inside above it) / in.label / in.negate, resampled to isotropic voxels (in.voxel_size, or
///   the smallest spacing) and placed where the file says (Grid::placement for rotated or reflected axes).
///   With neither iso nor label: a binary mask (two values, one of them 0) is the mask of its other value;
///   otherwise a NRRD holds a signed distance (read exactly by read_nrrd when its voxels are isotropic), and
///   a NIfTI file is refused with a message that asks for --iso or --label.
/// 	hrow InvalidInput naming the file (bad contents, contradicting options, no surface); IoError.
Volume read_volume(const std::string& path, const VolumeInput& in, VolumeReadInfo* info = nullptr);

/// Writes v as .nrrd (dense, band values and ±background elsewhere) or .vdb (sparse level set; with normals,
/// also the filtered normal map as a vector grid, write_vdb). A normal map needs .vdb.
void write_volume(const std::string& path, const Volume& v, const NormalMap* normals = nullptr);

}  // namespace normalflow
