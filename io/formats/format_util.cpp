#include "io/formats/format_util.h"

#include "core/errors.h"
#include "io/util/atomic_file.h"

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace normalflow::detail {

std::string read_whole_file(const std::string& path, std::string_view who) {
    const std::string w(who);
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw IoError(w + ": " + path + ": is a directory, not a file");
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
    if (!f) throw IoError(w + ": " + path + ": cannot open (" + std::strerror(errno) + ")");
    std::string data;
    if (std::fseek(f.get(), 0, SEEK_END) == 0) {
        const long size = std::ftell(f.get());
        if (size > 0) data.reserve(std::size_t(size));
        std::rewind(f.get());
    }
    char buf[1 << 16];
    for (;;) {
        const std::size_t n = std::fread(buf, 1, sizeof buf, f.get());
        data.append(buf, n);
        if (n < sizeof buf) break;
    }
    if (std::ferror(f.get())) throw IoError(w + ": " + path + ": read failed (" + std::strerror(errno) + ")");
    return data;
}

void fail(std::string_view who, std::string_view name, std::string_view what) {
    std::string s;
    s.append(who).append(": ").append(name).append(": ").append(what);
    throw InvalidInput(s);
}

void fail_line(std::string_view who, std::string_view name, std::size_t line, std::string_view what) {
    std::string s;
    s.append(who).append(": ").append(name).append(", line ").append(std::to_string(line)).append(": ").append(what);
    throw InvalidInput(s);
}

void validate_mesh_for_write(const Mesh& m, std::string_view who, std::string_view name) {
    if (m.triangles.empty()) fail(who, name, "mesh has no triangles, nothing to write");
    if (m.positions.size() > std::size_t(0x7fffffff))
        fail(who, name, "mesh has " + std::to_string(m.positions.size()) + " vertices, more than 2^31-1");
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        if (!is_finite(m.positions[i]))
            fail(who, name, "vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
    const std::size_t nv = m.positions.size();
    for (std::size_t i = 0; i < m.triangles.size(); ++i)
        for (const std::uint32_t v : m.triangles[i])
            if (v >= nv)
                fail(who, name,
                     "triangle " + std::to_string(i) + " has vertex index " + std::to_string(v) +
                         ", but the mesh has " + std::to_string(nv) + " vertices");
    try {
        check_mesh(m, "");  // attribute sizes and finiteness
    } catch (const InvalidInput& e) {
        fail(who, name, std::string_view(e.what()).substr(2));  // drop check_mesh's ": " prefix
    }
}

std::string split_warning(std::size_t n) {
    return std::to_string(n) + (n == 1 ? " face had" : " faces had") +
           " more than 3 corners (split into triangle fans)";
}

void write_ascii_vertices_and_faces(AtomicFile& f, std::string& buf, const Mesh& m, bool attributes) {
    constexpr std::size_t kChunk = 1 << 20;
    buf.reserve(kChunk + 256);
    const auto flush = [&] {
        if (buf.size() >= kChunk) {
            f.write(buf);
            buf.clear();
        }
    };
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        const Vec3f& v = m.positions[i];
        append_float(buf, v.x);
        buf += ' ';
        append_float(buf, v.y);
        buf += ' ';
        append_float(buf, v.z);
        if (attributes) {
            if (m.has_normals())
                for (int a = 0; a < 3; ++a) {
                    buf += ' ';
                    append_float(buf, m.normals[i][a]);
                }
            if (m.has_colors())
                for (int a = 0; a < 4; ++a) {
                    buf += ' ';
                    append_uint(buf, m.colors[i][std::size_t(a)]);
                }
            if (m.has_texcoords())
                for (int a = 0; a < 2; ++a) {
                    buf += ' ';
                    append_float(buf, m.texcoords[i][std::size_t(a)]);
                }
        }
        buf += '\n';
        flush();
    }
    for (const Tri& t : m.triangles) {
        buf += '3';
        for (const std::uint32_t i : t) {
            buf += ' ';
            append_uint(buf, i);
        }
        buf += '\n';
        flush();
    }
    f.write(buf);
    buf.clear();
}

}  // namespace normalflow::detail
