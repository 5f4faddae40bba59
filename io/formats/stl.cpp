// STL reader and writer, ASCII and binary (see mesh_formats.h).
#include "io/formats/mesh_formats.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "io/formats/format_util.h"
#include "io/util/atomic_file.h"

namespace normalflow {

namespace {

constexpr std::string_view kReader = "read_stl";
constexpr std::string_view kWriter = "write_stl";
constexpr std::size_t kHeader = 84;  // 80-byte header + uint32 triangle count
constexpr std::size_t kFacet = 50;   // 12 floats + uint16 attribute

bool iequals(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        char x = a[i], y = b[i];
        if (x >= 'A' && x <= 'Z') x = char(x - 'A' + 'a');
        if (y >= 'A' && y <= 'Z') y = char(y - 'A' + 'a');
        if (x != y) return false;
    }
    return true;
}

std::string printable(std::string_view s) {
    std::string r(s.substr(0, 24));
    for (char& c : r)
        if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
    return "'" + r + "'";
}

bool starts_with_solid(std::string_view b) {
    std::size_t i = 0;
    while (i < b.size() && (detail::is_space(b[i]) || b[i] == '\n')) ++i;
    return b.size() - i >= 5 && iequals(b.substr(i, 5), "solid") &&
           (b.size() - i == 5 || detail::is_space(b[i + 5]) || b[i + 5] == '\n');
}

struct Tokens {
    const char* p;
    const char* end;
    std::size_t line = 1;

    std::string_view next() {
        while (p < end && (detail::is_space(*p) || *p == '\n')) {
            if (*p == '\n') ++line;
            ++p;
        }
        const char* s = p;
        while (p < end && !detail::is_space(*p) && *p != '\n') ++p;
        return {s, std::size_t(p - s)};
    }
    void skip_line() {
        while (p < end && *p != '\n') ++p;
    }
};

Mesh read_binary(std::string_view bytes, const std::string& name, std::size_t n, ReadInfo* info) {
    if (n == 0) detail::fail(kReader, name, "no faces (binary STL with 0 triangles)");
    if (n > (std::size_t(std::numeric_limits<std::uint32_t>::max()) + 1) / 3)
        detail::fail(kReader, name, "too many triangles for 32-bit indices");
    Mesh m;
    m.positions.resize(3 * n);
    m.triangles.resize(n);
    const char* p = bytes.data() + kHeader;
    for (std::size_t i = 0; i < n; ++i, p += kFacet) {
        for (std::size_t k = 0; k < 3; ++k) {
            const char* v = p + 12 * (k + 1);
            Vec3f& q = m.positions[3 * i + k];
            q = {detail::load_scalar<float>(v, false), detail::load_scalar<float>(v + 4, false),
                 detail::load_scalar<float>(v + 8, false)};
            if (!is_finite(q))
                detail::fail(kReader, name, "facet " + std::to_string(i) + " has a NaN or infinite coordinate");
        }
        m.triangles[i] = Tri{std::uint32_t(3 * i), std::uint32_t(3 * i + 1), std::uint32_t(3 * i + 2)};
    }
    if (info) {
        *info = ReadInfo{};
        info->format = "stl-binary";
        info->file_vertices = 3 * n;
        info->file_faces = n;
        const std::size_t extra = bytes.size() - kHeader - kFacet * n;
        if (extra) info->warnings.push_back(std::to_string(extra) + " bytes after the last facet ignored");
    }
    return m;
}

Mesh read_ascii(std::string_view bytes, const std::string& name, ReadInfo* info, const std::string& binary_note) {
    using detail::fail_line;
    if (const void* nul = std::memchr(bytes.data(), 0, bytes.size())) {
        const auto off = std::size_t(static_cast<const char*>(nul) - bytes.data());
        const std::size_t line = 1 + std::size_t(std::count(bytes.begin(), bytes.begin() + std::ptrdiff_t(off), '\n'));
        fail_line(kReader, name, line, "binary data (NUL byte) in an ASCII STL file" + binary_note);
    }
    Tokens tk{bytes.data(), bytes.data() + bytes.size()};
    auto expect = [&](std::string_view word) {
        const std::string_view t = tk.next();
        if (t.empty()) fail_line(kReader, name, tk.line, "truncated file: expected '" + std::string(word) + "'");
        if (!iequals(t, word))
            fail_line(kReader, name, tk.line, "expected '" + std::string(word) + "', found " + printable(t));
    };
    auto number = [&](bool coordinate) {
        const std::string_view t = tk.next();
        if (t.empty()) fail_line(kReader, name, tk.line, "truncated file: expected a number");
        float v = 0;
        const char* s = t.data();
        if (!detail::parse_float(s, t.data() + t.size(), v) || s != t.data() + t.size())
            fail_line(kReader, name, tk.line, "expected a number, found " + printable(t));
        if (coordinate && !std::isfinite(v)) fail_line(kReader, name, tk.line, "NaN or infinite vertex coordinate");
        return v;
    };
    Mesh m;
    std::vector<std::uint32_t> poly;
    std::size_t facets = 0, split = 0;
    expect("solid");
    tk.skip_line();  // the solid's name
    for (;;) {
        const std::string_view t = tk.next();
        if (t.empty()) fail_line(kReader, name, tk.line, "truncated file: no 'endsolid'");
        if (iequals(t, "endsolid")) {
            tk.skip_line();
            const std::string_view more = tk.next();
            if (more.empty()) break;
            if (!iequals(more, "solid"))
                fail_line(kReader, name, tk.line, "expected 'solid' or the end of the file, found " + printable(more));
            tk.skip_line();
            continue;
        }
        if (!iequals(t, "facet"))
            fail_line(kReader, name, tk.line, "expected 'facet' or 'endsolid', found " + printable(t) + binary_note);
        expect("normal");
        for (int a = 0; a < 3; ++a) number(false);  // normals are recomputed downstream; NaN ones are common
        expect("outer");
        expect("loop");
        poly.clear();
        for (;;) {
            const std::string_view w = tk.next();
            if (w.empty()) fail_line(kReader, name, tk.line, "truncated file: expected 'vertex' or 'endloop'");
            if (iequals(w, "endloop")) break;
            if (!iequals(w, "vertex"))
                fail_line(kReader, name, tk.line, "expected 'vertex' or 'endloop', found " + printable(w));
            Vec3f v;
            for (int a = 0; a < 3; ++a) v[a] = number(true);
            if (m.positions.size() >= std::numeric_limits<std::uint32_t>::max())
                fail_line(kReader, name, tk.line, "too many vertices for 32-bit indices");
            poly.push_back(std::uint32_t(m.positions.size()));
            m.positions.push_back(v);
        }
        if (poly.size() < 3)
            fail_line(kReader, name, tk.line, "facet has " + std::to_string(poly.size()) + " vertices, expected 3");
        expect("endfacet");
        ++facets;
        if (poly.size() > 3) ++split;
        detail::push_fan(m.triangles, poly.data(), poly.size());
    }
    if (facets == 0) detail::fail(kReader, name, "no faces (ASCII STL without facets)");
    if (info) {
        *info = ReadInfo{};
        info->format = "stl-ascii";
        info->file_vertices = m.positions.size();
        info->file_faces = facets;
        info->polygons_split = split;
        if (split) info->warnings.push_back(detail::split_warning(split));
    }
    return m;
}

}  // namespace

