#include "io/draco/gltf_check.h"

#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/errors.h"

namespace normalflow {

namespace {

// ---- A small JSON reader (RFC 8259), enough to check a glTF asset. ----

struct JValue {
    enum class Type { Null, Bool, Number, String, Array, Object };
    Type type = Type::Null;
    bool b = false;
    double num = 0;
    std::string str;
    std::vector<JValue> items;      // array elements, or object member values
    std::vector<std::string> keys;  // object member names (keys[i] names items[i])

    const JValue* get(std::string_view key) const {
        if (type != Type::Object) return nullptr;
        for (std::size_t i = 0; i < keys.size(); ++i)
            if (keys[i] == key) return &items[i];
        return nullptr;
    }
};

class JsonReader {
public:
    JsonReader(std::string_view text, const std::string& who) : s_(text), who_(who) {}

    JValue parse() {
        JValue v = value(0);
        skip_ws();
        if (pos_ != s_.size()) fail("unexpected text after the JSON value");
        return v;
    }

private:
    static constexpr int kMaxDepth = 64;
    std::string_view s_;
    std::size_t pos_ = 0;
    const std::string& who_;

    [[noreturn]] void fail(const std::string& what) const {
        throw InvalidInput(who_ + ": glTF JSON, byte " + std::to_string(pos_) + ": " + what);
    }
    void skip_ws() {
        while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\n' || s_[pos_] == '\r'))
            ++pos_;
    }
    bool eat(char c) {
        skip_ws();
        if (pos_ < s_.size() && s_[pos_] == c) {
            ++pos_;
            return true;
        }
        return false;
    }
    void expect(char c) {
        if (!eat(c)) fail(std::string("expected '") + c + "'");
    }
    bool literal(std::string_view word) {
        if (s_.substr(pos_, word.size()) != word) return false;
        pos_ += word.size();
        return true;
    }

    JValue value(int depth) {
        if (depth > kMaxDepth) fail("nesting deeper than " + std::to_string(kMaxDepth));
        skip_ws();
        if (pos_ >= s_.size()) fail("unexpected end of the JSON text");
        JValue v;
        const char c = s_[pos_];
        if (c == '{') {
            ++pos_;
            v.type = JValue::Type::Object;
            if (eat('}')) return v;
            do {
                skip_ws();
                if (pos_ >= s_.size() || s_[pos_] != '"') fail("expected a member name");
                std::string key = string();
                expect(':');
                v.keys.push_back(std::move(key));
                v.items.push_back(value(depth + 1));
            } while (eat(','));
            expect('}');
        } else if (c == '[') {
            ++pos_;
            v.type = JValue::Type::Array;
            if (eat(']')) return v;
            do v.items.push_back(value(depth + 1));
            while (eat(','));
            expect(']');
        } else if (c == '"') {
            v.type = JValue::Type::String;
            v.str = string();
        } else if (literal("true")) {
            v.type = JValue::Type::Bool;
            v.b = true;
        } else if (literal("false")) {
            v.type = JValue::Type::Bool;
        } else if (literal("null")) {
        } else if (c == '-' || (c >= '0' && c <= '9')) {
            v.type = JValue::Type::Number;
            const char* b = s_.data() + pos_;
            const char* e = s_.data() + s_.size();
            const auto r = std::from_chars(b, e, v.num);
            if (r.ec == std::errc::result_out_of_range)
                v.num = std::numeric_limits<double>::infinity();
            else if (r.ec != std::errc())
                fail("bad number");
            pos_ += std::size_t(r.ptr - b);
        } else {
            fail(std::string("unexpected character '") + (c >= 32 && c < 127 ? std::string(1, c) : "?") + "'");
        }
        return v;
    }

