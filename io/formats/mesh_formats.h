#pragma once
/// \file mesh_formats.h
/// Readers and writers for the mesh formats that need no third-party library: Wavefront OBJ,
/// Stanford PLY (ASCII, binary little and big endian), OFF and STL (ASCII and binary).
/// Most callers want read_mesh / write_mesh in io/io.h, which dispatch on the file extension.
///
/// Readers return a polygon soup (see Mesh): every face in the file is kept in file order,
/// polygons with more than 3 corners are split into a triangle fan (0,k,k+1) and counted in
/// ReadInfo::polygons_split, points are not merged (STL gives 3 points per facet), orientation is
/// not changed. Per-vertex normals, colours and texture coordinates are read into the Mesh's
/// attributes where the format has them (OBJ, PLY; OFF and STL extras are skipped) and written by the
/// writers of the formats that can hold them (OBJ: no alpha; PLY: all; OFF and STL: none).
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

/// Reads a Wavefront OBJ file: `v x y z [w | r g b]`, `vt u [v]`, `vn x y z` and `f` lines with
/// corners `v`, `v/vt`, `v//vn` or `v/vt/vn`; negative indices count back from the last one read.
/// Colours: the common `v x y z r g b` extension, in 0..1 (or 0..255 when a value exceeds 1); a
/// vertex line without one is white. OBJ refers to texture coordinates and normals per face corner,
/// normalflow keeps them per vertex: a vertex takes those of its corners, and a corner whose (vt, vn)
/// contradicts an earlier corner of the same vertex gets a copy of the vertex, appended after the
/// file's vertices (a texture seam), with a warning; a corner without a reference matches any. A vt or
/// vn reference out of range drops that attribute with a warning (the geometry is still read). Other
/// statements (o, g, s, usemtl, mtllib, l, p, ...) are ignored.
/// \param info if not null, receives format "obj", counts and warnings.
Mesh read_obj(const std::string& path, ReadInfo* info = nullptr);

/// Reads a PLY file (ascii, binary_little_endian, binary_big_endian). The `vertex` element must
/// have x, y, z of any scalar type; the `face` element a list property `vertex_indices` or
/// `vertex_index` with any count and index types. Vertex attributes, read when all their components
/// are present: normals nx ny nz (or normal_x ...), colours red green blue [alpha] (or r g b [a],
/// diffuse_red ...; integer types as 0..255, ushort as 0..65535, float as 0..1) and texture
/// coordinates s t (or u v, texture_u texture_v, texture_s texture_t). Other elements and properties
/// are skipped.
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

/// Writes OBJ (`v` and `f` lines, 1-based; with the mesh's attributes, `v x y z r g b` colours, `vt`
/// and `vn` lines and `f a/a/a` corners).
void write_obj(const std::string& path, const Mesh& m, const WriteOptions& opt = {});
/// Writes PLY: binary little endian (default) or ascii (opt.binary = false); float x,y,z, then the
/// mesh's attributes (float nx,ny,nz; uchar red,green,blue,alpha; float s,t) and
/// `list uchar int vertex_indices`.
void write_ply(const std::string& path, const Mesh& m, const WriteOptions& opt = {});
/// Writes OFF (0-based indices).
void write_off(const std::string& path, const Mesh& m, const WriteOptions& opt = {});
/// Writes STL: binary (default; the 80-byte header never starts with "solid") or ASCII
/// (opt.binary = false). Facet normals are computed from the triangles (zero for degenerate ones).
/// Shared vertices are written once per triangle, as STL requires.
void write_stl(const std::string& path, const Mesh& m, const WriteOptions& opt = {});

}  // namespace normalflow
