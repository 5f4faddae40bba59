// OFF reader and writer (see mesh_formats.h).
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

constexpr std::string_view kReader = "read_off";
constexpr std::string_view kWriter = "write_off";

/// Walks the content lines of a text file: '#' comments stripped, blank lines skipped.
struct Lines {
    const char* p;
    const char* end;
    std::size_t line = 0;     // number of the line last returned
    const char* b = nullptr;  // current line [b, e), comment stripped, leading space skipped
    const char* e = nullptr;

    bool next() {
        while (p < end) {
            ++line;
            const char* eol = static_cast<const char*>(std::memchr(p, '\n', std::size_t(end - p)));
            if (!eol) eol = end;
            b = p;
            p = eol < end ? eol + 1 : end;
            e = static_cast<const char*>(std::memchr(b, '#', std::size_t(eol - b)));
            if (!e) e = eol;
            while (b < e && detail::is_space(*b)) ++b;
            if (b < e) return true;
        }
        return false;
    }
};

void skip_space(const char*& p, const char* e) {
    while (p < e && detail::is_space(*p)) ++p;
}

std::string token_text(const char* p, const char* e) {
    const char* q = p;
    while (q < e && !detail::is_space(*q) && q - p < 24) ++q;
    std::string s(p, q);
    for (char& c : s)
        if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
    return "'" + s + "'";
}

/// Parses one integer token at q (after optional space); false at the end of the line.
bool int_token(const char*& q, const char* e, std::int64_t& v, const std::string& name, std::size_t line) {
    skip_space(q, e);
    if (q == e) return false;
    const char* s = q;
    if (!detail::parse_int(q, e, v) || (q < e && !detail::is_space(*q)))
        detail::fail_line(kReader, name, line, "expected an integer, found " + token_text(s, e));
    return true;
}

}  // namespace