    std::string string() {
        ++pos_;  // opening quote
        std::string out;
        while (true) {
            if (pos_ >= s_.size()) fail("unterminated string");
            const char c = s_[pos_++];
            if (c == '"') return out;
            if (static_cast<unsigned char>(c) < 0x20) fail("control character in a string");
            if (c != '\\') {
                out.push_back(c);
                continue;
            }
            if (pos_ >= s_.size()) fail("unterminated string");
            const char e = s_[pos_++];
            switch (e) {
                case '"':
                case '\\':
                case '/': out.push_back(e); break;
                case 'b': out.push_back('\b'); break;
                case 'f': out.push_back('\f'); break;
                case 'n': out.push_back('\n'); break;
                case 'r': out.push_back('\r'); break;
                case 't': out.push_back('\t'); break;
                case 'u': {
                    if (s_.size() - pos_ < 4) fail("bad \\u escape");
                    unsigned cp = 0;
                    for (int k = 0; k < 4; ++k) {
                        const char h = s_[pos_++];
                        cp <<= 4;
                        if (h >= '0' && h <= '9')
                            cp |= unsigned(h - '0');
                        else if (h >= 'a' && h <= 'f')
                            cp |= unsigned(h - 'a' + 10);
                        else if (h >= 'A' && h <= 'F')
                            cp |= unsigned(h - 'A' + 10);
                        else
                            fail("bad \\u escape");
                    }
                    // UTF-8 (surrogates are kept as-is: names only need to compare equal).
                    if (cp < 0x80)
                        out.push_back(char(cp));
                    else if (cp < 0x800)
                        out += {char(0xC0 | (cp >> 6)), char(0x80 | (cp & 0x3F))};
                    else
                        out += {char(0xE0 | (cp >> 12)), char(0x80 | ((cp >> 6) & 0x3F)), char(0x80 | (cp & 0x3F))};
                    break;
                }
                default: fail("bad escape in a string");
            }
        }
    }
};

// ---- glTF checks ----

class Checker {
public:
    Checker(const JValue& root, std::optional<std::string_view> bin, const std::string& base_dir,
            const std::string& who)
        : root_(root), bin_(bin), base_dir_(base_dir), who_(who) {}

    void run() {
        if (root_.type != JValue::Type::Object) fail("the glTF JSON is not an object");
        buffers();
        buffer_views();
        accessors();
        meshes();
        nodes_and_scenes();
        images_and_textures();
    }

private:
    const JValue& root_;
    std::optional<std::string_view> bin_;
    const std::string& base_dir_;
    const std::string& who_;
    std::vector<std::uint64_t> buffer_len_;
    std::vector<std::string> buffer_data_;  // external and data: buffers, loaded for index checks
    std::vector<std::string_view> buffer_bytes_;
    struct View {
        std::uint64_t buffer = 0, offset = 0, length = 0, stride = 0;
    };
    std::vector<View> views_;
    struct Accessor {
        bool has_view = false;
        std::uint64_t view = 0, offset = 0, count = 0, elem = 0, comp = 0, component_type = 0;
        std::string type;
    };
    std::vector<Accessor> acc_;

    [[noreturn]] void fail(const std::string& what) const { throw InvalidInput(who_ + ": " + what); }

    const std::vector<JValue>* array(const JValue& parent, std::string_view key, const std::string& where) const {
        const JValue* v = parent.get(key);
        if (!v) return nullptr;
        if (v->type != JValue::Type::Array) fail(where + "\"" + std::string(key) + "\" is not an array");
        return &v->items;
    }
    /// An integer member in [lo, hi]; `def` if absent (or fails if def is nullopt).
    std::uint64_t integer(const JValue& obj, std::string_view key, const std::string& where,
                          std::optional<std::uint64_t> def, std::uint64_t lo = 0,
                          std::uint64_t hi = (std::uint64_t(1) << 53)) const {
        const JValue* v = obj.get(key);
        if (!v) {
            if (!def) fail(where + ": missing \"" + std::string(key) + "\"");
            return *def;
        }
        if (v->type != JValue::Type::Number || !(v->num >= double(lo)) || !(v->num <= double(hi)) ||
            v->num != std::floor(v->num))
            fail(where + ": \"" + std::string(key) + "\" must be an integer in [" + std::to_string(lo) + ", " +
                 std::to_string(hi) + "]");
        return std::uint64_t(v->num);
    }
    std::size_t count_of(std::string_view key) const {
        const JValue* v = root_.get(key);
        return v && v->type == JValue::Type::Array ? v->items.size() : 0;
    }
    /// An index member that must be < the size of the top-level array `target`.
    std::optional<std::uint64_t> index(const JValue& obj, std::string_view key, const std::string& where,
                                       std::string_view target, bool required = false) const {
        if (!obj.get(key) && !required) return std::nullopt;
        const std::uint64_t i = integer(obj, key, where, std::nullopt);
        if (i >= count_of(target))
            fail(where + ": " + std::string(key) + " " + std::to_string(i) + " does not exist (" +
                 std::to_string(count_of(target)) + " " + std::string(target) + ")");
        return i;
    }
    void object(const JValue& v, const std::string& where) const {
        if (v.type != JValue::Type::Object) fail(where + " is not an object");
    }

