#pragma once
/// \file gltf_check.h
/// Structural validation of a glTF 2.0 asset (.gltf or .glb) BEFORE a third-party decoder (Draco's
/// glTF reader) sees it, so that malformed accessors give a clear InvalidInput instead of an
/// out-of-bounds read inside the decoder (issue 7, fuzz finding glb-e1f699a6).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace normalflow {

/// Checks the JSON of a glTF 2.0 asset against its buffers.
///
/// Checks, in the spirit of the Khronos glTF validator (a subset):
/// - the JSON parses (nesting depth <= 64) and its top level is an object;
/// - every buffer has an integer byteLength >= 1, and its data (the GLB BIN chunk for a buffer without
///   uri, a base64 data: URI, or a file relative to base_dir) holds at least byteLength bytes;
/// - every bufferView names an existing buffer and lies inside it (byteOffset + byteLength <=
///   buffer.byteLength); byteStride, when given, is a multiple of 4 in [4, 252];
/// - every accessor has a valid componentType (5120, 5121, 5122, 5123, 5125, 5126) and type (SCALAR,
///   VEC2..4, MAT2..4), count >= 1, an existing bufferView, and byteOffset + (count - 1) * stride +
///   element size <= bufferView.byteLength (stride = byteStride or the element size); sparse accessors
///   are refused;
/// - every mesh primitive refers to existing accessors; an uncompressed primitive's indices are
///   SCALAR unsigned byte/short/int, and each index value is < the POSITION accessor's count; a
///   KHR_draco_mesh_compression extension names an existing bufferView and integer attribute ids;
/// - nodes refer to existing meshes and nodes; scenes to existing nodes.
/// \param json      the JSON text (the whole .gltf file, or the JSON chunk of a .glb)
/// \param glb_bin   the GLB BIN chunk (buffer 0 without uri), or nullopt for a .gltf file
/// \param base_dir  folder against which relative buffer URIs are resolved ("" = current folder)
/// \param who       message prefix naming the file, e.g. "read_gltf: scene.glb"
/// \throw InvalidInput "<who>: accessor 1: count 24 with stride 4 needs 96 bytes from byte 0, but
///        bufferView 1 has 72" and the like; IoError when an external buffer file cannot be read.
/// Cost: linear in the JSON size plus one pass over the index data. Single-threaded.
void check_gltf(std::string_view json, std::optional<std::string_view> glb_bin, const std::string& base_dir,
                const std::string& who);

}  // namespace normalflow
