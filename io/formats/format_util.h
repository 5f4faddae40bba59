#pragma once
/// \file format_util.h
/// Internals shared by the mesh format readers and writers (io/formats): whole-file reading,
/// locale-independent number parsing and formatting, byte order, mesh validation, and the
/// one-line error messages ("read_ply: scan.ply, line 12: ..."). Not part of the public API.

#include <bit>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>

#include "core/errors.h"
#include "core/mesh.h"

namespace normalflow {
class AtomicFile;
}

namespace normalflow::detail {

/// Reads the whole file at `path` into memory.
/// \throw IoError naming `who` and `path` if it cannot be opened (missing, a folder) or read.
std::string read_whole_file(const std::string& path, std::string_view who);

/// InvalidInput "who: name: what".
[[noreturn]] void fail(std::string_view who, std::string_view name, std::string_view what);
/// InvalidInput "who: name, line N: what".
[[noreturn]] void fail_line(std::string_view who, std::string_view name, std::size_t line, std::string_view what);

/// Throws InvalidInput (naming who and name) unless m has at least one triangle, finite positions
/// and indices in range. Writers call it before opening the output file.
void validate_mesh_for_write(const Mesh& m, std::string_view who, std::string_view name);

/// "N faces had more than 3 corners (split into triangle fans)".
std::string split_warning(std::size_t n);

/// Writes the body that ASCII PLY and OFF share, "x y z" per vertex then "3 i j k" per face, to f
/// in chunks of about 1 MiB. buf holds what comes before it (the header) and is left empty.
/// With attributes, each vertex line goes on with the normal (3 floats), colour (4 integers) and
/// texture coordinate (2 floats) that m has, in that order (ASCII PLY's vertex properties).
void write_ascii_vertices_and_faces(AtomicFile& f, std::string& buf, const Mesh& m, bool attributes = false);

/// Appends the shortest decimal text that reads back to exactly v (std::to_chars round trip).
inline void append_float(std::string& out, float v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, r.ptr);
}
inline void append_uint(std::string& out, std::uint64_t v) {
    char buf[24];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, r.ptr);
}

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

/// Parses a float at [p, end) (an optional leading '+' is accepted; "nan"/"inf" parse and are
/// caught later by finiteness checks). On success advances p and returns true. A value outside
/// float range yields +-inf (reported later as a non-finite coordinate).
inline bool parse_float(const char*& p, const char* end, float& v) {
    const char* s = p;
    if (s < end && *s == '+' && ++s < end && *s == '-') return false;
    const auto r = std::from_chars(s, end, v);
    if (r.ec == std::errc::result_out_of_range) {
        // from_chars leaves v unchanged: overflow becomes +-inf (caught by the finiteness checks),
        // underflow the nearest float of the double value.
        double d = 0;
        const auto r2 = std::from_chars(s, end, d);
        const bool neg = *s == '-';
        if (r2.ec == std::errc{} && std::fabs(d) <= double(std::numeric_limits<float>::max()))
            v = float(d);
        else
            v = neg ? -std::numeric_limits<float>::infinity() : std::numeric_limits<float>::infinity();
        p = r.ptr;
        return true;
    }
    if (r.ec != std::errc{}) return false;
    p = r.ptr;
    return true;
}

/// Parses a (possibly signed) integer at [p, end). On success advances p and returns true.
inline bool parse_int(const char*& p, const char* end, std::int64_t& v) {
    const char* s = p;
    if (s < end && *s == '+' && ++s < end && *s == '-') return false;
    const auto r = std::from_chars(s, end, v);
    if (r.ec != std::errc{}) return false;
    p = r.ptr;
    return true;
}

/// Byte-order helpers: load a little- or big-endian scalar of type T from unaligned memory.
template <class T>
inline T load_scalar(const char* p, bool big_endian) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, p, sizeof(T));
    const bool swap = big_endian != (std::endian::native == std::endian::big);
    if (swap)
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
}

/// Appends v in little-endian byte order.
template <class T>
inline void append_le(std::string& out, T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if constexpr (std::endian::native == std::endian::big)
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

/// Pushes the triangle fan of polygon idx[0..n) (n >= 3) onto tris.
template <class Tris>
inline void push_fan(Tris& tris, const std::uint32_t* idx, std::size_t n) {
    for (std::size_t k = 1; k + 1 < n; ++k) tris.push_back(Tri{idx[0], idx[k], idx[k + 1]});
}

}  // namespace normalflow::detail
