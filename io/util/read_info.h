#pragma once
/// \file read_info.h
/// What a mesh reader found in the file (ReadInfo): shared by every reader in io/formats, io/draco and
/// the read_mesh dispatch in io/io.h.

#include <cstddef>
#include <string>
#include <vector>

namespace normalflow {

/// What a reader found in the file, before any repair.
struct ReadInfo {
    std::string format;                 ///< "obj", "ply-ascii", "ply-binary-le", "stl-binary", ...
    std::size_t file_vertices = 0;      ///< points in the file
    std::size_t file_faces = 0;         ///< polygons in the file (before triangulation)
    std::size_t polygons_split = 0;     ///< faces with more than 3 corners, split into triangles (fan)
    std::vector<std::string> warnings;  ///< oddities handled (e.g. "12 faces had more than 3 corners")
};

}  // namespace normalflow
