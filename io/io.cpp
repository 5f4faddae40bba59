#include "io/io.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string_view>

#include "core/errors.h"
#include "io/formats/gltf.h"
#include "io/formats/mesh_formats.h"
#include "io/formats/nifti.h"
#include "io/formats/nrrd.h"
#include "sdf/image_to_volume.h"

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
            if (opt.glb == GlbEncoding::Draco)
                return write_draco_glb(path, m, opt.draco);  // KHR_draco_mesh_compression
#endif
            return write_glb(path, m);
        case MeshFormat::Gltf: throw InvalidInput("write_mesh: " + path + ": writing .gltf is not supported; use .glb");
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

namespace {

enum class VolumeKind { None, Vdb, Nrrd, Nifti };

VolumeKind volume_kind(const std::string& path) {
    const std::string ext = lower_extension(path);
    if (ext == ".vdb") return VolumeKind::Vdb;
    if (ext == ".nrrd" || ext == ".nhdr") return VolumeKind::Nrrd;
    if (ext == ".nii") return VolumeKind::Nifti;
    if (ext == ".gz" && lower_extension(std::filesystem::path(path).stem().string()) == ".nii")
        return VolumeKind::Nifti;
    return VolumeKind::None;
}

std::string number(double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", x);
    return buf;
}

}  // namespace

bool is_volume_path(const std::string& path) { return volume_kind(path) != VolumeKind::None; }

bool is_volume_output_path(const std::string& path) {
    const std::string ext = lower_extension(path);
    return ext == ".vdb" || ext == ".nrrd";
}

bool is_vdb_path(const std::string& path) { return lower_extension(path) == ".vdb"; }

Volume read_volume(const std::string& path) { return read_volume(path, VolumeInput{}); }

Volume read_volume(const std::string& path, const VolumeInput& in, VolumeReadInfo* info) {
    VolumeReadInfo local;
    VolumeReadInfo& ri = info ? *info : local;
    const VolumeKind kind = volume_kind(path);
    const auto bad = [&](const std::string& what) { throw InvalidInput("read_volume: " + path + ": " + what); };
    if (kind == VolumeKind::None)
        bad("unknown volume file " + shown_extension(path) + " (expected .nrrd, .nhdr, .nii, .nii.gz or .vdb)");
    if (in.iso && in.label) bad("give either an iso value or a label, not both");
    if (in.negate && in.label) bad("negate does not apply to a label map (its inside is the label's voxels)");
    if (in.iso && !std::isfinite(*in.iso)) bad("the iso value is not finite");
    if (in.label && !std::isfinite(*in.label)) bad("the label is not finite");
    if (!(in.voxel_size >= 0) || !std::isfinite(in.voxel_size)) bad("the voxel size must be > 0");
    const bool given = in.iso || in.label || in.negate || in.voxel_size > 0;

    if (kind == VolumeKind::Vdb) {
        if (given)
            bad("--iso, --label, --negate and --voxel-size apply to dense volumes (.nrrd, .nhdr, .nii); a .vdb level "
                "set is used as it is");
#if NORMALFLOW_HAS_OPENVDB
        Volume v = read_vdb(path);
        ri.format = "vdb";
        ri.dims = v.grid.dims;
        ri.spacing = {v.grid.voxel_size, v.grid.voxel_size, v.grid.voxel_size};
        ri.surface = "signed distance";
        ri.placed = !v.grid.placement.is_identity();
        return v;
#else
        no_support("read_volume", path, "reading .vdb", "OpenVDB");
#endif
    }

    const ScalarImage image = kind == VolumeKind::Nrrd ? read_nrrd_image(path) : read_nifti(path);
    ri.format = kind == VolumeKind::Nrrd ? "nrrd" : "nifti";
    ri.dims = image.dims;
    for (int a = 0; a < 3; ++a) ri.spacing[a] = norm(image.axes[a]);
    ImageToVolumeOptions opt;
    opt.voxel_size = in.voxel_size;
    if (in.label) {
        opt.surface.label = in.label;
        ri.surface = "label " + number(*in.label);
    } else if (in.iso) {
        opt.surface.iso = *in.iso;
        opt.surface.negate = !in.negate;  // inside above the iso value, unless negated
        ri.surface = std::string("iso ") + number(*in.iso) + (in.negate ? ", inside below" : ", inside above");
    } else if (const auto mask = binary_mask_label(image)) {
        opt.surface.label = mask;
        ri.surface = "label " + number(*mask) + " (a binary mask)";
    } else if (kind == VolumeKind::Nifti) {
        bad("give --iso V (a scalar image: the surface where the value is V) or --label L (a label map); its values "
            "are not a binary mask");
    } else {
        ri.surface = in.negate ? "signed distance, positive inside" : "signed distance";
        opt.surface.negate = in.negate;
        const double s = ri.spacing[0];
        const bool isotropic = std::abs(ri.spacing[1] - s) <= 1e-5 * s && std::abs(ri.spacing[2] - s) <= 1e-5 * s;
        if (isotropic && in.voxel_size == 0) {
            VolumeReadOptions ro;
            ro.negate = in.negate;
            Volume v = read_nrrd(path, ro);  // exactly the file's distances
            ri.placed = !v.grid.placement.is_identity();
            return v;
        }
    }
    try {
        Volume v = image_to_volume(image, opt);
        ri.resampled = v.grid.dims != image.dims;
        ri.placed = !v.grid.placement.is_identity();
        return v;
    } catch (const InvalidInput& e) {
        const std::string w = e.what();  // "image_to_volume: ..." → "read_volume: path: ..."
        throw InvalidInput("read_volume: " + path + ": " + w.substr(w.find(": ") + 2));
    }
}

void write_volume(const std::string& path, const Volume& v, const NormalMap* normals) {
    const std::string ext = lower_extension(path);
    if (ext == ".nrrd") {
        if (normals)
            throw InvalidInput("write_volume: " + path +
                               ": the normal map is written as a vector grid of a .vdb file; "
                               "use .vdb");
        return write_nrrd(path, v);
    }
    if (ext == ".vdb") {
#if NORMALFLOW_HAS_OPENVDB
        return write_vdb(path, v, normals);
#else
        no_support("write_volume", path, "writing .vdb", "OpenVDB");
#endif
    }
    throw InvalidInput("write_volume: " + path + ": unknown volume file " + shown_extension(path) +
                       " (expected .nrrd or .vdb)");
}

}  // namespace normalflow
