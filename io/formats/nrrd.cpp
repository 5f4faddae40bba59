#include "io/formats/nrrd.h"

#include <sys/stat.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <vector>

#if defined(NORMALFLOW_HAS_ZLIB)
#include <zlib.h>
#endif

#include "core/errors.h"
#include "io/util/atomic_file.h"

namespace normalflow {

namespace {

constexpr std::size_t kMaxHeaderBytes = 1 << 20;  // a header larger than 1 MiB is garbage
constexpr double kMaxSamples = 1ull << 40;        // sanity bound on sizes
constexpr double kMaxDeflateRatio = 1100.0;       // deflate cannot expand more than ~1032:1

enum class Scalar { I8, U8, I16, U16, I32, U32, F32, F64 };

std::size_t scalar_bytes(Scalar s) {
    switch (s) {
        case Scalar::I8:
        case Scalar::U8: return 1;
        case Scalar::I16:
        case Scalar::U16: return 2;
        case Scalar::I32:
        case Scalar::U32:
        case Scalar::F32: return 4;
        case Scalar::F64: return 8;
    }
    return 0;
}

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

/// Closes a FILE* on scope exit.
struct FileCloser {
    void operator()(std::FILE* f) const {
        if (f) std::fclose(f);
    }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

/// Where the samples of a NRRD file lie, as its header says: sample (i, j, k) at origin + i·axes[0] +
/// j·axes[1] + k·axes[2].
struct NrrdGeometry {
    enum class From { Default, Spacings, Directions } from = From::Default;
    std::array<Vec3d, 3> axes{Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};
    Vec3d origin;
    std::string text;  ///< the spacings or space directions field as written, for messages
};

/// Parser state for one NRRD file (and its detached data file); every error names the header file
/// and starts with `who` (read_nrrd, read_nrrd_image).
///
/// Use: parse_header(), geometry(), open_data(), then read_samples() until every sample is read.
class NrrdReader {
public:
    NrrdReader(const std::string& path, const char* who) : path_(path), who_(who) {}

    /// Streams the samples into a narrow-band Volume (read_nrrd).
    Volume read_volume(const VolumeReadOptions& opt);
    /// Reads every sample into a dense image (read_nrrd_image).
    ScalarImage read_image();

private:
    [[noreturn]] void bad(const std::string& what) const { throw InvalidInput(who_ + ": " + path_ + ": " + what); }
    [[noreturn]] void bad_line(const std::string& what) const { bad("line " + std::to_string(line_no_) + ": " + what); }
    [[noreturn]] void io_error(const std::string& what) const { throw IoError(who_ + ": " + path_ + ": " + what); }

    /// Opens the header file and parses the header; the stream is left at the first byte after it.
    void parse_header();
    bool read_line(std::string& line);
    std::vector<double> parse_numbers(const std::string& s, std::size_t expected, const char* field);
    std::vector<std::optional<std::array<double, 3>>> parse_vectors(const std::string& s);
    /// The geometry fields, parsed (finite numbers, three spatial axes), not yet judged.
    NrrdGeometry geometry();
    /// Opens the detached data file if there is one, applies line skip and byte skip, and checks that
    /// the data can hold what the sizes claim (before anything is allocated).
    void open_data();
    std::uint64_t sample_count() const {
        return std::uint64_t(sizes_[0]) * std::uint64_t(sizes_[1]) * std::uint64_t(sizes_[2]);
    }

    // Data sources: fill exactly `bytes` bytes or throw.
    void read_raw(void* dst, std::size_t bytes);
    void read_gzip(void* dst, std::size_t bytes);
    void read_ascii(double* dst, std::size_t count);
    void read_samples(double* dst, std::size_t count);

    std::string path_;
    std::string who_;
    FilePtr f_;
    std::uint64_t file_size_ = 0;  // of the file f_ reads: the header file, then the data file
    std::size_t header_bytes_ = 0;
    int line_no_ = 0;