    static std::optional<std::string> base64_decode(std::string_view s) {
        std::string out;
        out.reserve(s.size() / 4 * 3);
        unsigned acc = 0;
        int bits = 0;
        for (char c : s) {
            int d;
            if (c >= 'A' && c <= 'Z')
                d = c - 'A';
            else if (c >= 'a' && c <= 'z')
                d = c - 'a' + 26;
            else if (c >= '0' && c <= '9')
                d = c - '0' + 52;
            else if (c == '+' || c == '-')
                d = 62;
            else if (c == '/' || c == '_')
                d = 63;
            else if (c == '=')
                break;
            else
                return std::nullopt;
            acc = (acc << 6) | unsigned(d);
            bits += 6;
            if (bits >= 8) {
                bits -= 8;
                out.push_back(char((acc >> bits) & 0xFF));
            }
        }
        return out;
    }

    void buffers() {
        const auto* bs = array(root_, "buffers", "");
        if (!bs) return;
        buffer_data_.resize(bs->size());
        for (std::size_t i = 0; i < bs->size(); ++i) {
            const std::string where = "buffer " + std::to_string(i);
            const JValue& b = (*bs)[i];
            object(b, where);
            const std::uint64_t len = integer(b, "byteLength", where, std::nullopt, 1);
            buffer_len_.push_back(len);
            std::string_view data;
            const JValue* uri = b.get("uri");
            if (!uri) {
                if (i != 0 || !bin_) fail(where + ": no uri, and it is not the GLB BIN chunk");
                data = *bin_;
            } else {
                if (uri->type != JValue::Type::String) fail(where + ": uri is not a string");
                const std::string& u = uri->str;
                if (u.rfind("data:", 0) == 0) {
                    const auto comma = u.find(',');
                    if (comma == std::string::npos || u.substr(0, comma).find(";base64") == std::string::npos)
                        fail(where + ": data URI is not base64");
                    auto dec = base64_decode(std::string_view(u).substr(comma + 1));
                    if (!dec) fail(where + ": data URI has bad base64");
                    buffer_data_[i] = std::move(*dec);
                } else {
                    if (u.find("://") != std::string::npos) fail(where + ": remote uri \"" + u + "\" is not supported");
                    // URIs are percent-encoded ("my%20mesh.bin").
                    std::string file;
                    for (std::size_t k = 0; k < u.size(); ++k) {
                        unsigned hex = 0;
                        if (u[k] == '%' && k + 2 < u.size() &&
                            std::from_chars(u.data() + k + 1, u.data() + k + 3, hex, 16).ptr == u.data() + k + 3) {
                            file.push_back(char(hex));
                            k += 2;
                        } else {
                            file.push_back(u[k]);
                        }
                    }
                    const std::filesystem::path p = std::filesystem::path(base_dir_.empty() ? "." : base_dir_) / file;
                    std::ifstream f(p, std::ios::binary);
                    if (!f) fail(where + ": cannot open its file " + p.string());
                    buffer_data_[i].assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
                }
                data = buffer_data_[i];
            }
            if (data.size() < len)
                fail(where + ": byteLength " + std::to_string(len) + " but its data has only " +
                     std::to_string(data.size()) + " bytes");
            buffer_bytes_.push_back(data);
        }
    }

