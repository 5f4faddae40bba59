// Stanford PLY reader and writer (see mesh_formats.h).
#include "io/formats/mesh_formats.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "io/formats/format_util.h"
#include "io/util/atomic_file.h"

namespace normalflow {

namespace {

constexpr std::string_view kReader = "read_ply";
constexpr std::string_view kWriter = "write_ply";

enum class PType : std::uint8_t { I8, U8, I16, U16, I32, U32, F32, F64 };

std::size_t type_size(PType t) {
    switch (t) {
        case PType::I8:
        case PType::U8: return 1;
        case PType::I16:
        case PType::U16: return 2;
        case PType::I32:
        case PType::U32:
        case PType::F32: return 4;
        case PType::F64: return 8;
    }
    return 1;
}

bool is_integer(PType t) { return t != PType::F32 && t != PType::F64; }

bool parse_type(std::string_view s, PType& t) {
    struct Entry {
        std::string_view name;
        PType type;
    };
    static constexpr Entry table[] = {
        {"char", PType::I8},   {"int8", PType::I8},     {"uchar", PType::U8},   {"uint8", PType::U8},
        {"short", PType::I16}, {"int16", PType::I16},   {"ushort", PType::U16}, {"uint16", PType::U16},
        {"int", PType::I32},   {"int32", PType::I32},   {"uint", PType::U32},   {"uint32", PType::U32},
        {"float", PType::F32}, {"float32", PType::F32}, {"double", PType::F64}, {"float64", PType::F64}};
    for (const auto& e : table)
        if (e.name == s) {
            t = e.type;
            return true;
        }
    return false;
}

struct Property {
    std::string name;
    PType type = PType::F32;  // scalar type, or the list's item type
    bool is_list = false;
    PType count_type = PType::U8;
};

struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::vector<Property> props;
    std::size_t line = 0;
};

/// A scalar of type t at p as double.
double load_double(const char* p, PType t, bool be) {
    switch (t) {
        case PType::I8: return double(std::int8_t(*p));
        case PType::U8: return double(std::uint8_t(*p));
        case PType::I16: return double(detail::load_scalar<std::int16_t>(p, be));
        case PType::U16: return double(detail::load_scalar<std::uint16_t>(p, be));
        case PType::I32: return double(detail::load_scalar<std::int32_t>(p, be));
        case PType::U32: return double(detail::load_scalar<std::uint32_t>(p, be));
        case PType::F32: return double(detail::load_scalar<float>(p, be));
        case PType::F64: return detail::load_scalar<double>(p, be);
    }
    return 0.0;
}

/// An integer scalar of type t at p (t must be an integer type).
std::int64_t load_int(const char* p, PType t, bool be) {
    switch (t) {
        case PType::I8: return std::int8_t(*p);
        case PType::U8: return std::uint8_t(*p);
        case PType::I16: return detail::load_scalar<std::int16_t>(p, be);
        case PType::U16: return detail::load_scalar<std::uint16_t>(p, be);
        case PType::I32: return detail::load_scalar<std::int32_t>(p, be);
        case PType::U32: return detail::load_scalar<std::uint32_t>(p, be);
        default: return -1;
    }
}

/// Converts a double coordinate to float; false if it is NaN, infinite or beyond float range.
bool to_float(double d, float& f) {
    if (!(std::fabs(d) <= double(std::numeric_limits<float>::max()))) return false;
    f = float(d);
    return true;
}

std::string printable(std::string_view s) {
    std::string r(s.substr(0, 32));
    for (char& c : r)
        if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
    return "'" + r + "'";
}

enum class Encoding { Ascii, BinaryLE, BinaryBE };

struct Header {
    Encoding encoding = Encoding::Ascii;
    std::vector<Element> elements;
    std::size_t data_offset = 0;  // first byte after end_header's newline
    std::size_t lines = 0;        // header lines (the ascii body starts at line lines + 1)
};

Header parse_header(std::string_view bytes, const std::string& name) {
    using detail::fail;
    using detail::fail_line;
    if (bytes.empty()) fail(kReader, name, "empty file");
    if (bytes.size() < 4 || bytes.substr(0, 3) != "ply" || (bytes[3] != '\n' && bytes[3] != '\r'))
        fail(kReader, name, "not a PLY file (does not start with 'ply')");
    Header h;
    bool have_format = false, have_end = false;
    std::size_t pos = 0, line = 0;
    while (pos < bytes.size()) {
        ++line;
        std::size_t eol = bytes.find('\n', pos);
        if (eol == std::string_view::npos) eol = bytes.size();
        std::string_view l = bytes.substr(pos, eol - pos);
        pos = eol < bytes.size() ? eol + 1 : eol;
        // split into whitespace-separated words
        std::vector<std::string_view> w;
        for (std::size_t i = 0; i < l.size();) {
            while (i < l.size() && detail::is_space(l[i])) ++i;
            std::size_t j = i;
            while (j < l.size() && !detail::is_space(l[j])) ++j;
            if (j > i) w.push_back(l.substr(i, j - i));
            i = j;
        }
        if (line == 1) continue;  // "ply"
        if (w.empty()) continue;
        if (w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "end_header") {
            have_end = true;
            break;
        }
        if (w[0] == "format") {
            if (w.size() < 3) fail_line(kReader, name, line, "malformed format line");
            if (w[1] == "ascii")
                h.encoding = Encoding::Ascii;
            else if (w[1] == "binary_little_endian")
                h.encoding = Encoding::BinaryLE;
            else if (w[1] == "binary_big_endian")
                h.encoding = Encoding::BinaryBE;
            else
                fail_line(kReader, name, line, "unknown format " + printable(w[1]));
            have_format = true;
        } else if (w[0] == "element") {
            if (w.size() != 3) fail_line(kReader, name, line, "malformed element line (expected 'element NAME COUNT')");
            Element e;
            e.name = std::string(w[1]);
            e.line = line;
            const char* s = w[2].data();
            const char* se = s + w[2].size();
            const auto r = std::from_chars(s, se, e.count);
            if (r.ec != std::errc{} || r.ptr != se)
                fail_line(kReader, name, line, "element count " + printable(w[2]) + " is not a non-negative integer");
            h.elements.push_back(std::move(e));
        } else if (w[0] == "property") {
            if (h.elements.empty()) fail_line(kReader, name, line, "property before any element");
            Property p;
            if (w.size() >= 2 && w[1] == "list") {
                if (w.size() != 5)
                    fail_line(kReader, name, line,
                              "malformed list property (expected 'property list COUNT_TYPE ITEM_TYPE NAME')");
                if (!parse_type(w[2], p.count_type) || !parse_type(w[3], p.type))
                    fail_line(kReader, name, line, "unknown property type");
                if (!is_integer(p.count_type))
                    fail_line(kReader, name, line, "list count type must be an integer type");
                p.is_list = true;
                p.name = std::string(w[4]);
            } else {
                if (w.size() != 3)
                    fail_line(kReader, name, line, "malformed property line (expected 'property TYPE NAME')");
                if (!parse_type(w[1], p.type))
                    fail_line(kReader, name, line, "unknown property type " + printable(w[1]));
                p.name = std::string(w[2]);
            }
            h.elements.back().props.push_back(std::move(p));
        } else {
            fail_line(kReader, name, line, "unexpected header line starting with " + printable(w[0]));
        }
    }
    if (!have_end) fail(kReader, name, "no end_header (truncated, or not a PLY file)");
    if (!have_format) fail(kReader, name, "no format line in the header");
    h.data_offset = pos;
    h.lines = line;
    return h;
}

/// Fails unless the elements' minimal sizes fit into `available` bytes (before allocating).
void check_counts(const Header& h, std::size_t available, const std::string& name) {
    const bool ascii = h.encoding == Encoding::Ascii;
    std::uint64_t left = available + (ascii ? 1 : 0);  // ascii: the last token needs no separator
    for (const Element& e : h.elements) {
        if (e.count == 0) continue;
        if (e.props.empty())
            detail::fail_line(kReader, name, e.line, "element '" + e.name + "' has entries but no properties");
        std::uint64_t min_bytes = 0;
        for (const Property& p : e.props) min_bytes += ascii ? 2 : type_size(p.is_list ? p.count_type : p.type);
        if (e.count > left / min_bytes)
            detail::fail_line(kReader, name, e.line,
                              "header claims " + std::to_string(e.count) + " " + e.name + " entries, more than the " +
                                  std::to_string(available) + " bytes of data can hold (truncated or corrupt file)");
        left -= e.count * min_bytes;
    }
}

// Vertex attribute slots: 0..2 normal x, y, z; 3..6 red, green, blue, alpha; 7..8 texture u, v.
constexpr int kSlotNormal = 0, kSlotColor = 3, kSlotTex = 7, kSlots = 9;

/// The attribute slot a vertex property name fills, or -1.
int attribute_slot(std::string_view n) {
    struct Entry {
        std::string_view name;
        int slot;
    };
    static constexpr Entry table[] = {{"nx", 0},
                                      {"ny", 1},
                                      {"nz", 2},
                                      {"normal_x", 0},
                                      {"normal_y", 1},
                                      {"normal_z", 2},
                                      {"red", 3},
                                      {"green", 4},
                                      {"blue", 5},
                                      {"alpha", 6},
                                      {"r", 3},
                                      {"g", 4},
                                      {"b", 5},
                                      {"a", 6},
                                      {"diffuse_red", 3},
                                      {"diffuse_green", 4},
                                      {"diffuse_blue", 5},
                                      {"diffuse_alpha", 6},
                                      {"s", 7},
                                      {"t", 8},
                                      {"u", 7},
                                      {"v", 8},
                                      {"texture_u", 7},
                                      {"texture_v", 8},
                                      {"texture_s", 7},
                                      {"texture_t", 8}};
    for (const auto& e : table)
        if (e.name == n) return e.slot;
    return -1;
}

struct Layout {
    const Element* vertex = nullptr;
    int xyz[3] = {-1, -1, -1};  // property indices of x, y, z in vertex
    const Element* face = nullptr;
    int indices = -1;       // property index of vertex_indices in face
    std::vector<int> slot;  // per vertex property: the attribute slot it fills, or -1
    bool normals = false, colors = false, texcoords = false;
};

/// Sizes m's attribute arrays for the attributes L found (alpha defaults to opaque).
void allocate_attributes(const Layout& L, Mesh& m) {
    const std::size_t n = m.positions.size();
    if (L.normals) m.normals.assign(n, Vec3f{});
    if (L.colors) m.colors.assign(n, Rgba8{255, 255, 255, 255});
    if (L.texcoords) m.texcoords.assign(n, TexCoord{0.0f, 0.0f});
}

/// Stores value v of a vertex property of type t into attribute slot `slot` of vertex i. Colours of
/// integer type are taken as 0..255 (uint16 as 0..65535), float colours as 0..1; non-finite normals
/// and texture coordinates become 0.
void store_attribute(const Layout& L, Mesh& m, std::size_t i, int slot, double v, PType t) {
    if (slot < kSlotColor) {
        if (L.normals) m.normals[i][slot - kSlotNormal] = std::isfinite(v) ? float(v) : 0.0f;
    } else if (slot < kSlotTex) {
        if (!L.colors) return;
        const double scaled = t == PType::U16 ? v / 257.0 : is_integer(t) ? v : v * 255.0;
        m.colors[i][std::size_t(slot - kSlotColor)] =
            std::uint8_t(std::lround(std::clamp(std::isfinite(scaled) ? scaled : 0.0, 0.0, 255.0)));
    } else if (L.texcoords) {
        m.texcoords[i][std::size_t(slot - kSlotTex)] = std::isfinite(v) ? float(v) : 0.0f;
    }
}

Layout find_layout(const Header& h, const std::string& name) {
    Layout L;
    for (const Element& e : h.elements) {
        if (e.name == "vertex" && !L.vertex) L.vertex = &e;
        if (e.name == "face" && !L.face) L.face = &e;
    }
    if (!L.vertex) detail::fail(kReader, name, "no 'vertex' element in the header");
    for (int i = 0; i < int(L.vertex->props.size()); ++i) {
        const Property& p = L.vertex->props[std::size_t(i)];
        for (int a = 0; a < 3; ++a)
            if (p.name.size() == 1 && p.name[0] == "xyz"[a] && L.xyz[a] < 0) {
                if (p.is_list)
                    detail::fail_line(kReader, name, L.vertex->line, "vertex property " + p.name + " is a list");
                L.xyz[a] = i;
            }
    }
    if (L.xyz[0] < 0 || L.xyz[1] < 0 || L.xyz[2] < 0)
        detail::fail_line(kReader, name, L.vertex->line, "vertex element lacks an x, y or z property");
    bool seen[kSlots] = {};
    L.slot.assign(L.vertex->props.size(), -1);
    for (std::size_t i = 0; i < L.vertex->props.size(); ++i) {
        const Property& p = L.vertex->props[i];
        const int s = p.is_list ? -1 : attribute_slot(p.name);
        if (s >= 0 && !seen[s]) {
            seen[s] = true;
            L.slot[i] = s;
        }
    }
    L.normals = seen[0] && seen[1] && seen[2];
    L.colors = seen[3] && seen[4] && seen[5];
    L.texcoords = seen[7] && seen[8];
    if (!L.face) detail::fail(kReader, name, "no 'face' element in the header (a point cloud, not a mesh)");
    for (int i = 0; i < int(L.face->props.size()); ++i) {
        const Property& p = L.face->props[std::size_t(i)];
        if ((p.name == "vertex_indices" || p.name == "vertex_index") && L.indices < 0) {
            if (!p.is_list)
                detail::fail_line(kReader, name, L.face->line, "face property " + p.name + " is not a list");
            if (!is_integer(p.type))
                detail::fail_line(kReader, name, L.face->line, "face indices must have an integer type");
            L.indices = i;
        }
    }
    if (L.indices < 0)
        detail::fail_line(kReader, name, L.face->line, "face element lacks a vertex_indices (or vertex_index) list");
    if (L.face->count == 0) detail::fail(kReader, name, "no faces (the face element has 0 entries)");
    return L;
}

struct FaceSink {
    Mesh& m;
    std::vector<std::uint32_t> poly;
    std::size_t split = 0;
};

// ------------------------------------------------------------------------------------- binary

void read_binary(std::string_view bytes, const Header& h, const Layout& L, const std::string& name, Mesh& m,
                 FaceSink& sink, std::size_t& trailing) {
    const bool be = h.encoding == Encoding::BinaryBE;
    const char* p = bytes.data() + h.data_offset;
    const char* const end = bytes.data() + bytes.size();
    auto truncated = [&](const Element& e, std::uint64_t i) {
        detail::fail(kReader, name,
                     "truncated file: " + e.name + " " + std::to_string(i) + " of " + std::to_string(e.count) +
                         " is incomplete");
    };
    const std::size_t nv = m.positions.size();
    for (const Element& e : h.elements) {
        if (e.count == 0) continue;
        bool fixed = true;
        std::size_t stride = 0;
        std::vector<std::size_t> offset(e.props.size());
        for (std::size_t k = 0; k < e.props.size(); ++k) {
            if (e.props[k].is_list) fixed = false;
            offset[k] = stride;
            stride += type_size(e.props[k].type);
        }
        if (fixed) {
            if (std::uint64_t(end - p) / stride < e.count) truncated(e, std::uint64_t(end - p) / stride);
            if (&e == L.vertex) {
                const Property* px[3] = {&e.props[std::size_t(L.xyz[0])], &e.props[std::size_t(L.xyz[1])],
                                         &e.props[std::size_t(L.xyz[2])]};
                const std::size_t ox[3] = {offset[std::size_t(L.xyz[0])], offset[std::size_t(L.xyz[1])],
                                           offset[std::size_t(L.xyz[2])]};
                const bool all_float =
                    px[0]->type == PType::F32 && px[1]->type == PType::F32 && px[2]->type == PType::F32;
                for (std::size_t i = 0; i < nv; ++i, p += stride) {
                    for (std::size_t k = 0; k < e.props.size(); ++k)
                        if (L.slot[k] >= 0)
                            store_attribute(L, m, i, L.slot[k], load_double(p + offset[k], e.props[k].type, be),
                                            e.props[k].type);
                    Vec3f& v = m.positions[i];
                    if (all_float) {
                        v = {detail::load_scalar<float>(p + ox[0], be), detail::load_scalar<float>(p + ox[1], be),
                             detail::load_scalar<float>(p + ox[2], be)};
                        if (!is_finite(v))
                            detail::fail(kReader, name,
                                         "vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
                    } else {
                        for (int a = 0; a < 3; ++a)
                            if (!to_float(load_double(p + ox[a], px[a]->type, be), v[a]))
                                detail::fail(kReader, name,
                                             "vertex " + std::to_string(i) +
                                                 " has a NaN, infinite or out-of-float-range coordinate");
                    }
                }
            } else {
                p += e.count * stride;
            }
            continue;
        }
        // elements with lists: record by record
        const bool is_face = &e == L.face;
        const bool is_vertex = &e == L.vertex;
        for (std::uint64_t i = 0; i < e.count; ++i) {
            for (std::size_t k = 0; k < e.props.size(); ++k) {
                const Property& pr = e.props[k];
                if (!pr.is_list) {
                    const std::size_t sz = type_size(pr.type);
                    if (std::size_t(end - p) < sz) truncated(e, i);
                    if (is_vertex) {
                        for (int a = 0; a < 3; ++a)
                            if (int(k) == L.xyz[a] && !to_float(load_double(p, pr.type, be), m.positions[i][a]))
                                detail::fail(kReader, name,
                                             "vertex " + std::to_string(i) +
                                                 " has a NaN, infinite or out-of-float-range coordinate");
                        if (L.slot[k] >= 0)
                            store_attribute(L, m, std::size_t(i), L.slot[k], load_double(p, pr.type, be), pr.type);
                    }
                    p += sz;
                    continue;
                }
                const std::size_t csz = type_size(pr.count_type), isz = type_size(pr.type);
                if (std::size_t(end - p) < csz) truncated(e, i);
                const std::int64_t n = load_int(p, pr.count_type, be);
                p += csz;
                if (n < 0) detail::fail(kReader, name, e.name + " " + std::to_string(i) + ": negative list length");
                if (std::uint64_t(end - p) / isz < std::uint64_t(n)) truncated(e, i);
                if (is_face && int(k) == L.indices) {
                    if (n < 3)
                        detail::fail(kReader, name,
                                     "face " + std::to_string(i) + " has " + std::to_string(n) +
                                         " corners, expected at least 3");
                    sink.poly.resize(std::size_t(n));
                    for (std::int64_t c = 0; c < n; ++c, p += isz) {
                        const std::int64_t v = load_int(p, pr.type, be);
                        if (v < 0 || std::uint64_t(v) >= nv)
                            detail::fail(kReader, name,
                                         "face " + std::to_string(i) + ": vertex index " + std::to_string(v) +
                                             " out of range (the file has " + std::to_string(nv) + " vertices)");
                        sink.poly[std::size_t(c)] = std::uint32_t(v);
                    }
                    if (n > 3) ++sink.split;
                    detail::push_fan(m.triangles, sink.poly.data(), sink.poly.size());
                } else {
                    p += std::size_t(n) * isz;
                }
            }
        }
    }
    trailing = std::size_t(end - p);
}

// ------------------------------------------------------------------------------------- ascii

struct Tokens {
    const char* p;
    const char* end;
    std::size_t line;

    /// Skips whitespace and newlines up to the next token (or the end of the data).
    void skip() {
        while (p < end && (detail::is_space(*p) || *p == '\n')) {
            if (*p == '\n') ++line;
            ++p;
        }
    }
    /// Next whitespace-separated token; empty at the end of the data.
    std::string_view next() {
        skip();
        const char* s = p;
        while (p < end && !detail::is_space(*p) && *p != '\n') ++p;
        return {s, std::size_t(p - s)};
    }
};

void read_ascii(std::string_view bytes, const Header& h, const Layout& L, const std::string& name, Mesh& m,
                FaceSink& sink) {
    using detail::fail_line;
    Tokens tk{bytes.data() + h.data_offset, bytes.data() + bytes.size(), h.lines + 1};
    const std::size_t nv = m.positions.size();
    // Line where the current record starts: a record cut short by the end of the data is reported
    // there (the line that is incomplete), not on the line after the last newline.
    std::size_t record_line = tk.line;
    auto need = [&](const Element& e, std::uint64_t i) {
        const std::string_view t = tk.next();
        if (t.empty())
            fail_line(kReader, name, record_line,
                      "truncated file: " + e.name + " " + std::to_string(i) + " of " + std::to_string(e.count) +
                          " is incomplete");
        return t;
    };
    auto integer = [&](std::string_view t) {
        std::int64_t v = 0;
        const char* s = t.data();
        if (!detail::parse_int(s, t.data() + t.size(), v) || s != t.data() + t.size())
            fail_line(kReader, name, tk.line, "expected an integer, found " + printable(t));
        return v;
    };
    auto number = [&](std::string_view t) -> double {
        double v = 0;
        const char* s = t.data();
        if (s < t.data() + t.size() && *s == '+') ++s;
        const auto r = std::from_chars(s, t.data() + t.size(), v);
        if ((r.ec != std::errc{} && r.ec != std::errc::result_out_of_range) || r.ptr != t.data() + t.size())
            fail_line(kReader, name, tk.line, "expected a number, found " + printable(t));
        return v;
    };
    for (const Element& e : h.elements) {
        const bool is_vertex = &e == L.vertex, is_face = &e == L.face;
        for (std::uint64_t i = 0; i < e.count; ++i) {
            tk.skip();
            record_line = tk.line;
            for (std::size_t k = 0; k < e.props.size(); ++k) {
                const Property& pr = e.props[k];
                if (!pr.is_list) {
                    const std::string_view t = need(e, i);
                    int axis = -1;
                    if (is_vertex)
                        for (int a = 0; a < 3; ++a)
                            if (int(k) == L.xyz[a]) axis = a;
                    if (axis >= 0) {
                        const char* s = t.data();
                        float& f = m.positions[i][axis];
                        if (!detail::parse_float(s, t.data() + t.size(), f) || s != t.data() + t.size())
                            fail_line(kReader, name, tk.line, "expected a coordinate, found " + printable(t));
                        if (!std::isfinite(f))
                            fail_line(kReader, name, tk.line,
                                      "vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
                    } else if (is_vertex && L.slot[k] >= 0) {
                        store_attribute(L, m, std::size_t(i), L.slot[k], number(t), pr.type);
                    } else {
                        number(t);
                    }
                    continue;
                }
                const std::int64_t n = integer(need(e, i));
                if (n < 0) fail_line(kReader, name, tk.line, "negative list length");
                if (is_face && int(k) == L.indices) {
                    if (n < 3)
                        fail_line(kReader, name, tk.line,
                                  "face has " + std::to_string(n) + " corners, expected at least 3");
                    if (std::uint64_t(n) > bytes.size()) fail_line(kReader, name, tk.line, "absurd list length");
                    sink.poly.resize(std::size_t(n));
                    for (std::int64_t c = 0; c < n; ++c) {
                        const std::string_view t = tk.next();
                        if (t.empty())
                            fail_line(kReader, name, record_line,
                                      "truncated file: face " + std::to_string(i) + " of " + std::to_string(e.count) +
                                          " has " + std::to_string(c) + " of its " + std::to_string(n) + " indices");
                        const std::int64_t v = integer(t);
                        if (v < 0 || std::uint64_t(v) >= nv)
                            fail_line(kReader, name, tk.line,
                                      "vertex index " + std::to_string(v) + " out of range (the file has " +
                                          std::to_string(nv) + " vertices)");
                        sink.poly[std::size_t(c)] = std::uint32_t(v);
                    }
                    if (n > 3) ++sink.split;
                    detail::push_fan(m.triangles, sink.poly.data(), sink.poly.size());
                } else {
                    for (std::int64_t c = 0; c < n; ++c) number(need(e, i));
                }
            }
        }
    }
    const std::string_view rest = tk.next();
    if (!rest.empty())
        fail_line(kReader, name, tk.line, "unexpected data " + printable(rest) + " after the last element");
}

}  // namespace

Mesh read_ply_memory(std::string_view bytes, const std::string& name, ReadInfo* info) {
    const Header h = parse_header(bytes, name);
    const Layout L = find_layout(h, name);
    // An absurd count is reported with the file size, before anything is allocated.
    check_counts(h, bytes.size() - h.data_offset, name);
    if (L.vertex->count > std::numeric_limits<std::uint32_t>::max())
        detail::fail_line(kReader, name, L.vertex->line,
                          "header claims " + std::to_string(L.vertex->count) + " vertices, more than 2^32-1");

    Mesh m;
    m.positions.resize(std::size_t(L.vertex->count));
    m.triangles.reserve(std::size_t(L.face->count));
    allocate_attributes(L, m);
    FaceSink sink{m, {}, 0};
    std::size_t trailing = 0;
    if (h.encoding == Encoding::Ascii) {
        if (std::memchr(bytes.data() + h.data_offset, 0, bytes.size() - h.data_offset))
            detail::fail(kReader, name, "binary data (NUL byte) in an ascii PLY file");
        read_ascii(bytes, h, L, name, m, sink);
    } else {
        read_binary(bytes, h, L, name, m, sink, trailing);
    }

    if (info) {
        *info = ReadInfo{};
        info->format = h.encoding == Encoding::Ascii      ? "ply-ascii"
                       : h.encoding == Encoding::BinaryLE ? "ply-binary-le"
                                                          : "ply-binary-be";
        info->file_vertices = m.positions.size();
        info->file_faces = std::size_t(L.face->count);
        info->polygons_split = sink.split;
        if (sink.split) info->warnings.push_back(detail::split_warning(sink.split));
        if (trailing) info->warnings.push_back(std::to_string(trailing) + " bytes after the last element ignored");
    }
    return m;
}

Mesh read_ply(const std::string& path, ReadInfo* info) {
    const std::string data = detail::read_whole_file(path, kReader);
    return read_ply_memory(data, path, info);
}

void write_ply(const std::string& path, const Mesh& m, const WriteOptions& opt) {
    detail::validate_mesh_for_write(m, kWriter, path);
    AtomicFile f(path, kWriter);
    std::string buf;
    buf += "ply\nformat ";
    buf += opt.binary ? "binary_little_endian" : "ascii";
    buf += " 1.0\ncomment written by normalflow\nelement vertex ";
    detail::append_uint(buf, m.positions.size());
    buf += "\nproperty float x\nproperty float y\nproperty float z\n";
    if (m.has_normals()) buf += "property float nx\nproperty float ny\nproperty float nz\n";
    if (m.has_colors()) buf += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
    if (m.has_texcoords()) buf += "property float s\nproperty float t\n";
    buf += "element face ";
    detail::append_uint(buf, m.triangles.size());
    buf += "\nproperty list uchar int vertex_indices\nend_header\n";
    constexpr std::size_t kChunk = 1 << 20;
    auto flush = [&] {
        if (buf.size() >= kChunk) {
            f.write(buf);
            buf.clear();
        }
    };
    if (opt.binary) {
        for (std::size_t i = 0; i < m.positions.size(); ++i) {
            const Vec3f& v = m.positions[i];
            detail::append_le(buf, v.x);
            detail::append_le(buf, v.y);
            detail::append_le(buf, v.z);
            if (m.has_normals())
                for (int a = 0; a < 3; ++a) detail::append_le(buf, m.normals[i][a]);
            if (m.has_colors())
                for (const std::uint8_t c : m.colors[i]) buf += char(c);
            if (m.has_texcoords())
                for (const float c : m.texcoords[i]) detail::append_le(buf, c);
            flush();
        }
        for (const Tri& t : m.triangles) {
            buf += char(3);
            for (const std::uint32_t i : t) detail::append_le(buf, std::int32_t(i));
            flush();
        }
    } else {
        detail::write_ascii_vertices_and_faces(f, buf, m, /*attributes=*/true);
    }
    f.write(buf);
    f.commit();
}

}  // namespace normalflow