    std::map<std::string, std::string> fields_;  // lower-case field name -> description
    std::map<std::string, std::string> keys_;    // key:=value pairs
    std::string data_file_;                      // detached data file as written, or empty
    Scalar type_ = Scalar::F32;
    std::array<std::int64_t, 3> sizes_{0, 0, 0};
    enum class Encoding { Raw, Gzip, Ascii } encoding_ = Encoding::Raw;
    bool swap_ = false;
    std::int64_t byte_skip_ = 0;
    std::int64_t line_skip_ = 0;
    std::uint64_t samples_read_ = 0;

#if defined(NORMALFLOW_HAS_ZLIB)
    struct Inflater {
        z_stream zs{};
        bool init = false;
        bool done = false;
        std::vector<unsigned char> in;
        ~Inflater() {
            if (init) inflateEnd(&zs);
        }
    };
    std::unique_ptr<Inflater> z_;
#endif
    std::vector<char> raw_buf_;
};

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

void NrrdReader::read_raw(void* dst, std::size_t bytes) {
    const std::size_t got = std::fread(dst, 1, bytes, f_.get());
    if (got != bytes) {
        if (std::ferror(f_.get())) io_error(std::string("read error (") + std::strerror(errno) + ")");
        bad("truncated data after sample " + std::to_string(samples_read_ + got / scalar_bytes(type_)));
    }
}

#if defined(NORMALFLOW_HAS_ZLIB)
void NrrdReader::read_gzip(void* dst, std::size_t bytes) {
    if (!z_) {
        z_ = std::make_unique<Inflater>();
        if (inflateInit2(&z_->zs, 15 + 32) != Z_OK) bad("cannot initialise zlib");
        z_->init = true;
        z_->in.resize(1 << 16);
    }
    z_stream& zs = z_->zs;
    zs.next_out = static_cast<Bytef*>(dst);
    zs.avail_out = 0;
    std::size_t left = bytes;
    auto* out = static_cast<unsigned char*>(dst);
    while (left > 0) {
        if (z_->done)
            bad("truncated gzip data: decompressed stream ends after sample " + std::to_string(samples_read_));
        const uInt chunk = uInt(std::min<std::size_t>(left, 1u << 30));
        zs.next_out = out;
        zs.avail_out = chunk;
        while (zs.avail_out > 0) {
            if (zs.avail_in == 0) {
                const std::size_t n = std::fread(z_->in.data(), 1, z_->in.size(), f_.get());
                if (n == 0) {
                    if (std::ferror(f_.get())) io_error(std::string("read error (") + std::strerror(errno) + ")");
                    bad("truncated gzip data (file ends before sample " + std::to_string(samples_read_) +
                        " was complete)");
                }
                zs.next_in = z_->in.data();
                zs.avail_in = uInt(n);
            }
            const int rc = inflate(&zs, Z_NO_FLUSH);
            if (rc == Z_STREAM_END) {
                z_->done = true;
                break;
            }
            if (rc != Z_OK && rc != Z_BUF_ERROR)
                bad(std::string("corrupt gzip data (") + (zs.msg ? zs.msg : "zlib error") + ")");
        }
        const std::size_t produced = chunk - zs.avail_out;
        out += produced;
        left -= produced;
        if (z_->done && left > 0) bad("truncated gzip data: decompressed stream ends before all samples were read");
    }
}
#else
void NrrdReader::read_gzip(void*, std::size_t) { bad("gzip encoding is not supported by this build"); }
#endif

void NrrdReader::read_ascii(double* dst, std::size_t count) {
    std::FILE* f = f_.get();
    for (std::size_t n = 0; n < count; ++n) {
        char tok[64];
        int len = 0, c;
        while ((c = std::fgetc(f)) != EOF && (std::isspace(c) || c == ',')) {}
        while (c != EOF && !std::isspace(c) && c != ',') {
            if (len < 63)
                tok[len++] = char(c);
            else
                bad("malformed ascii sample " + std::to_string(samples_read_ + n));
            c = std::fgetc(f);
        }
        if (len == 0) bad("truncated ascii data: found " + std::to_string(samples_read_ + n) + " samples");
        tok[len] = '\0';
        char* end = nullptr;
        dst[n] = std::strtod(tok, &end);
        if (*end != '\0') bad("malformed ascii sample " + std::to_string(samples_read_ + n) + ": \"" + tok + "\"");
    }
}

template <class T>
void convert(const char* src, double* dst, std::size_t count, bool swap) {
    for (std::size_t i = 0; i < count; ++i) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, src + i * sizeof(T), sizeof(T));
        if (swap) std::reverse(b, b + sizeof(T));
        T v;
        std::memcpy(&v, b, sizeof(T));
        dst[i] = double(v);
    }
}

void NrrdReader::read_samples(double* dst, std::size_t count) {
    if (encoding_ == Encoding::Ascii) {
        read_ascii(dst, count);
    } else {
        const std::size_t sb = scalar_bytes(type_);
        raw_buf_.resize(count * sb);
        if (encoding_ == Encoding::Raw)
            read_raw(raw_buf_.data(), raw_buf_.size());
        else
            read_gzip(raw_buf_.data(), raw_buf_.size());
        const char* s = raw_buf_.data();
        switch (type_) {
            case Scalar::I8: convert<std::int8_t>(s, dst, count, false); break;
            case Scalar::U8: convert<std::uint8_t>(s, dst, count, false); break;
            case Scalar::I16: convert<std::int16_t>(s, dst, count, swap_); break;
            case Scalar::U16: convert<std::uint16_t>(s, dst, count, swap_); break;
            case Scalar::I32: convert<std::int32_t>(s, dst, count, swap_); break;
            case Scalar::U32: convert<std::uint32_t>(s, dst, count, swap_); break;
            case Scalar::F32: convert<float>(s, dst, count, swap_); break;
            case Scalar::F64: convert<double>(s, dst, count, swap_); break;
        }
    }
    for (std::size_t i = 0; i < count; ++i)
        if (!(std::abs(dst[i]) <= std::numeric_limits<float>::max()))  // NaN, Inf, or a double beyond float
            bad("sample " + std::to_string(samples_read_ + i) +
                " is not finite as a float (NaN, Inf or beyond 3.4e38)");
    samples_read_ += count;
}

void NrrdReader::open_data() {
    std::string where;  // "data file NAME: " in messages about a detached data file
    if (!data_file_.empty()) {
        namespace fs = std::filesystem;
        const fs::path p =
            fs::path(data_file_).is_absolute() ? fs::path(data_file_) : fs::path(path_).parent_path() / data_file_;
        where = "data file " + p.string() + ": ";
        struct stat st {};
        if (::stat(p.c_str(), &st) != 0) io_error(where + "cannot open (" + std::strerror(errno) + ")");
        if (!S_ISREG(st.st_mode)) io_error(where + "not a regular file");
        f_.reset(std::fopen(p.c_str(), "rb"));
        if (!f_) io_error(where + "cannot open (" + std::strerror(errno) + ")");
        file_size_ = std::uint64_t(st.st_size);
    }
    const std::uint64_t count = sample_count();
    const std::uint64_t need = count * scalar_bytes(type_);
    for (std::int64_t l = 0; l < line_skip_; ++l) {
        int c;
        while ((c = std::fgetc(f_.get())) != EOF && c != '\n') {}
        if (c == EOF) bad(where + "line skip " + std::to_string(line_skip_) + " runs past the end of the file");
    }
    const long tell = std::ftell(f_.get());
    if (tell < 0) io_error(where + "cannot tell the read position");
    std::uint64_t pos = std::uint64_t(tell);
    if (encoding_ == Encoding::Raw) {
        if (byte_skip_ == -1) {
            if (file_size_ < pos + need)
                bad(where + "sizes claim " + std::to_string(need) + " bytes of data, but the file holds only " +
                    std::to_string(file_size_ > pos ? file_size_ - pos : 0));
            pos = file_size_ - need;
        } else {
            pos += std::uint64_t(byte_skip_);
        }
        if (file_size_ < pos || file_size_ - pos < need)
            bad(where + "sizes " + std::to_string(sizes_[0]) + " " + std::to_string(sizes_[1]) + " " +
                std::to_string(sizes_[2]) + " claim " + std::to_string(need) +
                " bytes of data, but the file holds only " + std::to_string(file_size_ > pos ? file_size_ - pos : 0) +
                " (truncated?)");
        if (std::fseek(f_.get(), long(pos), SEEK_SET) != 0) io_error(where + "cannot seek");
    } else if (encoding_ == Encoding::Gzip) {
        const double avail = double(file_size_ - std::min(file_size_, pos));
        if (double(need) + double(std::max<std::int64_t>(byte_skip_, 0)) > avail * kMaxDeflateRatio + 1024)
            bad(where + "sizes claim " + std::to_string(need) + " bytes of data, more than " +
                std::to_string(std::uint64_t(avail)) + " bytes of gzip data can hold (truncated?)");
        if (byte_skip_ > 0) {
            std::vector<char> skip(std::size_t(std::min<std::int64_t>(byte_skip_, 1 << 20)));
            for (std::int64_t left = byte_skip_; left > 0;) {
                const std::size_t n = std::size_t(std::min<std::int64_t>(left, std::int64_t(skip.size())));
                read_gzip(skip.data(), n);
                left -= std::int64_t(n);
            }
        }
    } else {
        // ascii: at least one character and one separator per sample.
        if (double(count) > double(file_size_ - std::min(file_size_, pos)))
            bad(where + "sizes claim " + std::to_string(count) +
                " ascii samples, more than the file can hold (truncated?)");
        if (byte_skip_ > 0 && std::fseek(f_.get(), long(pos + std::uint64_t(byte_skip_)), SEEK_SET) != 0)
            io_error(where + "cannot seek");
    }
}

Volume NrrdReader::read_volume(const VolumeReadOptions& opt) {
    if (!(opt.half_width >= 0) || !std::isfinite(opt.half_width))
        bad("half_width " + std::to_string(opt.half_width) +
            " is out of range (expected > 0 voxels, or 0 for the default)");
    if (!std::isfinite(opt.iso)) bad("iso value is not finite");
    parse_header();
    const NrrdGeometry geo = geometry();

    // The grid: isotropic voxels, axis-aligned with positive steps (origin = the file's origin,
    // identity placement), or rotated/flipped orthogonal axes (origin 0, the file's frame in the placement).
    Grid g;
    for (int a = 0; a < 3; ++a) g.dims[std::size_t(a)] = int(sizes_[std::size_t(a)]);
    g.origin = geo.origin;
    if (geo.from == NrrdGeometry::From::Spacings) {
        for (int a = 0; a < 3; ++a)
            if (!(geo.axes[std::size_t(a)][a] > 0)) bad("spacings: axis " + std::to_string(a) + " is not positive");
        const double h = geo.axes[0].x;
        if (std::abs(geo.axes[1].y - h) > 1e-5 * h || std::abs(geo.axes[2].z - h) > 1e-5 * h)
            bad("anisotropic spacings (" + geo.text + "); isotropic voxels are required");
        g.voxel_size = h;
    } else if (geo.from == NrrdGeometry::From::Directions) {
        double len[3];
        for (int a = 0; a < 3; ++a) len[a] = norm(geo.axes[std::size_t(a)]);
        const double h = len[0];
        if (std::abs(len[1] - h) > 1e-5 * h || std::abs(len[2] - h) > 1e-5 * h)
            bad("anisotropic spacing (" + geo.text + "); isotropic voxels are required");
        g.voxel_size = h;
        bool aligned = true;
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                aligned = aligned && (a == b ? geo.axes[std::size_t(a)][b] > 0 : geo.axes[std::size_t(a)][b] == 0.0);
        if (!aligned) {
            Vec3d u[3];
            for (int a = 0; a < 3; ++a) u[a] = geo.axes[std::size_t(a)] / len[a];
            for (int a = 0; a < 3; ++a)
                for (int b = a + 1; b < 3; ++b)
                    if (std::abs(dot(u[a], u[b])) > 1e-5)
                        bad("space directions are not orthogonal (" + geo.text +
                            "); a volume needs orthogonal axes of equal length");
            g.placement = placement_from_axes(geo.axes, geo.origin);  // orthonormal to rounding, the file's handedness
            g.origin = Vec3d{};
        }
    }

    // Half width and background: positive, and checked against the float range (a finite double such
    // as 2e128 would become +Inf as a float).
    auto positive_float = [&](const char* key) {
        const auto v = parse_numbers(keys_.at(key), 1, key);
        if (!(v[0] > 0) || !(v[0] <= std::numeric_limits<float>::max()))
            bad(std::string(key) + " must be > 0 and fit in a float");
        return float(v[0]);
    };
    float half_width = opt.half_width;
    if (half_width == 0) {
        half_width = 3.f;
        if (keys_.count("normalflow_half_width")) half_width = positive_float("normalflow_half_width");
    }
    Volume vol(g, half_width);
    if (keys_.count("normalflow_background")) vol.background = positive_float("normalflow_background");
    const double band = double(half_width) * g.voxel_size;

    // Position at the data and check that the file can hold what the sizes claim, before allocating.
    open_data();

    // Stream 8 z-slices at a time and convert each slab of blocks.
    const std::uint64_t nx = std::uint64_t(sizes_[0]), ny = std::uint64_t(sizes_[1]);
    const double sgn = opt.negate ? -1.0 : 1.0;
    const double iso = opt.iso;
    std::vector<double> slab;
    const std::size_t slice = std::size_t(nx * ny);
    for (int bk = 0; bk < vol.block_dims[2]; ++bk) {
        const int z0 = bk * kBlockDim;
        const int zn = std::min<int>(kBlockDim, g.dims[2] - z0);
        slab.resize(slice * std::size_t(zn));
        read_samples(slab.data(), slab.size());
        for (double& x : slab) x = sgn * (x - iso);
        for (int bj = 0; bj < vol.block_dims[1]; ++bj) {
            const int y0 = bj * kBlockDim, yn = std::min<int>(kBlockDim, g.dims[1] - y0);
            for (int bi = 0; bi < vol.block_dims[0]; ++bi) {
                const int x0 = bi * kBlockDim, xn = std::min<int>(kBlockDim, g.dims[0] - x0);
                bool near = false, neg = false, pos = false;
                for (int lk = 0; lk < zn && !near; ++lk)
                    for (int lj = 0; lj < yn && !near; ++lj) {
                        const double* row = slab.data() + std::size_t(lk) * slice + std::size_t(y0 + lj) * nx + x0;
                        for (int li = 0; li < xn; ++li) {
                            const double x = row[li];
                            if (std::abs(x) < band) {
                                near = true;
                                break;
                            }
                            (x < 0 ? neg : pos) = true;
                        }
                    }
                if (near || (neg && pos)) {
                    const std::int32_t b = vol.allocate_block(bi, bj, bk);
                    float* dst = vol.block_values(b);
                    for (int lk = 0; lk < zn; ++lk)
                        for (int lj = 0; lj < yn; ++lj) {
                            const double* row = slab.data() + std::size_t(lk) * slice + std::size_t(y0 + lj) * nx + x0;
                            for (int li = 0; li < xn; ++li) dst[Volume::local_index(li, lj, lk)] = float(row[li]);
                        }
                } else if (neg) {
                    vol.block_table[vol.table_index(bi, bj, bk)] = kBlockInside;
                }
            }
        }
    }
    vol.check(who_ + ": " + path_);
    return vol;
}

ScalarImage NrrdReader::read_image() {
    parse_header();
    const NrrdGeometry geo = geometry();
    ScalarImage img;
    for (int a = 0; a < 3; ++a) img.dims[std::size_t(a)] = int(sizes_[std::size_t(a)]);
    img.axes = geo.axes;
    img.origin = geo.origin;
    open_data();  // checks the sizes against the data before anything is allocated
    const std::uint64_t count = sample_count();
    try {
        // Raw and ascii data hold what the sizes claim (checked); gzip data may end early: grow with it.
        img.values.reserve(std::size_t(encoding_ == Encoding::Gzip ? std::min<std::uint64_t>(count, 1u << 24) : count));
        std::vector<double> chunk;
        for (std::uint64_t done = 0; done < count;) {
            const std::size_t n = std::size_t(std::min<std::uint64_t>(count - done, 1u << 17));
            chunk.resize(n);
            read_samples(chunk.data(), n);  // finite as floats (checked)
            for (const double x : chunk) img.values.push_back(float(x));
            done += n;
        }
    } catch (const std::bad_alloc&) {
        throw OutOfMemory(who_ + ": " + path_ + ": " + std::to_string(count) + " samples do not fit in memory");
    }
    return img;
}

std::string num(double x) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    return buf;
}

}  // namespace