Mesh read_off_memory(std::string_view bytes, const std::string& name, ReadInfo* info) {
    using detail::fail;
    using detail::fail_line;
    if (bytes.empty()) fail(kReader, name, "empty file");
    if (const void* nul = std::memchr(bytes.data(), 0, bytes.size())) {
        const auto off = std::size_t(static_cast<const char*>(nul) - bytes.data());
        const std::size_t line = 1 + std::size_t(std::count(bytes.begin(), bytes.begin() + std::ptrdiff_t(off), '\n'));
        fail_line(kReader, name, line, "binary data (NUL byte) in a text file");
    }
    Lines L{bytes.data(), bytes.data() + bytes.size()};
    if (!L.next()) fail(kReader, name, "no header (only comments and blank lines)");

    // Header keyword: [ST][C][N][4][n]OFF, optional when the file starts with the counts.
    // The first token is the keyword unless it is a number (e.g. "4OFF" is a keyword, "3" a count).
    const char* q = L.b;
    const char* first_end = q;
    while (first_end < L.e && !detail::is_space(*first_end)) ++first_end;
    const bool starts_with_counts =
        std::all_of(q, first_end, [](char c) { return (c >= '0' && c <= '9') || c == '+' || c == '-'; });
    if (!starts_with_counts) {
        const char* kw = q;
        while (q < L.e && !detail::is_space(*q)) ++q;
        const std::string_view k(kw, std::size_t(q - kw));
        if (k.size() < 3 || k.substr(k.size() - 3) != "OFF")
            fail_line(kReader, name, L.line, "not an OFF file (expected 'OFF', found " + token_text(kw, L.e) + ")");
        std::string_view prefix = k.substr(0, k.size() - 3);
        if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
        if (!prefix.empty() && prefix[0] == 'C') prefix.remove_prefix(1);
        if (!prefix.empty() && prefix[0] == 'N') prefix.remove_prefix(1);
        if (!prefix.empty())
            fail_line(kReader, name, L.line,
                      "unsupported OFF variant " + token_text(kw, L.e) + " (4OFF and nOFF are not supported)");
        skip_space(q, L.e);
        if (q < L.e && std::string_view(q, std::size_t(L.e - q)).substr(0, 6) == "BINARY")
            fail_line(kReader, name, L.line, "binary OFF is not supported");
        if (q == L.e) {  // counts on the next line
            if (!L.next()) fail(kReader, name, "truncated file: no vertex and face counts after the header");
            q = L.b;
        }
    }
    std::int64_t nv = 0, nf = 0, ne = 0;
    if (!int_token(q, L.e, nv, name, L.line) || !int_token(q, L.e, nf, name, L.line))
        fail_line(kReader, name, L.line, "expected the vertex and face counts");
    int_token(q, L.e, ne, name, L.line);  // edge count: optional, ignored
    if (nv < 0 || nf < 0) fail_line(kReader, name, L.line, "negative vertex or face count");
    // Each vertex takes at least 6 bytes ("0 0 0\n") and each face at least 2 (its corner count and a
    // newline; a face with too few corners is then reported on its own line, not as a bad count).
    // The last line needs no newline, hence + 1.
    const auto left = std::uint64_t(L.end - L.p) + 1;
    if (std::uint64_t(nv) > left / 6 || std::uint64_t(nf) > left / 2 ||
        std::uint64_t(nv) * 6 + std::uint64_t(nf) * 2 > left)
        fail_line(kReader, name, L.line,
                  "header claims " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                      " faces, more than the remaining " + std::to_string(left - 1) +
                      " bytes can hold (truncated or corrupt file)");
    if (nf == 0) fail_line(kReader, name, L.line, "no faces (the header says 0 faces)");

    Mesh m;
    m.positions.resize(std::size_t(nv));
    m.triangles.reserve(std::size_t(nf));
    for (std::int64_t i = 0; i < nv; ++i) {
        if (!L.next())
            fail(kReader, name,
                 "truncated file: " + std::to_string(i) + " of " + std::to_string(nv) + " vertices present");
        const char* c = L.b;
        Vec3f& v = m.positions[std::size_t(i)];
        for (int a = 0; a < 3; ++a) {
            skip_space(c, L.e);
            const char* s = c;
            if (c == L.e) fail_line(kReader, name, L.line, "vertex has fewer than 3 coordinates");
            if (!detail::parse_float(c, L.e, v[a]) || (c < L.e && !detail::is_space(*c)))
                fail_line(kReader, name, L.line, "expected a coordinate, found " + token_text(s, L.e));
        }
        if (!is_finite(v)) fail_line(kReader, name, L.line, "vertex has a NaN or infinite coordinate");
    }
    std::vector<std::uint32_t> poly;
    std::size_t split = 0;
    for (std::int64_t i = 0; i < nf; ++i) {
        if (!L.next())
            fail(kReader, name,
                 "truncated file: " + std::to_string(i) + " of " + std::to_string(nf) + " faces present");
        const char* c = L.b;
        std::int64_t n = 0;
        int_token(c, L.e, n, name, L.line);
        if (n < 3) fail_line(kReader, name, L.line, "face has " + std::to_string(n) + " corners, expected at least 3");
        if (n > L.e - L.b)
            fail_line(kReader, name, L.line, "face claims " + std::to_string(n) + " corners, the line is shorter");
        poly.resize(std::size_t(n));
        for (std::int64_t k = 0; k < n; ++k) {
            std::int64_t v = 0;
            if (!int_token(c, L.e, v, name, L.line))
                fail_line(kReader, name, L.line,
                          "face has " + std::to_string(k) + " indices, expected " + std::to_string(n));
            if (v < 0 || v >= nv)
                fail_line(kReader, name, L.line,
                          "vertex index " + std::to_string(v) + " out of range (the file has " + std::to_string(nv) +
                              " vertices)");
            poly[std::size_t(k)] = std::uint32_t(v);
        }
        // anything after the indices (a colour) is ignored
        if (n > 3) ++split;
        detail::push_fan(m.triangles, poly.data(), poly.size());
    }
    std::size_t trailing = 0;
    while (L.next()) ++trailing;

    if (info) {
        *info = ReadInfo{};
        info->format = "off";
        info->file_vertices = std::size_t(nv);
        info->file_faces = std::size_t(nf);
        info->polygons_split = split;
        if (split) info->warnings.push_back(detail::split_warning(split));
        if (trailing) info->warnings.push_back(std::to_string(trailing) + " lines after the last face ignored");
    }
    return m;
}

Mesh read_off(const std::string& path, ReadInfo* info) {
    const std::string data = detail::read_whole_file(path, kReader);
    return read_off_memory(data, path, info);
}

void write_off(const std::string& path, const Mesh& m, const WriteOptions&) {
    detail::validate_mesh_for_write(m, kWriter, path);
    AtomicFile f(path, kWriter);
    std::string buf = "OFF\n# written by normalflow\n";
    detail::append_uint(buf, m.positions.size());
    buf += ' ';
    detail::append_uint(buf, m.triangles.size());
    buf += " 0\n";
    detail::write_ascii_vertices_and_faces(f, buf, m);
    f.commit();
}

}  // namespace normalflow
