#include "io/draco/draco_io.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/io/gltf_encoder.h>
#include <draco/io/mesh_io.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.h"
#include "io/draco/gltf_check.h"
#include "io/formats/gltf.h"
#include "io/util/atomic_file.h"
#include "io/util/isolate.h"

namespace normalflow {

namespace {

std::vector<char> read_all(const std::string& path, const std::string& who) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw IoError(who + ": " + path + ": cannot open (" + std::strerror(errno) + ")");
    std::vector<char> data;
    char buf[1 << 16];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.insert(data.end(), buf, buf + n);
    const bool err = std::ferror(f) != 0;
    std::fclose(f);
    if (err) throw IoError(who + ": " + path + ": read error");
    if (data.empty()) throw InvalidInput(who + ": " + path + ": empty file");
    return data;
}

std::uint32_t le32(const char* p) {
    unsigned char b[4];
    std::memcpy(b, p, 4);
    return std::uint32_t(b[0]) | (std::uint32_t(b[1]) << 8) | (std::uint32_t(b[2]) << 16) | (std::uint32_t(b[3]) << 24);
}

constexpr std::uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;
constexpr std::uint32_t kChunkBin = 0x004E4942;

bool is_glb(const std::vector<char>& d) { return d.size() >= 4 && le32(d.data()) == kGlbMagic; }

/// Checks the GLB container layout so that truncated or damaged files get a clear message before
/// the bytes reach Draco's glTF parser.
void check_glb(const std::vector<char>& d, const std::string& who) {
    const std::uint64_t size = d.size();
    if (size < 12) throw InvalidInput(who + ": truncated GLB header (" + std::to_string(size) + " bytes, expected 12)");
    if (le32(d.data()) != kGlbMagic) throw InvalidInput(who + ": not a GLB file (bad magic)");
    const std::uint32_t version = le32(d.data() + 4), length = le32(d.data() + 8);
    if (version != 2) throw InvalidInput(who + ": GLB version " + std::to_string(version) + ", expected 2");
    if (length != size)
        throw InvalidInput(who + ": GLB header says " + std::to_string(length) + " bytes, the file has " +
                           std::to_string(size) + (length > size ? " (truncated)" : ""));
    std::uint64_t off = 12;
    int chunk = 0;
    while (off < size) {
        if (size - off < 8) throw InvalidInput(who + ": truncated GLB chunk header at byte " + std::to_string(off));
        const std::uint32_t clen = le32(d.data() + off), ctype = le32(d.data() + off + 4);
        if (clen > size - off - 8)
            throw InvalidInput(who + ": GLB chunk " + std::to_string(chunk) + " claims " + std::to_string(clen) +
                               " bytes, only " + std::to_string(size - off - 8) + " remain (truncated)");
        if (chunk == 0 && ctype != kChunkJson) throw InvalidInput(who + ": first GLB chunk is not JSON");
        if (chunk == 0 && clen == 0) throw InvalidInput(who + ": empty GLB JSON chunk");
        if (chunk == 1 && ctype != kChunkBin) throw InvalidInput(who + ": second GLB chunk is not BIN");
        off += 8 + std::uint64_t(clen);
        ++chunk;
    }
    if (chunk == 0) throw InvalidInput(who + ": GLB file has no JSON chunk");
}

/// Bits per linear colour component in Draco-compressed glTF: enough that every 8-bit sRGB value comes
/// back (the smallest step between two sRGB bytes is 1/255/12.92 = 3.0e-4 in linear; 12 bits give a
/// worst error of 1.2e-4).
constexpr int kLinearColorBits = 12;

/// Where a decoded Draco mesh came from: glTF stores colours linear, .drc files (draco_encoder from
/// PLY/OBJ) as the 8-bit sRGB values of the source.
enum class ColorSpace { Srgb, Linear };

/// Reads one colour of a COLOR attribute as sRGB bytes (alpha 255 when it has 3 components).
Rgba8 read_color(const draco::PointAttribute& a, draco::AttributeValueIndex i, ColorSpace space) {
    const int n = std::min<int>(a.num_components(), 4);
    Rgba8 c{255, 255, 255, 255};
    float f[4] = {1, 1, 1, 1};
    if (a.data_type() == draco::DT_UINT8) {
        std::uint8_t b[4] = {255, 255, 255, 255};
        a.ConvertValue<std::uint8_t>(i, std::int8_t(n), b);
        for (int k = 0; k < 4; ++k) f[k] = float(b[k]) / 255.0f;
    } else if (a.data_type() == draco::DT_UINT16) {
        std::uint16_t b[4] = {65535, 65535, 65535, 65535};
        a.ConvertValue<std::uint16_t>(i, std::int8_t(n), b);
        for (int k = 0; k < 4; ++k) f[k] = float(b[k]) / 65535.0f;
    } else {
        a.ConvertValue<float>(i, std::int8_t(n), f);
    }
    for (int k = 0; k < 4; ++k) {
        float x = std::isfinite(f[k]) ? std::clamp(f[k], 0.0f, 1.0f) : 0.0f;
        if (space == ColorSpace::Linear && k < 3) x = linear_to_srgb(x);
        c[std::size_t(k)] = std::uint8_t(std::lround(x * 255.0f));
    }
    return c;
}

/// Copies POSITION, faces and NORMAL, COLOR and TEX_COORD (the first of each) of a decoded Draco mesh;
/// validates. Without attributes, points with equal positions are one vertex (Draco's position
/// values); with attributes, every Draco point is a vertex (a seam keeps its two sides).
/// Texture v is taken as it is: Draco's glTF decoder already turned glTF's downward v upward.
Mesh to_mesh(const draco::Mesh& dm, const std::string& who, ColorSpace colors) {
    const draco::PointAttribute* pa = dm.GetNamedAttribute(draco::GeometryAttribute::POSITION);
    if (!pa) throw InvalidInput(who + ": no POSITION attribute");
    if (pa->num_components() < 3)
        throw InvalidInput(who + ": POSITION has " + std::to_string(pa->num_components()) + " components, expected 3");
    if (dm.num_faces() == 0) throw InvalidInput(who + ": no triangles (point cloud or non-triangle primitives)");
    const draco::PointAttribute* na = dm.GetNamedAttribute(draco::GeometryAttribute::NORMAL);
    const draco::PointAttribute* ca = dm.GetNamedAttribute(draco::GeometryAttribute::COLOR);
    const draco::PointAttribute* ta = dm.GetNamedAttribute(draco::GeometryAttribute::TEX_COORD);
    if (na && na->num_components() < 3) na = nullptr;
    if (ca && ca->num_components() < 3) ca = nullptr;
    if (ta && ta->num_components() < 2) ta = nullptr;
    const bool per_point = na || ca || ta;
    Mesh m;
    const std::size_t nv = per_point ? dm.num_points() : pa->size();
    // vertex i's value index in attribute a
    const auto value = [&](const draco::PointAttribute* a, std::size_t i) {
        return per_point ? a->mapped_index(draco::PointIndex(std::uint32_t(i)))
                         : draco::AttributeValueIndex(std::uint32_t(i));
    };
    m.positions.resize(nv);
    for (std::size_t i = 0; i < nv; ++i) {
        float p[3];
        if (!pa->ConvertValue<float>(value(pa, i), 3, p))
            throw InvalidInput(who + ": cannot convert POSITION value " + std::to_string(i));
        m.positions[i] = {p[0], p[1], p[2]};
        if (!is_finite(m.positions[i])) throw InvalidInput(who + ": point " + std::to_string(i) + " is not finite");
    }
    if (na) {
        m.normals.resize(nv);
        for (std::size_t i = 0; i < nv; ++i) {
            float n[3] = {0, 0, 0};
            na->ConvertValue<float>(value(na, i), 3, n);
            m.normals[i] = is_finite(Vec3f{n[0], n[1], n[2]}) ? Vec3f{n[0], n[1], n[2]} : Vec3f{};
        }
    }
    if (ca) {
        m.colors.resize(nv);
        for (std::size_t i = 0; i < nv; ++i) m.colors[i] = read_color(*ca, value(ca, i), colors);
    }
    if (ta) {
        m.texcoords.resize(nv);
        for (std::size_t i = 0; i < nv; ++i) {
            float t[2] = {0, 0};
            ta->ConvertValue<float>(value(ta, i), 2, t);
            for (float& x : t)
                if (!std::isfinite(x)) x = 0;
            m.texcoords[i] = {t[0], t[1]};
        }
    }
    m.triangles.resize(dm.num_faces());
    for (std::uint32_t f = 0; f < dm.num_faces(); ++f) {
        const auto& face = dm.face(draco::FaceIndex(f));
        for (int c = 0; c < 3; ++c) {
            if (face[c].value() >= dm.num_points())
                throw InvalidInput(who + ": triangle " + std::to_string(f) + " references point " +
                                   std::to_string(face[c].value()) + " of " + std::to_string(dm.num_points()));
            const std::uint32_t v = per_point ? face[c].value() : pa->mapped_index(face[c]).value();
            if (v >= nv) throw InvalidInput(who + ": triangle " + std::to_string(f) + " has an invalid position index");
            m.triangles[f][std::size_t(c)] = v;
        }
    }
    return m;
}

void check_options(const DracoOptions& opt, const std::string& who) {
    if (opt.position_bits < 1 || opt.position_bits > 30)
        throw InvalidInput(who + ": position_bits " + std::to_string(opt.position_bits) + " out of range [1, 30]");
    if (opt.normal_bits < 1 || opt.normal_bits > 30)
        throw InvalidInput(who + ": normal_bits " + std::to_string(opt.normal_bits) + " out of range [1, 30]");
    if (opt.texcoord_bits < 1 || opt.texcoord_bits > 30)
        throw InvalidInput(who + ": texcoord_bits " + std::to_string(opt.texcoord_bits) + " out of range [1, 30]");
    if (opt.compression_level < 0 || opt.compression_level > 10)
        throw InvalidInput(who + ": compression_level " + std::to_string(opt.compression_level) +
                           " out of range [0, 10]");
}

/// Builds a Draco mesh from m (validated) with its attributes, with equal points merged.
/// For glTF (linear_colors, flip_v) colours are stored linear and texture v flipped.
std::unique_ptr<draco::Mesh> to_draco(const Mesh& m, const std::string& who, bool linear_colors, bool flip_v) {
    const std::size_t nv = m.positions.size(), nf = m.triangles.size();
    check_mesh(m, who);
    if (nv == 0 || nf == 0)
        throw InvalidInput(who + ": empty mesh (" + std::to_string(nv) + " points, " + std::to_string(nf) +
                           " triangles)");
    if (nv > std::size_t(std::numeric_limits<std::int32_t>::max()) ||
        nf > std::size_t(std::numeric_limits<std::int32_t>::max()))
        throw InvalidInput(who + ": mesh too large for Draco");
    auto dm = std::make_unique<draco::Mesh>();
    dm->set_num_points(std::uint32_t(nv));
    draco::GeometryAttribute ga;
    ga.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false, sizeof(float) * 3, 0);
    const int id = dm->AddAttribute(ga, true, std::uint32_t(nv));
    draco::PointAttribute* pa = dm->attribute(id);
    for (std::size_t i = 0; i < nv; ++i) {
        const Vec3f& p = m.positions[i];
        if (!is_finite(p)) throw InvalidInput(who + ": point " + std::to_string(i) + " is not finite");
        const float xyz[3] = {p.x, p.y, p.z};
        pa->SetAttributeValue(draco::AttributeValueIndex(std::uint32_t(i)), xyz);
    }
    for (std::size_t f = 0; f < nf; ++f) {
        const Tri& t = m.triangles[f];
        for (std::uint32_t idx : t)
            if (idx >= nv)
                throw InvalidInput(who + ": triangle " + std::to_string(f) + " has index " + std::to_string(idx) +
                                   ", expected < " + std::to_string(nv));
        dm->AddFace({draco::PointIndex(t[0]), draco::PointIndex(t[1]), draco::PointIndex(t[2])});
    }
    // Optional attributes, one value per point (deduplicated below like the positions).
    const auto add = [&](draco::GeometryAttribute::Type type, int comps, draco::DataType dt, bool normalized,
                         std::size_t bytes, auto&& fill) {
        draco::GeometryAttribute g;
        g.Init(type, nullptr, std::int8_t(comps), dt, normalized, std::int64_t(bytes), 0);
        draco::PointAttribute* a = dm->attribute(dm->AddAttribute(g, true, std::uint32_t(nv)));
        for (std::size_t i = 0; i < nv; ++i) fill(a, i);
    };
    if (m.has_normals())
        add(draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32, false, 12,
            [&](draco::PointAttribute* a, std::size_t i) {
                Vec3f n = m.normals[i];
                const float len = std::sqrt(dot(n, n));
                n = len > 0 && std::isfinite(len) ? n / len : Vec3f{0, 0, 1};
                const float v[3] = {n.x, n.y, n.z};
                a->SetAttributeValue(draco::AttributeValueIndex(std::uint32_t(i)), v);
            });
    // glTF's linear colours are stored as floats, quantised by Draco to kLinearColorBits: 8 linear bits
    // would merge the dark sRGB shades (sRGB 0..12 all fall on linear 0..1/255).
    if (m.has_colors() && linear_colors)
        add(draco::GeometryAttribute::COLOR, 4, draco::DT_FLOAT32, false, 16,
            [&](draco::PointAttribute* a, std::size_t i) {
                const Rgba8 c = m.colors[i];
                float v[4];
                for (std::size_t k = 0; k < 4; ++k)
                    v[k] = k < 3 ? srgb_to_linear(float(c[k]) / 255.0f) : float(c[k]) / 255.0f;
                a->SetAttributeValue(draco::AttributeValueIndex(std::uint32_t(i)), v);
            });
    else if (m.has_colors())
        add(draco::GeometryAttribute::COLOR, 4, draco::DT_UINT8, true, 4, [&](draco::PointAttribute* a, std::size_t i) {
            a->SetAttributeValue(draco::AttributeValueIndex(std::uint32_t(i)), m.colors[i].data());
        });
    if (m.has_texcoords())
        add(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32, false, 8,
            [&](draco::PointAttribute* a, std::size_t i) {
                const TexCoord t = m.texcoords[i];
                const float v[2] = {t[0], flip_v ? 1.0f - t[1] : t[1]};
                if (!std::isfinite(v[0]) || !std::isfinite(v[1]))
                    throw InvalidInput(who + ": texture coordinate " + std::to_string(i) + " is not finite");
                a->SetAttributeValue(draco::AttributeValueIndex(std::uint32_t(i)), v);
            });
    dm->DeduplicateAttributeValues();
    dm->DeduplicatePointIds();
    return dm;
}

