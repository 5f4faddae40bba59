// The NRRD reader's header (nrrd_reader.h): the header's lines, its fields and keys, the sizes,
// type, encoding, endianness and skips, and the geometry fields. The data are read in nrrd.cpp.
#include "io/formats/nrrd_reader.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace normalflow::detail {

namespace {

constexpr std::size_t kMaxHeaderBytes = 1 << 20;  // a header larger than 1 MiB is garbage
constexpr double kMaxSamples = 1ull << 40;        // sanity bound on sizes

std::optional<Scalar> parse_type(const std::string& t) {
    static const std::map<std::string, Scalar> table = {{"signed char", Scalar::I8},
                                                        {"int8", Scalar::I8},
                                                        {"int8_t", Scalar::I8},
                                                        {"uchar", Scalar::U8},
                                                        {"unsigned char", Scalar::U8},
                                                        {"uint8", Scalar::U8},
                                                        {"uint8_t", Scalar::U8},
                                                        {"short", Scalar::I16},
                                                        {"short int", Scalar::I16},
                                                        {"signed short", Scalar::I16},
                                                        {"signed short int", Scalar::I16},
                                                        {"int16", Scalar::I16},
                                                        {"int16_t", Scalar::I16},
                                                        {"ushort", Scalar::U16},
                                                        {"unsigned short", Scalar::U16},
                                                        {"unsigned short int", Scalar::U16},
                                                        {"uint16", Scalar::U16},
                                                        {"uint16_t", Scalar::U16},
                                                        {"int", Scalar::I32},
                                                        {"signed int", Scalar::I32},
                                                        {"int32", Scalar::I32},
                                                        {"int32_t", Scalar::I32},
                                                        {"uint", Scalar::U32},
                                                        {"unsigned int", Scalar::U32},
                                                        {"uint32", Scalar::U32},
                                                        {"uint32_t", Scalar::U32},
                                                        {"float", Scalar::F32},
                                                        {"double", Scalar::F64}};
    const auto it = table.find(t);
    if (it == table.end()) return std::nullopt;
    return it->second;
}

std::string trim(const std::string& s) {
    std::size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return s.substr(a, b - a);
}

std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

}  // namespace

bool NrrdReader::read_line(std::string& line) {
    line.clear();
    int c;
    while ((c = std::fgetc(f_.get())) != EOF) {
        if (++header_bytes_ > kMaxHeaderBytes) bad("header longer than 1 MiB (not a NRRD file?)");
        if (c == '\n') break;
        if (c == '\0')
            bad("line " + std::to_string(line_no_ + 1) + ": NUL byte in header (truncated or not a NRRD file)");
        line.push_back(char(c));
    }
    if (c == EOF && line.empty()) return false;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    ++line_no_;
    return true;
}

