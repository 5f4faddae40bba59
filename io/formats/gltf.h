#pragma once
/// \file gltf.h
/// A dependency-free writer for uncompressed binary glTF 2.0 (.glb) triangle meshes.
/// (Reading glTF/GLB, and Draco-compressed GLB, live in io/draco/draco_io.h.)

#include <string>

#include "core/mesh.h"

namespace normalflow {

/// The material every normalflow glTF carries: a plain dielectric (metallicFactor 0, roughness 0.6,
/// light grey base colour, which vertex colours multiply), so viewers without an environment map
/// do not draw the surface black as they do for glTF's default (fully metallic) material.
inline constexpr const char* kGltfMaterial =
    R"({"name":"normalflow","pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1],"metallicFactor":0,)"
    R"("roughnessFactor":0.6}})";

/// sRGB-encoded colour component in [0, 1] to linear (glTF's COLOR_0 is linear) and back.
float srgb_to_linear(float c);
float linear_to_srgb(float c);

/// Writes m as a binary glTF 2.0 file (GLB): a 12-byte header, a JSON chunk and a BIN chunk holding
/// one buffer with FLOAT VEC3 positions (accessor with exact min/max), then the attributes m has:
/// NORMAL (FLOAT VEC3, unit length; zero normals written as +z), COLOR_0 (FLOAT VEC4, linear: the
/// sRGB bytes converted), TEXCOORD_0 (FLOAT VEC2, v flipped to glTF's top-left origin), then
/// UNSIGNED_INT triangle indices; one scene, one node (identity transform), one mesh, one TRIANGLES
/// primitive with kGltfMaterial.
/// Every chunk is padded to 4 bytes (JSON with spaces, BIN with zeros), all numbers little-endian.
/// Written atomically (temporary file + rename).
/// \param path  output file (any extension; .glb is customary)
/// \param m     indexed triangles; unreferenced points are written as well
/// \throw InvalidInput if m has no points or no triangles, a non-finite coordinate, an index out of
///        range, attribute arrays of the wrong size, or is too large for GLB's 32-bit lengths (about 4 GiB); IoError if the file cannot
///        be written.
/// Cost: O(#V + #F) time, one pass; no extra copy of the mesh. Single-threaded.
void write_glb(const std::string& path, const Mesh& m);

}  // namespace normalflow
