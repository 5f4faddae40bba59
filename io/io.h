#pragma once
/// \file io.h
/// Reading and writing meshes and volumes by file extension, over whatever adapters this build
/// has (formats always; Draco for .drc/.gltf/.glb reading; OpenVDB for .vdb).
///
/// Every writer writes to a temporary file beside the target and renames it into place only
/// when complete, so a failed run never leaves a partial file and never damages an existing one.
/// Every error is thrown (IoError for the file system, InvalidInput for bad contents) with a
/// message that names the file and the problem.

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

/// True for .vdb and .nrrd paths.
bool is_volume_path(const std::string& path);

/// Reads a signed distance volume from .nrrd or .vdb (the first float grid).
Volume read_volume(const std::string& path);

/// Writes v as .nrrd (dense, band values and ±background elsewhere) or .vdb (sparse level set).
void write_volume(const std::string& path, const Volume& v);

}  // namespace normalflow