void NrrdReader::parse_header() {
    f_.reset(std::fopen(path_.c_str(), "rb"));
    if (!f_) io_error(std::string("cannot open (") + std::strerror(errno) + ")");
    if (std::fseek(f_.get(), 0, SEEK_END) != 0) io_error("cannot seek (not a regular file?)");
    const long fs = std::ftell(f_.get());
    if (fs < 0) io_error("cannot determine the file size");
    file_size_ = std::uint64_t(fs);
    std::rewind(f_.get());
    if (file_size_ == 0) bad("empty file");

    std::string line;
    if (!read_line(line)) bad("empty file");
    if (line.size() != 8 || line.compare(0, 7, "NRRD000") != 0 || line[7] < '1' || line[7] > '5')
        bad("not a NRRD file (expected magic NRRD0001..NRRD0005, found \"" + line.substr(0, 16) + "\")");
    bool blank = false;
    while (read_line(line)) {
        if (line.empty()) {
            blank = true;
            break;
        }
        if (line[0] == '#') continue;
        const std::size_t kv = line.find(":=");
        const std::size_t colon = line.find(": ");
        if (kv != std::string::npos && (colon == std::string::npos || kv < colon)) {
            keys_[line.substr(0, kv)] = line.substr(kv + 2);
            continue;
        }
        if (colon == std::string::npos)
            bad_line("expected \"field: description\", found \"" + line.substr(0, 40) + "\"");
        const std::string name = lower(trim(line.substr(0, colon)));
        if (fields_.count(name)) bad_line("field \"" + name + "\" given twice");
        fields_[name] = trim(line.substr(colon + 2));
        // "data file: LIST" is the last field: the file names follow it, one a line.
        if ((name == "data file" || name == "datafile") &&
            (fields_[name] == "LIST" || fields_[name].rfind("LIST ", 0) == 0))
            bad_line(
                "data file: LIST (a list of data files after the header) is not supported; use a single data file");
    }
    // Detached data: one file, named relative to the header's folder (or absolute).
    if (fields_.count("data file") && fields_.count("datafile")) bad("both \"data file\" and \"datafile\" given");
    if (const auto it = fields_.count("data file") ? fields_.find("data file") : fields_.find("datafile");
        it != fields_.end()) {
        const std::string& d = it->second;
        if (d.empty()) bad("data file: no file name given");
        if (d.find('%') != std::string::npos)
            bad("data file: \"" + d +
                "\" is a format string naming several data files; only a single data file is supported");
        data_file_ = d;
    }
    // A header must end with a blank line before attached data; without one the file is truncated.
    if (!blank && data_file_.empty()) bad("truncated header (no blank line before the data)");

    auto need = [&](const char* name) -> const std::string& {
        const auto it = fields_.find(name);
        if (it == fields_.end()) bad(std::string("missing required field \"") + name + "\"");
        return it->second;
    };
    // dimension
    {
        const std::string& d = need("dimension");
        if (d != "3") bad("dimension is " + d + ", expected 3");
    }
    // type
    {
        const std::string& t = need("type");
        const auto s = parse_type(lower(t));
        if (!s) bad("unsupported type \"" + t + "\" (expected float, double, (u)char, (u)short or (u)int)");
        type_ = *s;
    }
    // sizes
    {
        const auto v = parse_numbers(need("sizes"), 3, "sizes");
        double total = 1;
        for (int a = 0; a < 3; ++a) {
            if (v[a] < 1 || v[a] != std::floor(v[a]) || v[a] > double(1 << 30))
                bad("sizes: axis " + std::to_string(a) + " has size " + trim(std::to_string(v[a])) +
                    ", expected an integer in [1, 2^30]");
            sizes_[a] = std::int64_t(v[a]);
            total *= v[a];
        }
        if (total > kMaxSamples) bad("sizes claim " + std::to_string(total) + " samples (more than 2^40)");
    }
    // encoding
    {
        const std::string e = lower(need("encoding"));
        if (e == "raw")
            encoding_ = Encoding::Raw;
        else if (e == "gzip" || e == "gz") {
#if defined(NORMALFLOW_HAS_ZLIB)
            encoding_ = Encoding::Gzip;
#else
            bad("gzip encoding is not supported by this build (no zlib)");
#endif
        } else if (e == "ascii" || e == "text" || e == "txt")
            encoding_ = Encoding::Ascii;
        else
            bad("unsupported encoding \"" + e + "\" (expected raw, gzip or ascii)");
    }
    // endian
    if (scalar_bytes(type_) > 1 && encoding_ != Encoding::Ascii) {
        const auto it = fields_.find("endian");
        if (it == fields_.end()) bad("missing required field \"endian\" for a multi-byte type");
        const std::string e = lower(it->second);
        bool little;
        if (e == "little")
            little = true;
        else if (e == "big")
            little = false;
        else
            bad("endian is \"" + it->second + "\", expected little or big");
        swap_ = little != (std::endian::native == std::endian::little);
    }
    // skips
    auto integer_field = [&](const char* a, const char* b) -> std::int64_t {
        auto it = fields_.find(a);
        if (it == fields_.end()) it = fields_.find(b);
        if (it == fields_.end()) return 0;
        char* end = nullptr;
        errno = 0;
        const long long x = std::strtoll(it->second.c_str(), &end, 10);
        if (errno || end == it->second.c_str() || *end != '\0')
            bad(std::string(a) + ": expected an integer, found \"" + it->second + "\"");
        return x;
    };
    byte_skip_ = integer_field("byte skip", "byteskip");
    line_skip_ = integer_field("line skip", "lineskip");
    if (line_skip_ < 0) bad("line skip must be >= 0");
    if (byte_skip_ < -1) bad("byte skip must be >= -1");
    if (byte_skip_ == -1 && encoding_ != Encoding::Raw) bad("byte skip -1 is only allowed with raw encoding");
}