    void buffer_views() {
        const auto* vs = array(root_, "bufferViews", "");
        if (!vs) return;
        for (std::size_t i = 0; i < vs->size(); ++i) {
            const std::string where = "bufferView " + std::to_string(i);
            const JValue& v = (*vs)[i];
            object(v, where);
            View w;
            w.buffer = *index(v, "buffer", where, "buffers", true);
            w.offset = integer(v, "byteOffset", where, 0);
            w.length = integer(v, "byteLength", where, std::nullopt, 1);
            w.stride = integer(v, "byteStride", where, 0, 0, 252);
            if (v.get("byteStride") && (w.stride < 4 || w.stride % 4 != 0))
                fail(where + ": byteStride " + std::to_string(w.stride) + " is not a multiple of 4 in [4, 252]");
            if (w.offset + w.length > buffer_len_[w.buffer])
                fail(where + ": bytes [" + std::to_string(w.offset) + ", " + std::to_string(w.offset + w.length) +
                     ") lie outside buffer " + std::to_string(w.buffer) + " (" + std::to_string(buffer_len_[w.buffer]) +
                     " bytes)");
            views_.push_back(w);
        }
    }

    static std::uint64_t component_size(std::uint64_t ct) {
        switch (ct) {
            case 5120:
            case 5121: return 1;
            case 5122:
            case 5123: return 2;
            case 5125:
            case 5126: return 4;
            default: return 0;
        }
    }

    void accessors() {
        const auto* as = array(root_, "accessors", "");
        if (!as) return;
        for (std::size_t i = 0; i < as->size(); ++i) {
            const std::string where = "accessor " + std::to_string(i);
            const JValue& a = (*as)[i];
            object(a, where);
            Accessor x;
            x.component_type = integer(a, "componentType", where, std::nullopt);
            x.comp = component_size(x.component_type);
            if (x.comp == 0) fail(where + ": componentType " + std::to_string(x.component_type) + " is not valid");
            const JValue* t = a.get("type");
            if (!t || t->type != JValue::Type::String) fail(where + ": missing \"type\"");
            x.type = t->str;
            std::uint64_t cols = 1, rows = 0;
            if (x.type == "SCALAR")
                rows = 1;
            else if (x.type == "VEC2")
                rows = 2;
            else if (x.type == "VEC3")
                rows = 3;
            else if (x.type == "VEC4")
                rows = 4;
            else if (x.type == "MAT2")
                rows = cols = 2;
            else if (x.type == "MAT3")
                rows = cols = 3;
            else if (x.type == "MAT4")
                rows = cols = 4;
            else
                fail(where + ": type \"" + x.type + "\" is not valid");
            // Matrix columns start on 4-byte boundaries (glTF 2.0, 3.6.2.4).
            x.elem = cols == 1 ? rows * x.comp : cols * ((rows * x.comp + 3) / 4 * 4);
            x.count = integer(a, "count", where, std::nullopt, 1, std::uint64_t(1) << 40);
            x.offset = integer(a, "byteOffset", where, 0);
            if (const auto v = index(a, "bufferView", where, "bufferViews")) {
                x.has_view = true;
                x.view = *v;
                const View& w = views_[x.view];
                const std::uint64_t stride = w.stride ? w.stride : x.elem;
                const std::uint64_t need = x.offset + (x.count - 1) * stride + x.elem;
                if (need > w.length)
                    fail(where + ": count " + std::to_string(x.count) + " with stride " + std::to_string(stride) +
                         " needs " + std::to_string(need) + " bytes from byte 0, but bufferView " +
                         std::to_string(x.view) + " has " + std::to_string(w.length));
            }
            if (const JValue* sp = a.get("sparse")) {
                object(*sp, where + " sparse");
                for (const char* part : {"indices", "values"}) {
                    const JValue* p = sp->get(part);
                    if (!p) fail(where + ": sparse without " + part);
                    object(*p, where + " sparse " + part);
                    index(*p, "bufferView", where + " sparse " + part, "bufferViews", true);
                }
            }
            acc_.push_back(x);
        }
    }