/// Encodes dm as a Draco bitstream (edgebreaker; sequential if edgebreaker fails).
draco::EncoderBuffer encode(const draco::Mesh& dm, const DracoOptions& opt, const std::string& who) {
    draco::Encoder enc;
    enc.SetAttributeQuantization(draco::GeometryAttribute::POSITION, opt.position_bits);
    enc.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, opt.normal_bits);
    enc.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, opt.texcoord_bits);
    enc.SetAttributeQuantization(draco::GeometryAttribute::COLOR, kLinearColorBits);  // float colours only
    const int speed = 10 - opt.compression_level;
    enc.SetSpeedOptions(speed, speed);
    enc.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
    draco::EncoderBuffer buf;
    draco::Status st = enc.EncodeMeshToBuffer(dm, &buf);
    if (!st.ok()) {
        buf.Clear();
        enc.SetEncodingMethod(draco::MESH_SEQUENTIAL_ENCODING);
        st = enc.EncodeMeshToBuffer(dm, &buf);
    }
    if (!st.ok()) throw InvalidInput(who + ": Draco encoding failed (" + st.error_msg_string() + ")");
    return buf;
}

void write_buffer(const std::string& path, const char* who, const char* data, std::size_t size) {
    AtomicFile f(path, who);
    f.write(data, size);
    f.commit();
}

