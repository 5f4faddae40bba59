#pragma once
/// \file mesh_formats.h
/// Readers and writers for the mesh formats that need no third-party library: Wavefront OBJ,
/// Stanford PLY (ASCII, binary little and big endian), OFF and STL (ASCII and binary).
/// Most callers want read_mesh / write_mesh in io/io.h, which dispatch on the file extension.
///
/// Readers return a polygon soup (see Mesh): every face in the file is kept in file order,
/// polygons with more than 3 corners are split into a triangle fan (0,k,k+1) and counted in
/// ReadInfo::polygons_split, points are not merged (STL gives 3 points per facet), orientation is
/// not changed. Per-vertex extras (normals, colours, texture coordinates) are skipped.
///
/// Every reader reads the whole file into memory once and parses it with std::from_chars
/// (locale-independent). It validates as it goes and throws InvalidInput with one line naming the
/// reader, the file, the line (text formats) or the element (binary formats) and the problem:
/// empty or truncated file, garbage, NaN/Inf coordinates, face indices out of range, faces with
/// fewer than 3 corners, no faces, header counts the file size cannot hold (checked before
/// anything is allocated). A file that cannot be opened or read throws IoError.
///
/// Every writer validates the mesh first (at least one triangle, finite positions, indices in
/// range: InvalidInput otherwise) and writes through AtomicFile, so a failure never leaves a
/// partial file nor damages an existing one (IoError when the folder is not writable). Coordinates
/// are written exactly: float32 in binary formats, the shortest round-trip decimal in text formats,
/// so write then read gives bit-identical positions.
///
/// Cost: linear in the file size, single-threaded; about 10 ms for a 170k-face binary PLY.

#include <string>
#include <string_view>

#include "core/mesh.h"
#include "io/util/read_info.h"
#include "io/util/write_options.h"

namespace normalflow {

/// Reads a Wavefront OBJ file: `v x y z [w | r g b]` and `f` lines with corners `v`, `v/vt`,
/// `v//vn` or `v/vt/vn`; negative indices count back from the last vertex read. Other
/// statements (vt, vn, o, g, s, usemtl, mtllib, l, p, ...) are ignored.
/// \param info if not null, receives format "obj", counts and warnings.
Mesh read_obj(const std::string& path, ReadInfo* info = nullptr);

/// Reads a PLY file (ascii, binary_little_endian, binary_big_endian). The `vertex` element must
/// have x, y, z of any scalar type; the `face` element a list property `vertex_indices` or
/// `vertex_index` with any count and index types. Other elements and properties are skipped.
/// \param info format "ply-ascii", "ply-binary-le" or "ply-binary-be".
Mesh read_ply(const std::string& path, ReadInfo* info = nullptr);

/// Reads an OFF file (also COFF, NOFF, STOFF, ... : extra vertex data is ignored), with `#`
/// comments and optional colour values after a face's indices. Indices are 0-based.
Mesh read_off(const std::string& path, ReadInfo* info = nullptr);

/// Reads an STL file, ASCII or binary. A file whose size is exactly 84 + 50 n (n from bytes
/// 80..83) is binary even if it starts with "solid"; otherwise a file starting with "solid" is
/// ASCII. Every facet gives 3 new points (no merging). Facet normals are ignored.
/// \param info format "stl-binary" or "stl-ascii".
Mesh read_stl(const std::string& path, ReadInfo* info = nullptr);

/// The same readers over bytes already in memory; `name` is used in error messages.
Mesh read_obj_memory(std::string_view bytes, const std::string& name, ReadInfo* info = nullptr);
Mesh read_ply_memory(std::string_view bytes, const std::string& name, ReadInfo* info = nullptr);
Mesh read_off_memory(std::string_view bytes, const std::string& name, ReadInfo* info = nullptr);
Mesh read_stl_memory(std::string_view bytes, const std::string& name, ReadInfo* info = nullptr);

/// Writes OBJ (`v` and `f` lines, 1-based).
void write_obj(const std::string& path, const Mesh& m, const WriteOptions& opt = {});
/// Writes PLY: binary little endian (default) or ascii (opt.binary = false); float x,y,z and
/// `list uchar int vertex_indices`.
void write_ply(const std::string& path, const Mesh& m, const WriteOptions& opt = {});
/// Writes OFF (0-based indices).
void write_off(const std::string& path, const Mesh& m, const WriteOptions& opt = {});
/// Writes STL: binary (default; the 80-byte header never starts with "solid") or ASCII
/// (opt.binary = false). Facet normals are computed from the triangles (zero for degenerate ones).
/// Shared vertices are written once per triangle, as STL requires.
void write_stl(const std::string& path, const Mesh& m, const WriteOptions& opt = {});

}  // namespace normalflow