    std::uint64_t read_index(const Accessor& a, std::uint64_t k) const {
        const View& w = views_[a.view];
        const std::uint64_t stride = w.stride ? w.stride : a.elem;
        const char* p = buffer_bytes_[w.buffer].data() + w.offset + a.offset + k * stride;
        if (a.comp == 1) return static_cast<unsigned char>(*p);
        if (a.comp == 2) {
            std::uint16_t v;
            std::memcpy(&v, p, 2);
            return v;
        }
        std::uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
    }

    static const char* expected_type(const std::string& semantic) {
        if (semantic == "POSITION" || semantic == "NORMAL") return "VEC3";
        if (semantic == "TANGENT") return "VEC4";
        if (semantic.rfind("TEXCOORD_", 0) == 0) return "VEC2";
        if (semantic.rfind("JOINTS_", 0) == 0 || semantic.rfind("WEIGHTS_", 0) == 0) return "VEC4";
        return nullptr;
    }

    void meshes() {
        const auto* ms = array(root_, "meshes", "");
        if (!ms) return;
        for (std::size_t i = 0; i < ms->size(); ++i) {
            const std::string mwhere = "mesh " + std::to_string(i);
            object((*ms)[i], mwhere);
            const auto* ps = array((*ms)[i], "primitives", mwhere + ": ");
            if (!ps) fail(mwhere + ": no primitives");
            for (std::size_t j = 0; j < ps->size(); ++j) {
                const std::string where = mwhere + " primitive " + std::to_string(j);
                const JValue& p = (*ps)[j];
                object(p, where);
                integer(p, "mode", where, 4, 0, 6);
                const JValue* draco = nullptr;
                if (const JValue* ext = p.get("extensions")) {
                    object(*ext, where + " extensions");
                    draco = ext->get("KHR_draco_mesh_compression");
                }
                if (draco) {
                    object(*draco, where + " KHR_draco_mesh_compression");
                    index(*draco, "bufferView", where + " KHR_draco_mesh_compression", "bufferViews", true);
                    const JValue* at = draco->get("attributes");
                    if (!at) fail(where + ": KHR_draco_mesh_compression without attributes");
                    object(*at, where + " KHR_draco_mesh_compression attributes");
                    for (std::size_t k = 0; k < at->keys.size(); ++k) {
                        const JValue& id = at->items[k];
                        if (id.type != JValue::Type::Number || id.num < 0 || id.num > 1e9 ||
                            id.num != std::floor(id.num))
                            fail(where + ": Draco attribute id of " + at->keys[k] + " is not a non-negative integer");
                    }
                }
                const JValue* at = p.get("attributes");
                if (!at) fail(where + ": no attributes");
                object(*at, where + " attributes");
                std::optional<std::uint64_t> vertices;
                for (const std::string& semantic : at->keys) {
                    const std::uint64_t a = *index(*at, semantic, where + " attribute", "accessors", true);
                    const Accessor& x = acc_[a];
                    const char* want = expected_type(semantic);
                    if (want && x.type != want && !(semantic.rfind("COLOR_", 0) == 0))
                        fail(where + ": attribute " + semantic + " is " + x.type + ", expected " + want);
                    if (semantic.rfind("COLOR_", 0) == 0 && x.type != "VEC3" && x.type != "VEC4")
                        fail(where + ": attribute " + semantic + " is " + x.type + ", expected VEC3 or VEC4");
                    if (!draco && !x.has_view)
                        fail(where + ": attribute " + semantic + " (accessor " + std::to_string(a) +
                             ") has no bufferView (not supported)");
                    if (vertices && *vertices != x.count)
                        fail(where + ": attribute " + semantic + " has " + std::to_string(x.count) +
                             " elements, the others " + std::to_string(*vertices));
                    vertices = x.count;
                }
                if (!at->get("POSITION")) fail(where + ": no POSITION attribute");
                const auto ia = index(p, "indices", where, "accessors");
                if (!ia || draco) continue;
                const Accessor& x = acc_[*ia];
                if (x.type != "SCALAR" ||
                    (x.component_type != 5121 && x.component_type != 5123 && x.component_type != 5125))
                    fail(where + ": indices accessor " + std::to_string(*ia) +
                         " is not SCALAR unsigned byte/short/int");
                if (!x.has_view) fail(where + ": indices accessor " + std::to_string(*ia) + " has no bufferView");
                for (std::uint64_t k = 0; k < x.count; ++k) {
                    const std::uint64_t v = read_index(x, k);
                    if (v >= *vertices)
                        fail(where + ": index " + std::to_string(k) + " is " + std::to_string(v) +
                             ", but POSITION has " + std::to_string(*vertices) + " elements");
                }
            }
        }
    }