std::string float_text(float x) {
    char buf[32];
    for (int prec = 6; prec <= 9; ++prec) {
        std::snprintf(buf, sizeof buf, "%.*g", prec, double(x));
        if (std::strtof(buf, nullptr) == x) break;
    }
    return buf;
}

void append_u32(std::string& s, std::uint32_t v) {
    for (int b = 0; b < 4; ++b) s.push_back(char((v >> (8 * b)) & 0xFF));
}

/// GLB with a Draco-compressed primitive plus uncompressed fallback buffers (hand-built).
std::string draco_glb_with_fallback(const draco::Mesh& dm, const DracoOptions& opt, const std::string& who) {
    const draco::EncoderBuffer enc = encode(dm, opt, who);
    // The fallback accessors must describe the points in the order the Draco decoder yields them.
    draco::DecoderBuffer in;
    in.Init(enc.data(), enc.size());
    draco::Decoder dec;
    auto res = dec.DecodeMeshFromBuffer(&in);
    if (!res.ok()) throw InvalidInput(who + ": Draco round trip failed (" + res.status().error_msg_string() + ")");
    const std::unique_ptr<draco::Mesh> d = std::move(res).value();
    const draco::PointAttribute* pa = d->GetNamedAttribute(draco::GeometryAttribute::POSITION);
    if (!pa) throw InvalidInput(who + ": Draco round trip lost POSITION");
    const std::uint32_t np = d->num_points(), nf = d->num_faces();
    std::string bin(enc.data(), enc.size());
    while (bin.size() % 4) bin.push_back('\0');
    const std::size_t pos_off = bin.size();
    float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                   std::numeric_limits<float>::max()};
    float hi[3] = {-lo[0], -lo[1], -lo[2]};
    for (std::uint32_t p = 0; p < np; ++p) {
        float xyz[3];
        pa->ConvertValue<float>(pa->mapped_index(draco::PointIndex(p)), 3, xyz);
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], xyz[a]);
            hi[a] = std::max(hi[a], xyz[a]);
            append_u32(bin, std::bit_cast<std::uint32_t>(xyz[a]));
        }
    }
    const std::size_t pos_len = bin.size() - pos_off;
    std::string attributes = R"("POSITION":0)", draco_ids = R"("POSITION":)" + std::to_string(pa->unique_id());
    std::string accessors = R"({"bufferView":1,"componentType":5126,"count":)" + std::to_string(np) +
                            R"(,"type":"VEC3","min":[)" + float_text(lo[0]) + "," + float_text(lo[1]) + "," +
                            float_text(lo[2]) + "],\"max\":[" + float_text(hi[0]) + "," + float_text(hi[1]) + "," +
                            float_text(hi[2]) + "]}";
    std::string views = R"({"buffer":0,"byteOffset":0,"byteLength":)" + std::to_string(enc.size()) + "}," +
                        R"({"buffer":0,"byteOffset":)" + std::to_string(pos_off) + R"(,"byteLength":)" +
                        std::to_string(pos_len) + R"(,"target":34962})";
    int next = 1;  // accessor index; its buffer view is next + 1
    // The optional attributes, decoded as the Draco decoder yields them: NORMAL and TEXCOORD_0 as float,
    // COLOR_0 as float (the linear values write_draco_glb gives Draco).
    struct Extra {
        draco::GeometryAttribute::Type type;
        const char* name;
        const char* vec;
        int comps;
    };
    for (const Extra e : {Extra{draco::GeometryAttribute::NORMAL, "NORMAL", "VEC3", 3},
                          Extra{draco::GeometryAttribute::COLOR, "COLOR_0", "VEC4", 4},
                          Extra{draco::GeometryAttribute::TEX_COORD, "TEXCOORD_0", "VEC2", 2}}) {
        const draco::PointAttribute* a = d->GetNamedAttribute(e.type);
        if (!a) continue;
        const std::size_t off = bin.size();
        for (std::uint32_t p = 0; p < np; ++p) {
            const draco::AttributeValueIndex v = a->mapped_index(draco::PointIndex(p));
            float x[4] = {0, 0, 0, 1};
            a->ConvertValue<float>(v, std::int8_t(std::min<int>(a->num_components(), e.comps)), x);
            for (int k = 0; k < e.comps; ++k) append_u32(bin, std::bit_cast<std::uint32_t>(x[k]));
        }
        ++next;
        attributes += ",\"" + std::string(e.name) + "\":" + std::to_string(next - 1);
        draco_ids += ",\"" + std::string(e.name) + "\":" + std::to_string(a->unique_id());
        accessors += R"(,{"bufferView":)" + std::to_string(next) + R"(,"componentType":)" + "5126" + R"(,"count":)" +
                     std::to_string(np) + R"(,"type":")" + e.vec + "\"}";
        views += R"(,{"buffer":0,"byteOffset":)" + std::to_string(off) + R"(,"byteLength":)" +
                 std::to_string(bin.size() - off) + R"(,"target":34962})";
    }
    const std::size_t idx_off = bin.size();
    for (std::uint32_t f = 0; f < nf; ++f)
        for (int c = 0; c < 3; ++c) append_u32(bin, d->face(draco::FaceIndex(f))[c].value());
    const std::size_t idx_len = bin.size() - idx_off;
    ++next;
    accessors += R"(,{"bufferView":)" + std::to_string(next) + R"(,"componentType":5125,"count":)" +
                 std::to_string(3 * std::uint64_t(nf)) + R"(,"type":"SCALAR"})";
    views += R"(,{"buffer":0,"byteOffset":)" + std::to_string(idx_off) + R"(,"byteLength":)" + std::to_string(idx_len) +
             R"(,"target":34963})";
    std::string json;
    json += R"({"asset":{"version":"2.0","generator":"normalflow"},"extensionsUsed":["KHR_draco_mesh_compression"],)";
    json += R"("scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)";
    json += R"("meshes":[{"primitives":[{"attributes":{)" + attributes + R"(},"indices":)" + std::to_string(next - 1) +
            R"(,"material":0,"mode":4,)";
    json += R"("extensions":{"KHR_draco_mesh_compression":{"bufferView":0,"attributes":{)" + draco_ids + "}}}}]}],";
    json += std::string(R"("materials":[)") + kGltfMaterial + "],";
    json += R"("accessors":[)" + accessors + "],";
    json += R"("bufferViews":[)" + views + "],";
    json += R"("buffers":[{"byteLength":)" + std::to_string(bin.size()) + "}]}";
    while (json.size() % 4) json.push_back(' ');
    const std::uint64_t total = 12 + 8 + json.size() + 8 + bin.size();
    if (total > std::numeric_limits<std::uint32_t>::max()) throw InvalidInput(who + ": mesh too large for GLB");
    std::string out;
    out.reserve(std::size_t(total));
    append_u32(out, kGlbMagic);
    append_u32(out, 2);
    append_u32(out, std::uint32_t(total));
    append_u32(out, std::uint32_t(json.size()));
    append_u32(out, kChunkJson);
    out += json;
    append_u32(out, std::uint32_t(bin.size()));
    append_u32(out, kChunkBin);
    out += bin;
    return out;
}

}  // namespace

