#include "io/formats/gltf.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <vector>

#include "core/errors.h"
#include "io/util/atomic_file.h"

namespace normalflow {

namespace {

constexpr std::uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"

std::uint32_t to_le(std::uint32_t v) {
    if constexpr (std::endian::native == std::endian::little) return v;
    return ((v & 0xFFu) << 24) | ((v & 0xFF00u) << 8) | ((v >> 8) & 0xFF00u) | (v >> 24);
}

void put_u32(AtomicFile& f, std::uint32_t v) {
    v = to_le(v);
    f.write(&v, 4);
}

// Shortest text that reads back as exactly the same float.
std::string float_text(float x) {
    char buf[32];
    for (int prec = 6; prec <= 9; ++prec) {
        std::snprintf(buf, sizeof buf, "%.*g", prec, double(x));
        if (std::strtof(buf, nullptr) == x) break;
    }
    return buf;
}

}  // namespace

void write_glb(const std::string& path, const Mesh& m) {
    const std::string who = "write_glb: " + path;
    const std::size_t nv = m.positions.size(), nf = m.triangles.size();
    if (nv == 0 || nf == 0) throw InvalidInput(who + ": empty mesh (" + std::to_string(nv) + " points, " +
                                               std::to_string(nf) + " triangles)");
    Vec3f lo{std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
             std::numeric_limits<float>::max()};
    Vec3f hi = -lo;
    for (std::size_t i = 0; i < nv; ++i) {
        const Vec3f& p = m.positions[i];
        if (!is_finite(p)) throw InvalidInput(who + ": point " + std::to_string(i) + " is not finite");
        lo = cwise_min(lo, p);
        hi = cwise_max(hi, p);
    }
    for (std::size_t f = 0; f < nf; ++f)
        for (std::uint32_t idx : m.triangles[f])
            if (idx >= nv)
                throw InvalidInput(who + ": triangle " + std::to_string(f) + " has index " + std::to_string(idx) +
                                   ", expected < " + std::to_string(nv));

    const std::uint64_t pos_bytes = std::uint64_t(nv) * 12, idx_bytes = std::uint64_t(nf) * 12;
    const std::uint64_t bin_bytes = pos_bytes + idx_bytes;  // both multiples of 4
    std::string json;
    json.reserve(1024);
    json += R"({"asset":{"version":"2.0","generator":"normalflow"},"scene":0,"scenes":[{"nodes":[0]}],)";
    json += R"("nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"mode":4}]}],)";
    json += R"("accessors":[{"bufferView":0,"componentType":5126,"count":)" + std::to_string(nv) +
            R"(,"type":"VEC3","min":[)" + float_text(lo.x) + "," + float_text(lo.y) + "," + float_text(lo.z) +
            "],\"max\":[" + float_text(hi.x) + "," + float_text(hi.y) + "," + float_text(hi.z) + "]},";
    json += R"({"bufferView":1,"componentType":5125,"count":)" + std::to_string(3 * std::uint64_t(nf)) +
            R"(,"type":"SCALAR"}],)";
    json += R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":)" + std::to_string(pos_bytes) +
            R"(,"target":34962},{"buffer":0,"byteOffset":)" + std::to_string(pos_bytes) +
            R"(,"byteLength":)" + std::to_string(idx_bytes) + R"(,"target":34963}],)";
    json += R"("buffers":[{"byteLength":)" + std::to_string(bin_bytes) + "}]}";
    while (json.size() % 4 != 0) json += ' ';

    const std::uint64_t total = 12 + 8 + json.size() + 8 + bin_bytes;
    if (total > std::numeric_limits<std::uint32_t>::max())
        throw InvalidInput(who + ": mesh too large for GLB (" + std::to_string(total) + " bytes, limit 4 GiB)");

    AtomicFile f(path, "write_glb");
    put_u32(f, kGlbMagic);
    put_u32(f, 2);
    put_u32(f, std::uint32_t(total));
    put_u32(f, std::uint32_t(json.size()));
    put_u32(f, kChunkJson);
    f.write(json);
    put_u32(f, std::uint32_t(bin_bytes));
    put_u32(f, kChunkBin);
    static_assert(sizeof(Vec3f) == 12 && sizeof(Tri) == 12, "tightly packed position/triangle types expected");
    if constexpr (std::endian::native == std::endian::little) {
        f.write(m.positions.data(), pos_bytes);
        f.write(m.triangles.data(), idx_bytes);
    } else {
        std::vector<std::uint32_t> buf;
        buf.reserve(3 * 4096);
        auto flush = [&] { f.write(buf.data(), buf.size() * 4); buf.clear(); };
        for (const Vec3f& p : m.positions) {
            for (int a = 0; a < 3; ++a) buf.push_back(to_le(std::bit_cast<std::uint32_t>(p[a])));
            if (buf.size() >= 3 * 4096) flush();
        }
        flush();
        for (const Tri& t : m.triangles) {
            for (int a = 0; a < 3; ++a) buf.push_back(to_le(t[a]));
            if (buf.size() >= 3 * 4096) flush();
        }
        flush();
    }
    f.commit();
}

}  // namespace normalflow
