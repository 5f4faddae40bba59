// Wavefront OBJ reader and writer (see mesh_formats.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "io/formats/format_util.h"
#include "io/formats/mesh_formats.h"
#include "io/util/atomic_file.h"

namespace normalflow {

namespace {

constexpr std::string_view kReader = "read_obj";
constexpr std::string_view kWriter = "write_obj";

void skip_space(const char*& p, const char* e) {
    while (p < e && detail::is_space(*p)) ++p;
}

std::string quote_token(const char* p, const char* e) {
    const char* q = p;
    while (q < e && !detail::is_space(*q) && q - p < 24) ++q;
    std::string s(p, q);
    for (char& c : s)
        if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
    return "'" + s + "'";
}

bool is_ignored_statement(std::string_view k) {
    static constexpr std::string_view known[] = {
        "vp",     "o",      "g",          "s",         "usemtl", "mtllib", "l",        "p",        "cstype",
        "deg",    "bmat",   "step",       "curv",      "curv2",  "surf",   "parm",     "trim",     "hole",
        "scrv",   "sp",     "end",        "con",       "mg",     "bevel",  "c_interp", "d_interp", "lod",
        "maplib", "usemap", "shadow_obj", "trace_obj", "ctech",  "stech"};
    for (const auto& s : known)
        if (k == s) return true;
    return false;
}

/// Turns OBJ's per-corner texture coordinate and normal references into per-vertex attributes of m:
/// a vertex takes the (vt, vn) of its first corner; a corner of the same vertex with another (vt, vn)
/// gets a copy of the vertex (position and colour), one per distinct pair, appended after the file's
/// vertices. Returns the number of copies. corner_ref holds 3 entries per triangle of m.
std::size_t attach_corner_attributes(Mesh& m, const std::vector<std::array<std::int64_t, 2>>& corner_ref,
                                     const std::vector<TexCoord>* texcoords, const std::vector<Vec3f>* normals) {
    if (!texcoords && !normals) return 0;
    const std::size_t nv = m.positions.size();
    std::vector<std::array<std::int64_t, 2>> first(nv, {-2, -2});  // -2: no corner yet
    std::map<std::array<std::int64_t, 3>, std::uint32_t> copies;
    auto key_of = [&](const std::array<std::int64_t, 2>& r) {
        return std::array<std::int64_t, 2>{texcoords ? r[0] : -1, normals ? r[1] : -1};
    };
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        for (std::size_t c = 0; c < 3; ++c) {
            std::uint32_t& v = m.triangles[t][c];
            const auto key = key_of(corner_ref[3 * t + c]);
            // an absent reference (-1) matches any; a vertex is copied only for a conflicting one
            const auto agrees = [](std::int64_t a, std::int64_t b) { return a < 0 || b < 0 || a == b; };
            if (first[v][0] == -2) {
                first[v] = key;
            } else if (agrees(first[v][0], key[0]) && agrees(first[v][1], key[1])) {
                for (std::size_t k = 0; k < 2; ++k) first[v][k] = std::max(first[v][k], key[k]);
            } else {
                const auto [it, fresh] =
                    copies.try_emplace({std::int64_t(v), key[0], key[1]}, std::uint32_t(first.size()));
                if (fresh) {
                    m.positions.push_back(m.positions[v]);
                    if (m.has_colors()) m.colors.push_back(m.colors[v]);
                    first.push_back(key);
                }
                v = it->second;
            }
        }
    if (texcoords) {
        m.texcoords.assign(first.size(), TexCoord{0.0f, 0.0f});
        for (std::size_t v = 0; v < first.size(); ++v)
            if (first[v][0] >= 0) m.texcoords[v] = (*texcoords)[std::size_t(first[v][0])];
    }
    if (normals) {
        m.normals.assign(first.size(), Vec3f{});
        for (std::size_t v = 0; v < first.size(); ++v)
            if (first[v][1] >= 0) m.normals[v] = (*normals)[std::size_t(first[v][1])];
    }
    return copies.size();
}

}  // namespace

Mesh read_obj_memory(std::string_view bytes, const std::string& name, ReadInfo* info) {
    using detail::fail;
    using detail::fail_line;
    if (bytes.empty()) fail(kReader, name, "empty file");
    if (const void* nul = std::memchr(bytes.data(), 0, bytes.size())) {
        const auto off = std::size_t(static_cast<const char*>(nul) - bytes.data());
        const std::size_t line = 1 + std::size_t(std::count(bytes.begin(), bytes.begin() + std::ptrdiff_t(off), '\n'));
        fail_line(kReader, name, line, "binary data (NUL byte) in a text file");
    }

    Mesh m;
    std::vector<std::uint32_t> poly;
    std::vector<Rgba8> colors;                                      // per v line, once any has a colour
    std::vector<TexCoord> texcoords;                                // vt lines
    std::vector<Vec3f> normals;                                     // vn lines
    std::vector<std::array<std::int64_t, 2>> poly_ref, corner_ref;  // per corner: vt, vn (0-based, -1 absent)
    bool any_ref[2] = {false, false};
    std::pair<std::int64_t, std::size_t> max_ref[2] = {{-1, 0}, {-1, 0}};  // largest positive reference, its line
    std::string bad_ref[2];  // why the texture coordinates / normals are dropped, if they are
    std::size_t faces = 0, split = 0, unknown = 0, first_unknown_line = 0;
    std::string first_unknown;
    std::int64_t max_index = -1;  // largest 0-based index from a positive reference
    std::size_t max_index_line = 0;

    const char* p = bytes.data();
    const char* const end = p + bytes.size();
    std::size_t line = 0;
    while (p < end) {
        ++line;
        const char* eol = static_cast<const char*>(std::memchr(p, '\n', std::size_t(end - p)));
        if (!eol) eol = end;
        const char* q = p;
        p = eol < end ? eol + 1 : end;
        const char* le = static_cast<const char*>(std::memchr(q, '#', std::size_t(eol - q)));
        if (!le) le = eol;
        skip_space(q, le);
        if (q == le) continue;
        const char* kw = q;
        while (q < le && !detail::is_space(*q)) ++q;
        const std::string_view key(kw, std::size_t(q - kw));

        if (key == "v") {
            Vec3f v;
            for (int a = 0; a < 3; ++a) {
                skip_space(q, le);
                const char* s = q;
                if (q == le || !detail::parse_float(q, le, v[a]) || (q < le && !detail::is_space(*q)))
                    fail_line(kReader, name, line,
                              q == le && s == le ? "vertex has fewer than 3 coordinates"
                                                 : "expected a coordinate, found " + quote_token(s, le));
            }
            if (!is_finite(v)) fail_line(kReader, name, line, "vertex has a NaN or infinite coordinate");
            // optional w, or a colour r g b (0..1, the common extension; values above 1 are read as 0..255)
            float extra[3];
            int n_extra = 0;
            for (; n_extra < 3; ++n_extra) {
                skip_space(q, le);
                if (q == le || !detail::parse_float(q, le, extra[n_extra])) break;
            }
            m.positions.push_back(v);
            if (n_extra == 3) {
                if (colors.empty()) colors.resize(m.positions.size() - 1, Rgba8{255, 255, 255, 255});
                const bool bytes01 = extra[0] > 1.0f || extra[1] > 1.0f || extra[2] > 1.0f;
                Rgba8 c{0, 0, 0, 255};
                for (int a = 0; a < 3; ++a) {
                    const float x = std::isfinite(extra[a]) ? extra[a] * (bytes01 ? 1.0f : 255.0f) : 0.0f;
                    c[std::size_t(a)] = std::uint8_t(std::lround(std::clamp(x, 0.0f, 255.0f)));
                }
                colors.push_back(c);
            } else if (!colors.empty()) {
                colors.push_back(Rgba8{255, 255, 255, 255});
            }
        } else if (key == "vt" || key == "vn") {
            const int dims = key == "vt" ? 2 : 3;
            float c[3] = {0, 0, 0};
            for (int a = 0; a < dims; ++a) {
                skip_space(q, le);
                const char* s = q;
                // vt's second coordinate is optional ("vt u"); vn needs all three
                if (q == le && key == "vt" && a == 1) break;
                if (q == le || !detail::parse_float(q, le, c[a]) || (q < le && !detail::is_space(*q)))
                    fail_line(kReader, name, line,
                              std::string(key) + " expects " + std::to_string(dims) + " numbers, found " +
                                  (q == le && s == le ? std::string("fewer") : quote_token(s, le)));
                if (!std::isfinite(c[a])) c[a] = 0.0f;
            }
            if (key == "vt")
                texcoords.push_back(TexCoord{c[0], c[1]});
            else
                normals.push_back(Vec3f{c[0], c[1], c[2]});
        } else if (key == "f") {
            poly.clear();
            const auto nv = std::int64_t(m.positions.size());
            for (;;) {
                skip_space(q, le);
                if (q == le) break;
                const char* s = q;
                std::int64_t idx = 0;
                bool ok = detail::parse_int(q, le, idx);
                // optional /vt, //vn or /vt/vn
                std::int64_t tn[2] = {0, 0};  // 1-based or negative as in the file, 0 = absent
                for (int slash = 0; ok && slash < 2 && q < le && *q == '/'; ++slash) {
                    ++q;
                    if (q < le && *q != '/' && !detail::is_space(*q)) ok = detail::parse_int(q, le, tn[slash]);
                }
                if (!ok || (q < le && !detail::is_space(*q)))
                    fail_line(kReader, name, line,
                              "expected a face corner (v, v/vt, v//vn or v/vt/vn), found " + quote_token(s, le));
                std::int64_t r = 0;
                if (idx == 0) {
                    fail_line(kReader, name, line, "vertex index 0 (OBJ indices start at 1)");
                } else if (idx < 0) {
                    r = nv + idx;
                    if (r < 0)
                        fail_line(kReader, name, line,
                                  "relative vertex index " + std::to_string(idx) +
                                      " reaches before the first vertex (" + std::to_string(nv) +
                                      " vertices read so far)");
                } else {
                    r = idx - 1;
                    if (r >= std::int64_t(std::numeric_limits<std::uint32_t>::max()))
                        fail_line(kReader, name, line, "vertex index " + std::to_string(idx) + " is too large");
                    if (r > max_index) {
                        max_index = r;
                        max_index_line = line;
                    }
                }
                poly.push_back(std::uint32_t(r));
                std::array<std::int64_t, 2> ref{-1, -1};  // 0-based vt, vn index, -1 = absent
                const std::size_t counts[2] = {texcoords.size(), normals.size()};
                for (int k = 0; k < 2; ++k) {
                    if (tn[k] == 0) continue;
                    ref[std::size_t(k)] = tn[k] < 0 ? std::int64_t(counts[k]) + tn[k] : tn[k] - 1;
                    if (ref[std::size_t(k)] < 0) {
                        if (bad_ref[k].empty())
                            bad_ref[k] = (k ? "normal" : "texture coordinate") + std::string(" index ") +
                                         std::to_string(tn[k]) + " at line " + std::to_string(line) +
                                         " reaches before the first one";
                        ref[std::size_t(k)] = -1;
                    }
                    if (tn[k] > 0) max_ref[k] = std::max(max_ref[k], std::make_pair(ref[std::size_t(k)], line));
                    any_ref[k] = true;
                }
                poly_ref.push_back(ref);
            }
            if (poly.size() < 3)
                fail_line(kReader, name, line,
                          "face has " + std::to_string(poly.size()) + " corners, expected at least 3");
            ++faces;
            if (poly.size() > 3) ++split;
            detail::push_fan(m.triangles, poly.data(), poly.size());
            for (std::size_t k = 1; k + 1 < poly_ref.size(); ++k)
                for (const std::size_t c : {std::size_t(0), k, k + 1}) corner_ref.push_back(poly_ref[c]);
            poly_ref.clear();
        } else if (!is_ignored_statement(key)) {
            if (unknown++ == 0) {
                first_unknown = quote_token(kw, le);
                first_unknown_line = line;
            }
        }
    }
    if (max_index >= std::int64_t(m.positions.size()))
        fail_line(kReader, name, max_index_line,
                  "vertex index " + std::to_string(max_index + 1) + " out of range (the file has " +
                      std::to_string(m.positions.size()) + " vertices)");
    if (faces == 0) fail(kReader, name, "no faces (" + std::to_string(m.positions.size()) + " vertices, no 'f' lines)");
    for (int k = 0; k < 2; ++k) {
        const std::size_t count = k ? normals.size() : texcoords.size();
        if (max_ref[k].first >= std::int64_t(count) && bad_ref[k].empty())
            bad_ref[k] = (k ? "normal" : "texture coordinate") + std::string(" index ") +
                         std::to_string(max_ref[k].first + 1) + " at line " + std::to_string(max_ref[k].second) +
                         " is out of range (the file has " + std::to_string(count) + ")";
        // The positions and faces are sound: a broken attribute reference drops that attribute, not the file.
        if (!bad_ref[k].empty()) any_ref[k] = false;
    }
    if (!colors.empty()) m.colors = std::move(colors);
    const std::size_t file_vertices = m.positions.size();
    const std::size_t split_vertices =
        attach_corner_attributes(m, corner_ref, any_ref[0] ? &texcoords : nullptr, any_ref[1] ? &normals : nullptr);

    if (info) {
        *info = ReadInfo{};
        info->format = "obj";
        info->file_vertices = file_vertices;
        info->file_faces = faces;
        info->polygons_split = split;
        if (split) info->warnings.push_back(detail::split_warning(split));
        for (int k = 0; k < 2; ++k)
            if (!bad_ref[k].empty())
                info->warnings.push_back(bad_ref[k] + "; the " + (k ? "normals" : "texture coordinates") +
                                         " are ignored");
        if (split_vertices)
            info->warnings.push_back(std::to_string(split_vertices) +
                                     " vertices duplicated where their corners have different texture coordinates "
                                     "or normals");
        if (unknown)
            info->warnings.push_back(std::to_string(unknown) + " lines with unknown statements ignored (first: " +
                                     first_unknown + " at line " + std::to_string(first_unknown_line) + ")");
    }
    return m;
}

Mesh read_obj(const std::string& path, ReadInfo* info) {
    const std::string data = detail::read_whole_file(path, kReader);
    return read_obj_memory(data, path, info);
}

void write_obj(const std::string& path, const Mesh& m, const WriteOptions&) {
    detail::validate_mesh_for_write(m, kWriter, path);
    AtomicFile f(path, kWriter);
    constexpr std::size_t kChunk = 1 << 20;
    std::string buf;
    buf.reserve(kChunk + 256);
    buf += "# written by normalflow\n";
    const auto flush = [&] {
        if (buf.size() >= kChunk) {
            f.write(buf);
            buf.clear();
        }
    };
    const auto floats = [&](const char* key, const float* x, int n) {
        buf += key;
        for (int a = 0; a < n; ++a) {
            buf += ' ';
            detail::append_float(buf, x[a]);
        }
        buf += '\n';
        flush();
    };
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        const Vec3f& v = m.positions[i];
        float x[6] = {v.x, v.y, v.z, 0, 0, 0};
        if (m.has_colors())
            for (int a = 0; a < 3; ++a) x[3 + a] = float(m.colors[i][std::size_t(a)]) / 255.0f;
        floats("v", x, m.has_colors() ? 6 : 3);
    }
    for (const TexCoord& t : m.texcoords) floats("vt", t.data(), 2);
    for (const Vec3f& n : m.normals) {
        const float x[3] = {n.x, n.y, n.z};
        floats("vn", x, 3);
    }
    for (const Tri& t : m.triangles) {
        buf += 'f';
        for (const std::uint32_t i : t) {
            buf += ' ';
            detail::append_uint(buf, std::uint64_t(i) + 1);
            if (m.has_texcoords() || m.has_normals()) buf += '/';
            if (m.has_texcoords()) detail::append_uint(buf, std::uint64_t(i) + 1);
            if (m.has_normals()) {
                buf += '/';
                detail::append_uint(buf, std::uint64_t(i) + 1);
            }
        }
        buf += '\n';
        if (buf.size() >= kChunk) {
            f.write(buf);
            buf.clear();
        }
    }
    f.write(buf);
    f.commit();
}

}  // namespace normalflow
