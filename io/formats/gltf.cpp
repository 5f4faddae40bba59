#include "io/formats/gltf.h"

#include <algorithm>
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

constexpr std::uint32_t kGlbMagic = 0x46546C67;   // "glTF"
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
    if (nv == 0 || nf == 0)
        throw InvalidInput(who + ": empty mesh (" + std::to_string(nv) + " points, " + std::to_string(nf) +
                           " triangles)");
    Vec3f lo{std::numeric_limits<float>::max(), std::numeric_limits<float>::max(), std::numeric_limits<float>::max()};
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
    check_mesh(m, who);  // attribute sizes and values

    // The BIN chunk: POSITION, then NORMAL, COLOR_0, TEXCOORD_0 as present (all float, little-endian),
    // then the indices. Every part is a multiple of 4 bytes.
    std::vector<float> attr;  // the optional attributes, one after the other
    std::string attributes = R"("POSITION":0)", accessors, views;
    std::uint64_t offset = std::uint64_t(nv) * 12;
    int next = 1;  // accessor and buffer view index
    views = R"({"buffer":0,"byteOffset":0,"byteLength":)" + std::to_string(offset) + R"(,"target":34962})";
    accessors = R"({"bufferView":0,"componentType":5126,"count":)" + std::to_string(nv) + R"(,"type":"VEC3","min":[)" +
                float_text(lo.x) + "," + float_text(lo.y) + "," + float_text(lo.z) + "],\"max\":[" + float_text(hi.x) +
                "," + float_text(hi.y) + "," + float_text(hi.z) + "]}";
    const auto add = [&](const char* name, const char* type, int comps, auto&& value) {
        const std::size_t first = attr.size();
        for (std::size_t i = 0; i < nv; ++i)
            for (int c = 0; c < comps; ++c) attr.push_back(value(i, c));
        const std::uint64_t bytes = std::uint64_t(attr.size() - first) * 4;
        attributes += ",\"" + std::string(name) + "\":" + std::to_string(next);
        accessors += R"(,{"bufferView":)" + std::to_string(next) + R"(,"componentType":5126,"count":)" +
                     std::to_string(nv) + R"(,"type":")" + type + "\"}";
        views += R"(,{"buffer":0,"byteOffset":)" + std::to_string(offset) + R"(,"byteLength":)" +
                 std::to_string(bytes) + R"(,"target":34962})";
        offset += bytes;
        ++next;
    };
    if (m.has_normals())
        add("NORMAL", "VEC3", 3, [&](std::size_t i, int c) {
            // glTF wants unit normals: a zero normal (undefined) is written as +z.
            const Vec3f n = m.normals[i];
            const float len = std::sqrt(dot(n, n));
            return len > 0 ? n[c] / len : (c == 2 ? 1.0f : 0.0f);
        });
    if (m.has_colors())
        add("COLOR_0", "VEC4", 4, [&](std::size_t i, int c) {
            const float x = float(m.colors[i][std::size_t(c)]) / 255.0f;
            return c == 3 ? x : srgb_to_linear(x);
        });
    if (m.has_texcoords())
        add("TEXCOORD_0", "VEC2", 2,
            [&](std::size_t i, int c) { return c == 0 ? m.texcoords[i][0] : 1.0f - m.texcoords[i][1]; });
    const std::uint64_t idx_bytes = std::uint64_t(nf) * 12;
    accessors += R"(,{"bufferView":)" + std::to_string(next) + R"(,"componentType":5125,"count":)" +
                 std::to_string(3 * std::uint64_t(nf)) + R"(,"type":"SCALAR"})";
    views += R"(,{"buffer":0,"byteOffset":)" + std::to_string(offset) + R"(,"byteLength":)" +
             std::to_string(idx_bytes) + R"(,"target":34963})";
    const std::uint64_t bin_bytes = offset + idx_bytes;

    std::string json;
    json.reserve(1024);
    json += R"({"asset":{"version":"2.0","generator":"normalflow"},"scene":0,"scenes":[{"nodes":[0]}],)";
    json += R"("nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{)" + attributes + R"(},"indices":)" +
            std::to_string(next) + R"(,"material":0,"mode":4}]}],)";
    json += std::string(R"("materials":[)") + kGltfMaterial + "],";
    json += R"("accessors":[)" + accessors + "],";
    json += R"("bufferViews":[)" + views + "],";
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
        f.write(m.positions.data(), std::uint64_t(nv) * 12);
        f.write(attr.data(), attr.size() * 4);
        f.write(m.triangles.data(), idx_bytes);
    } else {
        std::vector<std::uint32_t> buf;
        buf.reserve(3 * 4096);
        auto flush = [&] {
            f.write(buf.data(), buf.size() * 4);
            buf.clear();
        };
        auto put = [&](std::uint32_t v) {
            buf.push_back(to_le(v));
            if (buf.size() >= 3 * 4096) flush();
        };
        for (const Vec3f& p : m.positions)
            for (int a = 0; a < 3; ++a) put(std::bit_cast<std::uint32_t>(p[a]));
        for (const float x : attr) put(std::bit_cast<std::uint32_t>(x));
        for (const Tri& t : m.triangles)
            for (int a = 0; a < 3; ++a) put(t[a]);
        flush();
    }
    f.commit();
}

float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

float linear_to_srgb(float c) {
    c = std::clamp(c, 0.0f, 1.0f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

}  // namespace normalflow