std::vector<double> NrrdReader::parse_numbers(const std::string& s, std::size_t expected, const char* field) {
    std::vector<double> out;
    const char* p = s.c_str();
    while (*p) {
        while (*p && std::isspace(static_cast<unsigned char>(*p))) ++p;
        if (!*p) break;
        char* end = nullptr;
        const double x = std::strtod(p, &end);
        if (end == p) bad(std::string(field) + ": expected numbers, found \"" + s + "\"");
        out.push_back(x);
        p = end;
    }
    if (expected && out.size() != expected)
        bad(std::string(field) + ": expected " + std::to_string(expected) + " values, found " +
            std::to_string(out.size()));
    for (double x : out)
        if (!std::isfinite(x)) bad(std::string(field) + ": non-finite value in \"" + s + "\"");
    return out;
}

std::vector<std::optional<std::array<double, 3>>> NrrdReader::parse_vectors(const std::string& s) {
    std::vector<std::optional<std::array<double, 3>>> out;
    std::size_t i = 0;
    auto skip = [&] {
        while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    };
    for (;;) {
        skip();
        if (i >= s.size()) break;
        if (s.compare(i, 4, "none") == 0) {
            out.emplace_back();
            i += 4;
            continue;
        }
        if (s[i] != '(') bad("malformed vector list \"" + s + "\" (expected \"(x,y,z)\" or none)");
        const std::size_t close = s.find(')', i);
        if (close == std::string::npos) bad("malformed vector list \"" + s + "\" (missing ')')");
        std::string inner = s.substr(i + 1, close - i - 1);
        std::replace(inner.begin(), inner.end(), ',', ' ');
        const auto v = parse_numbers(inner, 0, "vector");
        if (v.size() != 3)
            bad("vector \"" + s.substr(i, close - i + 1) + "\" has " + std::to_string(v.size()) +
                " components, expected 3 (space dimension 3)");
        out.push_back(std::array<double, 3>{v[0], v[1], v[2]});
        i = close + 1;
    }
    return out;
}

NrrdGeometry NrrdReader::geometry() {
    if (const auto it = fields_.find("space dimension"); it != fields_.end() && trim(it->second) != "3")
        bad("space dimension is " + it->second + ", expected 3");
    if (const auto it = fields_.find("space");
        it != fields_.end() && lower(it->second).find("time") != std::string::npos)
        bad("space \"" + it->second + "\" has a time axis; expected a 3-D space");
    NrrdGeometry geo;
    if (const auto it = fields_.find("space directions"); it != fields_.end()) {
        const auto dirs = parse_vectors(it->second);
        if (dirs.size() != 3) bad("space directions: expected 3 vectors, found " + std::to_string(dirs.size()));
        for (int a = 0; a < 3; ++a) {
            if (!dirs[std::size_t(a)])
                bad("space directions: axis " + std::to_string(a) + " is \"none\"; expected 3 spatial axes");
            const auto& d = *dirs[std::size_t(a)];
            geo.axes[std::size_t(a)] = {d[0], d[1], d[2]};
            const double n = norm(geo.axes[std::size_t(a)]);
            if (!(n > 0) || !std::isfinite(n))
                bad("space directions: axis " + std::to_string(a) + " has no length (" + it->second + ")");
        }
        geo.from = NrrdGeometry::From::Directions;
        geo.text = it->second;
    } else if (const auto sit = fields_.find("spacings"); sit != fields_.end()) {
        const auto v = parse_numbers(sit->second, 3, "spacings");
        for (int a = 0; a < 3; ++a) {
            if (v[std::size_t(a)] == 0) bad("spacings: axis " + std::to_string(a) + " is 0");
            geo.axes[std::size_t(a)] = Vec3d{};
            geo.axes[std::size_t(a)][a] = v[std::size_t(a)];
        }
        if (const auto mit = fields_.find("axis mins"); mit != fields_.end()) {
            const auto m = parse_numbers(mit->second, 3, "axis mins");
            geo.origin = {m[0], m[1], m[2]};
        }
        geo.from = NrrdGeometry::From::Spacings;
        geo.text = sit->second;
    }
    if (const auto it = fields_.find("space origin"); it != fields_.end()) {
        const auto o = parse_vectors(it->second);
        if (o.size() != 1 || !o[0]) bad("space origin: expected one vector \"(x,y,z)\", found \"" + it->second + "\"");
        geo.origin = {(*o[0])[0], (*o[0])[1], (*o[0])[2]};
    }
    return geo;
}

}  // namespace normalflow::detail