Mesh read_gltf(const std::string& path, ReadInfo* info) {
    const std::string who = "read_gltf: " + path;
    const std::vector<char> data = read_all(path, "read_gltf");
    const bool glb = is_glb(data);
    std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : std::string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".glb" && !glb) throw InvalidInput(who + ": not a GLB file (bad magic)");
    if (glb) check_glb(data, who);
    // Our own structural check first (accessors against buffer views, index ranges, ...): Draco's glTF
    // reader trusts accessor data and reads out of bounds on malformed files (fuzz finding glb-e1f699a6).
    const std::string base_dir = std::filesystem::path(path).parent_path().string();
    if (glb) {
        const std::uint32_t json_len = le32(data.data() + 12);
        const std::string_view json(data.data() + 20, json_len);
        std::optional<std::string_view> bin;
        const std::size_t bin_at = 20 + std::size_t(json_len);
        if (data.size() - bin_at >= 8 && le32(data.data() + bin_at + 4) == kChunkBin)
            bin = std::string_view(data.data() + bin_at + 8, le32(data.data() + bin_at));
        check_gltf(json, bin, base_dir, who);
    } else {
        check_gltf(std::string_view(data.data(), data.size()), std::nullopt, base_dir, who);
    }
    // Decode in a forked child so that a crash inside Draco becomes an IoError (io/util/isolate.h).
    // draco::ReadMeshFromFile runs draco::GltfDecoder::DecodeFromFile (all nodes, transforms applied).
    // (Including draco/io/gltf_decoder.h directly would need tiny_gltf.h, which Debian does not ship
    // with libdraco-dev, and would have to match the copy compiled into libdraco exactly.)
    const std::string bytes = run_isolated(who, [&] {
        std::unique_ptr<draco::Mesh> dm;
        try {
            auto res = draco::ReadMeshFromFile(path);
            if (!res.ok()) throw InvalidInput(who + ": " + res.status().error_msg_string());
            dm = std::move(res).value();
        } catch (const InvalidInput&) {
            throw;
        } catch (const std::exception& e) {
            throw InvalidInput(who + ": malformed glTF (" + e.what() + ")");
        }
        if (!dm) throw InvalidInput(who + ": no mesh decoded");
        ByteWriter w;
        put_mesh(w, to_mesh(*dm, who, ColorSpace::Linear));
        return w.take();
    });
    ByteReader r(bytes, who);
    Mesh m = get_mesh(r);
    if (info) {
        info->format = glb ? "glb" : "gltf";
        info->file_vertices = m.positions.size();
        info->file_faces = m.triangles.size();
    }
    return m;
}

