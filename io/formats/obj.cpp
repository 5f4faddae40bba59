// Wavefront OBJ reader and writer (see mesh_formats.h).
#include <algorithm>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "io/util/atomic_file.h"
#include "io/formats/format_util.h"
#include "io/formats/mesh_formats.h"

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
    static constexpr std::string_view known[] = {"vt", "vn", "vp", "o", "g", "s", "usemtl", "mtllib",
                                                 "l", "p", "cstype", "deg", "bmat", "step", "curv",
                                                 "curv2", "surf", "parm", "trim", "hole", "scrv", "sp",
                                                 "end", "con", "mg", "bevel", "c_interp", "d_interp",
                                                 "lod", "maplib", "usemap", "shadow_obj", "trace_obj",
                                                 "ctech", "stech"};
    for (const auto& s : known)
        if (k == s) return true;
    return false;
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
            m.positions.push_back(v);
        } else if (key == "f") {
            poly.clear();
            const auto nv = std::int64_t(m.positions.size());
            for (;;) {
                skip_space(q, le);
                if (q == le) break;
                const char* s = q;
                std::int64_t idx = 0;
                bool ok = detail::parse_int(q, le, idx);
                // optional /vt, //vn or /vt/vn: the numbers are checked for syntax only
                for (int slash = 0; ok && slash < 2 && q < le && *q == '/'; ++slash) {
                    ++q;
                    std::int64_t ignored = 0;
                    if (q < le && *q != '/' && !detail::is_space(*q)) ok = detail::parse_int(q, le, ignored);
                }
                if (!ok || (q < le && !detail::is_space(*q)))
                    fail_line(kReader, name, line, "expected a face corner (v, v/vt, v//vn or v/vt/vn), found " +
                                                       quote_token(s, le));
                std::int64_t r = 0;
                if (idx == 0) {
                    fail_line(kReader, name, line, "vertex index 0 (OBJ indices start at 1)");
                } else if (idx < 0) {
                    r = nv + idx;
                    if (r < 0)
                        fail_line(kReader, name, line,
                                  "relative vertex index " + std::to_string(idx) + " reaches before the first vertex (" +
                                      std::to_string(nv) + " vertices read so far)");
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
            }
            if (poly.size() < 3)
                fail_line(kReader, name, line,
                          "face has " + std::to_string(poly.size()) + " corners, expected at least 3");
            ++faces;
            if (poly.size() > 3) ++split;
            detail::push_fan(m.triangles, poly.data(), poly.size());
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

    if (info) {
        *info = ReadInfo{};
        info->format = "obj";
        info->file_vertices = m.positions.size();
        info->file_faces = faces;
        info->polygons_split = split;
        if (split) info->warnings.push_back(detail::split_warning(split));
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
    for (const Vec3f& v : m.positions) {
        buf += "v ";
        detail::append_float(buf, v.x);
        buf += ' ';
        detail::append_float(buf, v.y);
        buf += ' ';
        detail::append_float(buf, v.z);
        buf += '\n';
        if (buf.size() >= kChunk) {
            f.write(buf);
            buf.clear();
        }
    }
    for (const Tri& t : m.triangles) {
        buf += 'f';
        for (const std::uint32_t i : t) {
            buf += ' ';
            detail::append_uint(buf, std::uint64_t(i) + 1);
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
