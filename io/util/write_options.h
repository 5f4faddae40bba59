#pragma once
/// \file write_options.h
/// Options for writing meshes (WriteOptions), shared by the writers in io/formats and io/draco and by
/// write_mesh in io/io.h. Plain structs: they exist in every build, with or without Draco.

namespace normalflow {

/// Options for Draco compression (write_drc, write_draco_glb in io/draco/draco_io.h, and write_mesh for
/// .drc and, in builds with Draco, .glb).
struct DracoOptions {
    int position_bits = 14;     ///< bits per position axis, 1..30 (0 = lossless float storage is NOT supported)
    int normal_bits = 10;       ///< bits per normal component, 1..30 (meshes with normals: smooth's output,
                                ///< or an input that had them)
    int texcoord_bits = 12;     ///< bits per texture coordinate component, 1..30
    int compression_level = 7;  ///< 0 (fastest, largest) .. 10 (slowest, smallest); Draco speed = 10 - level
    bool fallback = false;      ///< write_draco_glb only: also store uncompressed (dequantized) positions and
                                ///< indices, and list KHR_draco_mesh_compression as used but not required,
                                ///< so viewers without Draco can still show the mesh (file grows ~4x)
};

/// How write_mesh writes a .glb file.
enum class GlbEncoding {
    Plain,  ///< uncompressed binary glTF (write_glb), in every build
    Draco,  ///< KHR_draco_mesh_compression with WriteOptions::draco (write_draco_glb) in builds with
            ///< Draco; a plain GLB in builds without
};

/// Options for writing meshes.
struct WriteOptions {
    bool binary = true;                    ///< PLY/STL: binary (default) or ASCII
    GlbEncoding glb = GlbEncoding::Plain;  ///< .glb: plain (default) or Draco-compressed
    DracoOptions draco{};                  ///< .drc, and .glb with GlbEncoding::Draco
};

}  // namespace normalflow
