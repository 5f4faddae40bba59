#pragma once
/// \file draco_io.h
/// glTF 2.0 (.gltf, .glb) reading and Draco (.drc, Draco-compressed .glb) reading and writing, through
/// Google's Draco library (Apache-2.0; Debian's build with glTF support). Draco types stay in the .cpp.
///
/// Draco stores positions quantized to `position_bits` bits per axis over the bounding box, so a
/// written point moves by at most bbox_extent / (2^bits - 1) / 2 per axis (about 1.5e-4 of the box at
/// 14 bits), and it may reorder points and triangles (triangle orientation is kept).

#include <string>

#include "core/mesh.h"
#include "io/util/read_info.h"
#include "io/util/write_options.h"

namespace normalflow {

/// Reads all triangle primitives of all nodes of the default scene of a .gltf or .glb file, with
/// each node's transform (matrix or TRS, composed down the node tree) applied to the positions.
/// Primitives compressed with KHR_draco_mesh_compression are decoded. POSITION is kept, and NORMAL,
/// COLOR_0 (linear, converted to 8-bit sRGB) and TEXCOORD_0 (v turned upward) when present.
/// Without attributes, equal positions are merged into one point (Draco's glTF reader does this);
/// with them, every glTF vertex is one (a seam keeps its two sides).
/// A .glb container is checked first (magic, version 2, length, chunk layout) for clear messages.
/// \param info  optional: format ("gltf"/"glb"), file_vertices (points after merging), file_faces
/// \throw IoError if the file cannot be opened or read; InvalidInput naming the file for anything
///        else: truncated or garbage files, non-triangle primitives, missing buffers, no triangles,
///        non-finite positions, and anything io/draco/gltf_check.h refuses (accessors outside their
///        buffer views, buffer views outside their buffers, indices past the last point, ...);
///        IoError if Draco crashes on the file (it decodes in a forked child, io/util/isolate.h).
/// Cost: linear in the file size, plus one fork(). Single-threaded.
Mesh read_gltf(const std::string& path, ReadInfo* info = nullptr);

/// Reads a Draco (.drc) triangle mesh: POSITION, and NORMAL, COLOR (8-bit sRGB as draco_encoder stores
/// a PLY's) and TEX_COORD when present, dequantized to float.
/// \param info  optional: format "drc", file_vertices, file_faces
/// \throw IoError if the file cannot be opened or read; InvalidInput naming the file for truncated or
///        garbage data, point clouds (no faces), a missing POSITION attribute, non-finite positions;
///        IoError if Draco crashes on the file (it decodes in a forked child, io/util/isolate.h).
Mesh read_drc(const std::string& path, ReadInfo* info = nullptr);

/// Writes m as a Draco (.drc) bitstream (edgebreaker connectivity coding, falling back to sequential
/// coding for meshes edgebreaker rejects), atomically (temporary file + rename), with m's normals
/// (opt.normal_bits), colours (8-bit sRGB, exact) and texture coordinates (opt.texcoord_bits).
/// \throw InvalidInput for empty meshes, out-of-range indices, non-finite positions or options out of
///        range; IoError if the file cannot be written.
void write_drc(const std::string& path, const Mesh& m, const DracoOptions& opt = {});

/// Writes m as a binary glTF 2.0 file whose primitive is compressed with KHR_draco_mesh_compression
/// (through draco::GltfEncoder; with opt.fallback, a hand-built GLB that also holds uncompressed
/// buffers), atomically, with kGltfMaterial and m's attributes as NORMAL, COLOR_0 (linear floats
/// quantised to 12 bits, so every sRGB byte comes back) and TEXCOORD_0. Read it back with read_gltf.
/// \throw as write_drc.
void write_draco_glb(const std::string& path, const Mesh& m, const DracoOptions& opt = {});

}  // namespace normalflow