Volume read_nrrd(const std::string& path, const VolumeReadOptions& opt) {
    return NrrdReader(path, "read_nrrd").read_volume(opt);
}

Volume read_nrrd(const std::string& path) { return read_nrrd(path, VolumeReadOptions{}); }

ScalarImage read_nrrd_image(const std::string& path) { return NrrdReader(path, "read_nrrd_image").read_image(); }

void write_nrrd(const std::string& path, const Volume& v) {
    v.check("write_nrrd: " + path);
    const Grid& g = v.grid;
    const Placement& pl = g.placement;
    // The file's frame is the world: directions h · rotation columns, origin the world position of
    // sample (0, 0, 0). With the identity placement these are (h,0,0) (0,h,0) (0,0,h) and grid.origin.
    std::string dirs, origin;
    if (pl.is_identity()) {
        const std::string h = num(g.voxel_size);
        dirs = "(" + h + ",0,0) (0," + h + ",0) (0,0," + h + ")";
        origin = "(" + num(g.origin.x) + "," + num(g.origin.y) + "," + num(g.origin.z) + ")";
    } else {
        for (int a = 0; a < 3; ++a) {
            const Vec3d d = pl.rotation[std::size_t(a)] * g.voxel_size;
            dirs += std::string(a ? " " : "") + "(" + num(d.x) + "," + num(d.y) + "," + num(d.z) + ")";
        }
        const Vec3d o = pl.point(g.origin);
        origin = "(" + num(o.x) + "," + num(o.y) + "," + num(o.z) + ")";
    }
    std::string hdr =
        "NRRD0004\n# Complete NRRD file format specification at:\n"
        "# http://teem.sourceforge.net/nrrd/format.html\n"
        "# written by normalflow: signed distance, world units, negative inside\n"
        "type: float\ndimension: 3\nspace dimension: 3\n";
    hdr += "sizes: " + std::to_string(g.dims[0]) + " " + std::to_string(g.dims[1]) + " " + std::to_string(g.dims[2]) +
           "\n";
    hdr += "space directions: " + dirs + "\n";
    hdr += "kinds: domain domain domain\ncenterings: node node node\n";
    hdr += std::string("endian: ") + (std::endian::native == std::endian::little ? "little" : "big") + "\n";
    hdr += "encoding: raw\n";
    hdr += "space origin: " + origin + "\n";
    hdr += "normalflow_half_width:=" + num(v.half_width) + "\n";
    hdr += "normalflow_background:=" + num(v.background) + "\n\n";

    AtomicFile f(path, "write_nrrd");
    f.write(hdr);
    std::vector<float> row(std::size_t(g.dims[0]));
    for (int k = 0; k < g.dims[2]; ++k)
        for (int j = 0; j < g.dims[1]; ++j) {
            for (int i = 0; i < g.dims[0]; ++i) row[std::size_t(i)] = v.value(i, j, k);
            f.write(row.data(), row.size() * sizeof(float));
        }
    f.commit();
}

}  // namespace normalflow
