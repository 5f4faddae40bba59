#include "io/io.h"

#include <filesystem>
#include <string_view>

#include "core/errors.h"
#include "io/formats/gltf.h"
#include "io/formats/mesh_formats.h"
#include "io/formats/nrrd.h"

#if NORMALFLOW_HAS_DRACO
#include "io/draco/draco_io.h"
#endif
#if NORMALFLOW_HAS_OPENVDB
#include "io/openvdb/vdb_io.h"
#endif

namespace normalflow {

namespace {

/// The extension of path, lower case, with its dot ("" if none).
std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext)
        if (c >= 'A' && c <= 'Z') c = char(c - 'A' + 'a');
    return ext;
}

std::string shown_extension(const std::string& path) {
    const std::string ext = std::filesystem::path(path).extension().string();
    return ext.empty() ? "no extension" : "extension '" + ext + "'";
}

[[noreturn, maybe_unused]] void no_support(std::string_view who, const std::string& path, std::string_view what,
                             std::string_view library) {
    throw InvalidInput(std::string(who) + ": " + path + ": " + std::string(what) + " needs " + std::string(library) +
                       ", and this build has no " + std::string(library) + " support");
}

}  // namespace

MeshFormat mesh_format_from_path(const std::string& path) {
    const std::string ext = lower_extension(path);
    if (ext == ".obj") return MeshFormat::Obj;
    if (ext == ".ply") return MeshFormat::Ply;
    if (ext == ".off") return MeshFormat::Off;
    if (ext == ".stl") return MeshFormat::Stl;
    if (ext == ".gltf") return MeshFormat::Gltf;
    if (ext == ".glb") return MeshFormat::Glb;
    if (ext == ".drc") return MeshFormat::Drc;
    return MeshFormat::Unknown;
}

Mesh read_mesh(const std::string& path, ReadInfo* info) {
    switch (mesh_format_from_path(path)) {
        case MeshFormat::Obj: return read_obj(path, info);
        case MeshFormat::Ply: return read_ply(path, info);
        case MeshFormat::Off: return read_off(path, info);
        case MeshFormat::Stl: return read_stl(path, info);
        case MeshFormat::Gltf:
        case MeshFormat::Glb:
#if NORMALFLOW_HAS_DRACO
            return read_gltf(path, info);
#else
            no_support("read_mesh", path, "reading glTF/GLB", "Draco");
#endif
        case MeshFormat::Drc:
#if NORMALFLOW_HAS_DRACO
            return read_drc(path, info);
#else
            no_support("read_mesh", path, "reading .drc", "Draco");
#endif
        case MeshFormat::Unknown: break;
    }
    throw InvalidInput("read_mesh: " + path + ": unknown mesh file " + shown_extension(path) +
                       " (expected .obj, .ply, .off, .stl, .gltf, .glb or .drc)");
}

void write_mesh(const std::string& path, const Mesh& m, const WriteOptions& opt) {
    switch (mesh_format_from_path(path)) {
        case MeshFormat::Obj: return write_obj(path, m, opt);
        case MeshFormat::Ply: return write_ply(path, m, opt);
        case MeshFormat::Off: return write_off(path, m, opt);
        case MeshFormat::Stl: return write_stl(path, m, opt);
        case MeshFormat::Glb:
#if NORMALFLOW_HAS_DRACO
            if (opt.glb == GlbEncoding::Draco) return write_draco_glb(path, m, opt.draco);  // KHR_draco_mesh_compression
#endif
            return write_glb(path, m);
        case MeshFormat::Gltf:
            throw InvalidInput("write_mesh: " + path + ": writing .gltf is not supported; use .glb");
        case MeshFormat::Drc:
#if NORMALFLOW_HAS_DRACO
            return write_drc(path, m, opt.draco);
#else
            no_support("write_mesh", path, "writing .drc", "Draco");
#endif
        case MeshFormat::Unknown: break;
    }
    throw InvalidInput("write_mesh: " + path + ": unknown mesh file " + shown_extension(path) +
                       " (expected .obj, .ply, .off, .stl, .glb or .drc)");
}

bool is_volume_path(const std::string& path) {
    const std::string ext = lower_extension(path);
    return ext == ".vdb" || ext == ".nrrd";
}

Volume read_volume(const std::string& path) {
    const std::string ext = lower_extension(path);
    if (ext == ".nrrd") return read_nrrd(path);
    if (ext == ".vdb") {
#if NORMALFLOW_HAS_OPENVDB
        return read_vdb(path);
#else
        no_support("read_volume", path, "reading .vdb", "OpenVDB");
#endif
    }
    throw InvalidInput("read_volume: " + path + ": unknown volume file " + shown_extension(path) +
                       " (expected .nrrd or .vdb)");
}

void write_volume(const std::string& path, const Volume& v) {
    const std::string ext = lower_extension(path);
    if (ext == ".nrrd") return write_nrrd(path, v);
    if (ext == ".vdb") {
#if NORMALFLOW_HAS_OPENVDB
        return write_vdb(path, v);
#else
        no_support("write_volume", path, "writing .vdb", "OpenVDB");
#endif
    }
    throw InvalidInput("write_volume: " + path + ": unknown volume file " + shown_extension(path) +
                       " (expected .nrrd or .vdb)");
}

}  // namespace normalflow