    void nodes_and_scenes() {
        const std::size_t n = count_of("nodes");
        std::vector<std::int64_t> parent(n, -1);
        if (const auto* ns = array(root_, "nodes", "")) {
            for (std::size_t i = 0; i < ns->size(); ++i) {
                const std::string where = "node " + std::to_string(i);
                const JValue& nd = (*ns)[i];
                object(nd, where);
                index(nd, "mesh", where, "meshes");
                if (const auto* ch = array(nd, "children", where + ": ")) {
                    for (const JValue& c : *ch) {
                        if (c.type != JValue::Type::Number || c.num < 0 || c.num >= double(n) ||
                            c.num != std::floor(c.num))
                            fail(where + ": a child is not an existing node");
                        const auto k = std::size_t(c.num);
                        if (parent[k] >= 0 || k == i)
                            fail(where + ": node " + std::to_string(k) +
                                 " has more than one parent (or is its own child)");
                        parent[k] = std::int64_t(i);
                    }
                }
            }
        }
        // Cycles: every node has at most one parent, so walk up from each node until a root or a node
        // known to reach one; meeting a node of the current walk again means a cycle.
        std::vector<char> state(n, 0);  // 0 unknown, 1 on the current walk, 2 reaches a root
        std::vector<std::size_t> walk;
        for (std::size_t i = 0; i < n; ++i) {
            walk.clear();
            for (std::size_t k = i;;) {
                if (state[k] == 2) break;
                if (state[k] == 1) fail("node hierarchy has a cycle through node " + std::to_string(k));
                state[k] = 1;
                walk.push_back(k);
                if (parent[k] < 0) break;
                k = std::size_t(parent[k]);
            }
            for (std::size_t w : walk) state[w] = 2;
        }
        if (const auto* ss = array(root_, "scenes", "")) {
            for (std::size_t i = 0; i < ss->size(); ++i) {
                const std::string where = "scene " + std::to_string(i);
                object((*ss)[i], where);
                if (const auto* nodes = array((*ss)[i], "nodes", where + ": "))
                    for (const JValue& c : *nodes)
                        if (c.type != JValue::Type::Number || c.num < 0 || c.num >= double(n) ||
                            c.num != std::floor(c.num))
                            fail(where + ": a root is not an existing node");
            }
        }
        index(root_, "scene", "the default scene", "scenes");
    }

    void images_and_textures() {
        if (const auto* is = array(root_, "images", ""))
            for (std::size_t i = 0; i < is->size(); ++i) {
                object((*is)[i], "image " + std::to_string(i));
                index((*is)[i], "bufferView", "image " + std::to_string(i), "bufferViews");
            }
        if (const auto* ts = array(root_, "textures", ""))
            for (std::size_t i = 0; i < ts->size(); ++i) {
                object((*ts)[i], "texture " + std::to_string(i));
                index((*ts)[i], "source", "texture " + std::to_string(i), "images");
                index((*ts)[i], "sampler", "texture " + std::to_string(i), "samplers");
            }
    }
};

}  // namespace

void check_gltf(std::string_view json, std::optional<std::string_view> glb_bin, const std::string& base_dir,
                const std::string& who) {
    const JValue root = JsonReader(json, who).parse();
    Checker(root, glb_bin, base_dir, who).run();
}

}  // namespace normalflow