Mesh read_drc(const std::string& path, ReadInfo* info) {
    const std::string who = "read_drc: " + path;
    const std::vector<char> data = read_all(path, "read_drc");
    if (data.size() < 5 || std::memcmp(data.data(), "DRACO", 5) != 0)
        throw InvalidInput(who + ": not a Draco file (expected magic \"DRACO\")");
    // Decode in a forked child so that a crash or undefined behaviour inside Draco on a corrupt
    // bitstream becomes an IoError (fuzz finding drc-80305ea1; io/util/isolate.h).
    const std::string bytes = run_isolated(who, [&] {
        draco::DecoderBuffer buf;
        buf.Init(data.data(), data.size());
        auto type = draco::Decoder::GetEncodedGeometryType(&buf);
        if (!type.ok()) throw InvalidInput(who + ": " + type.status().error_msg_string());
        if (type.value() != draco::TRIANGULAR_MESH) throw InvalidInput(who + ": not a triangle mesh (point cloud?)");
        draco::Decoder dec;
        auto res = dec.DecodeMeshFromBuffer(&buf);
        if (!res.ok()) throw InvalidInput(who + ": " + res.status().error_msg_string());
        const std::unique_ptr<draco::Mesh> dm = std::move(res).value();
        ByteWriter w;
        put_mesh(w, to_mesh(*dm, who, ColorSpace::Srgb));
        return w.take();
    });
    ByteReader r(bytes, who);
    Mesh m = get_mesh(r);
    if (info) {
        info->format = "drc";
        info->file_vertices = m.positions.size();
        info->file_faces = m.triangles.size();
    }
    return m;
}

