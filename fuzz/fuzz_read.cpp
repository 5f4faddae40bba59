// libFuzzer target for one normalflow reader, chosen at compile time: NF_FUZZ_FORMAT is the file
// extension without its dot ("obj", "ply", "off", "stl", "glb", "drc", "nrrd", "nii", "vdb").
//
// Contract under test (issue 7): any byte string either reads into a valid Mesh/Volume/ScalarImage or throws
// InvalidInput / IoError / OutOfMemory. Any other exception, a crash, a leak, a hang, or a result
// that breaks the type's invariant (index out of range, non-finite value) is a finding.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include <unistd.h>

#include "core/errors.h"
#include "io/formats/mesh_formats.h"
#include "io/formats/nifti.h"
#include "io/io.h"

#ifndef NF_FUZZ_FORMAT
#error "define NF_FUZZ_FORMAT"
#endif
#define NF_STR2(x) #x
#define NF_STR(x) NF_STR2(x)

namespace {

using namespace normalflow;

const std::string kExt = NF_STR(NF_FUZZ_FORMAT);

[[noreturn]] void finding(const std::string& what) {
    std::fprintf(stderr, "fuzz_read_%s: %s\n", kExt.c_str(), what.c_str());
    std::abort();
}

/// A reader's result must pass the same checks every stage applies to its input.
void check(const Mesh& m) {
    try {
        check_mesh(m, "a reader returned a mesh that breaks the Mesh invariant");
    } catch (const std::exception& e) {
        finding(e.what());
    }
}

void check(const Volume& v) {
    try {
        v.check("a reader returned a volume that breaks the Volume invariants");
    } catch (const std::exception& e) {
        finding(e.what());
    }
}

/// A dense image (read_nifti): dims >= 1, one value per sample, finite values, origin and axes, axes
/// of non-zero length.
void check(const ScalarImage& img) {
    for (int a = 0; a < 3; ++a)
        if (img.dims[std::size_t(a)] < 1) finding("a reader returned an image with dims < 1");
    if (img.values.size() != img.sample_count())
        finding("a reader returned an image whose values are not dims' product");
    for (const float x : img.values)
        if (!std::isfinite(x)) finding("a reader returned an image with a non-finite value");
    if (!is_finite(img.origin)) finding("a reader returned an image with a non-finite origin");
    for (const Vec3d& a : img.axes)
        if (!is_finite(a) || !(norm(a) > 0)) finding("a reader returned an image with a non-finite or zero axis");
}

/// Readers that only take a path get the bytes through a private temporary file.
std::string temp_path() {
    static const std::string path = [] {
        const char* dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
        return std::string(dir) + "/nf_fuzz_" + std::to_string(getpid()) + "." + kExt;
    }();
    return path;
}

std::string through_file(std::string_view bytes) {
    const std::string path = temp_path();
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) finding("cannot write the temporary file");
    if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) finding("short write");
    std::fclose(f);
    return path;
}

void read_one(std::string_view bytes) {
    const std::string name = "fuzz." + kExt;
    if (kExt == "obj") return check(read_obj_memory(bytes, name));
    if (kExt == "ply") return check(read_ply_memory(bytes, name));
    if (kExt == "off") return check(read_off_memory(bytes, name));
    if (kExt == "stl") return check(read_stl_memory(bytes, name));
    const std::string path = through_file(bytes);
    if (kExt == "nii") return check(read_nifti(path));
    if (is_volume_path(path)) return check(read_volume(path));
    return check(read_mesh(path));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        read_one(std::string_view(reinterpret_cast<const char*>(data), size));
    } catch (const normalflow::InvalidInput&) {
    } catch (const normalflow::IoError&) {
    } catch (const normalflow::OutOfMemory&) {}
    return 0;
}
