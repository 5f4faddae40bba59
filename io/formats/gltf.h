#pragma once
/// \file gltf.h
/// A dependency-free writer for uncompressed binary glTF 2.0 (.glb) triangle meshes.
/// (Reading glTF/GLB, and Draco-compressed GLB, live in io/draco/draco_io.h.)

#include <string>

#include "core/mesh.h"

namespace normalflow {

/// Writes m as a binary glTF 2.0 file (GLB): a 12-byte header, a JSON chunk and a BIN chunk holding
/// one buffer with FLOAT VEC3 positions (accessor with exact min/max) followed by UNSIGNED_INT
/// triangle indices; one scene, one node (identity transform), one mesh, one TRIANGLES primitive.
/// Every chunk is padded to 4 bytes (JSON with spaces, BIN with zeros), all numbers little-endian.
/// Written atomically (temporary file + rename).
/// \param path  output file (any extension; .glb is customary)
/// \param m     indexed triangles; unreferenced points are written as well
/// \throw InvalidInput if m has no points or no triangles, a non-finite coordinate, an index out of
///        range, or is too large for GLB's 32-bit lengths (about 4 GiB); IoError if the file cannot
///        be written.
/// Cost: O(#V + #F) time, one pass; no extra copy of the mesh. Single-threaded.
void write_glb(const std::string& path, const Mesh& m);

}  // namespace normalflow