void write_drc(const std::string& path, const Mesh& m, const DracoOptions& opt) {
    const std::string who = "write_drc: " + path;
    check_options(opt, who);
    const auto dm = to_draco(m, who, /*linear_colors=*/false, /*flip_v=*/false);
    const draco::EncoderBuffer buf = encode(*dm, opt, who);
    write_buffer(path, "write_drc", buf.data(), buf.size());
}

void write_draco_glb(const std::string& path, const Mesh& m, const DracoOptions& opt) {
    const std::string who = "write_draco_glb: " + path;
    check_options(opt, who);
    // draco::GltfEncoder flips texture v itself; the fallback's hand-built Draco stream is read by glTF
    // viewers as is, so it holds glTF's flipped v.
    const auto dm = to_draco(m, who, /*linear_colors=*/true, /*flip_v=*/opt.fallback);
    if (opt.fallback) {
        const std::string glb = draco_glb_with_fallback(*dm, opt, who);
        write_buffer(path, "write_draco_glb", glb.data(), glb.size());
        return;
    }
    draco::DracoCompressionOptions co;
    co.compression_level = opt.compression_level;
    co.quantization_position.SetQuantizationBits(opt.position_bits);
    co.quantization_bits_normal = opt.normal_bits;
    co.quantization_bits_tex_coord = opt.texcoord_bits;
    co.quantization_bits_color = kLinearColorBits;
    draco::Material* material = dm->GetMaterialLibrary().MutableMaterial(0);
    material->SetName("normalflow");
    material->SetColorFactor(draco::Vector4f(0.8f, 0.8f, 0.8f, 1.0f));
    material->SetMetallicFactor(0.0f);
    material->SetRoughnessFactor(0.6f);
    dm->SetCompressionEnabled(true);
    dm->SetCompressionOptions(co);
    draco::GltfEncoder enc;
    draco::EncoderBuffer buf;
    const draco::Status st = enc.EncodeToBuffer(*dm, &buf);
    if (!st.ok()) throw InvalidInput(who + ": Draco glTF encoding failed (" + st.error_msg_string() + ")");
    write_buffer(path, "write_draco_glb", buf.data(), buf.size());
}

}  // namespace normalflow