Mesh read_stl_memory(std::string_view bytes, const std::string& name, ReadInfo* info) {
    if (bytes.empty()) detail::fail(kReader, name, "empty file");
    const bool solid = starts_with_solid(bytes);
    if (bytes.size() >= kHeader) {
        const std::uint64_t n = detail::load_scalar<std::uint32_t>(bytes.data() + 80, false);
        const std::uint64_t expected = kHeader + kFacet * n;
        // A binary file may start with "solid" (many exporters write it): the exact size decides.
        if (expected == bytes.size() || (!solid && expected < bytes.size()))
            return read_binary(bytes, name, std::size_t(n), info);
        if (!solid)
            detail::fail(kReader, name,
                         "truncated binary STL: the header says " + std::to_string(n) + " triangles (" +
                             std::to_string(expected) + " bytes), the file has " + std::to_string(bytes.size()) +
                             " bytes");
        return read_ascii(bytes, name, info,
                          " (not a binary STL either: " + std::to_string(bytes.size()) + " bytes, not 84 + 50 * " +
                              std::to_string(n) + ")");
    }
    if (!solid)
        detail::fail(
            kReader, name,
            "not an STL file (" + std::to_string(bytes.size()) + " bytes: too short for binary, no 'solid' keyword)");
    return read_ascii(bytes, name, info, "");
}

Mesh read_stl(const std::string& path, ReadInfo* info) {
    const std::string data = detail::read_whole_file(path, kReader);
    return read_stl_memory(data, path, info);
}

void write_stl(const std::string& path, const Mesh& m, const WriteOptions& opt) {
    detail::validate_mesh_for_write(m, kWriter, path);
    if (m.triangles.size() > std::numeric_limits<std::uint32_t>::max())
        detail::fail(kWriter, path, "more than 2^32-1 triangles");
    AtomicFile f(path, kWriter);
    constexpr std::size_t kChunk = 1 << 20;
    std::string buf;
    buf.reserve(kChunk + 1024);
    auto flush = [&] {
        if (buf.size() >= kChunk) {
            f.write(buf);
            buf.clear();
        }
    };
    auto normal = [&](const Tri& t) {
        const Vec3d n = normalized(face_area_vector(m, t));
        return Vec3f(n);
    };
    if (opt.binary) {
        char header[80] = {};
        const char text[] = "binary STL written by normalflow";
        std::memcpy(header, text, sizeof text - 1);
        buf.append(header, sizeof header);
        detail::append_le(buf, std::uint32_t(m.triangles.size()));
        for (const Tri& t : m.triangles) {
            const Vec3f n = normal(t);
            detail::append_le(buf, n.x);
            detail::append_le(buf, n.y);
            detail::append_le(buf, n.z);
            for (const std::uint32_t i : t) {
                const Vec3f& v = m.positions[i];
                detail::append_le(buf, v.x);
                detail::append_le(buf, v.y);
                detail::append_le(buf, v.z);
            }
            detail::append_le(buf, std::uint16_t(0));
            flush();
        }
    } else {
        auto vec = [&](const Vec3f& v) {
            detail::append_float(buf, v.x);
            buf += ' ';
            detail::append_float(buf, v.y);
            buf += ' ';
            detail::append_float(buf, v.z);
            buf += '\n';
        };
        buf += "solid normalflow\n";
        for (const Tri& t : m.triangles) {
            buf += "facet normal ";
            vec(normal(t));
            buf += " outer loop\n";
            for (const std::uint32_t i : t) {
                buf += "  vertex ";
                vec(m.positions[i]);
            }
            buf += " endloop\nendfacet\n";
            flush();
        }
        buf += "endsolid normalflow\n";
    }
    f.write(buf);
    f.commit();
}

}  // namespace normalflow
