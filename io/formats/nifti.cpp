#include "io/formats/nifti.h"

#include <sys/stat.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <vector>

#if defined(NORMALFLOW_HAS_ZLIB)
#include <zlib.h>
#endif

#include "core/errors.h"

namespace normalflow {

namespace {

constexpr double kMaxSamples = double(1ull << 40);  // sanity bound on sizes
constexpr double kMaxDeflateRatio = 1100.0;         // deflate cannot expand more than ~1032:1
constexpr std::size_t kChunkBytes = 1 << 20;        // read and convert 1 MiB at a time

std::string num(double x) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.9g", x);
    return buf;
}

/// The bytes of a magic field, printable ones as they are and others as \xNN.
std::string shown_bytes(const unsigned char* p, std::size_t n) {
    std::string s;
    for (std::size_t i = 0; i < n; ++i) {
        if (p[i] >= 32 && p[i] < 127 && p[i] != '"' && p[i] != '\\') {
            s.push_back(char(p[i]));
        } else {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", unsigned(p[i]));
            s += buf;
        }
    }
    return s;
}

/// NIfTI datatype codes and their names (nifti1.h).
const char* datatype_name(int code) {
    switch (code) {
        case 0: return "UNKNOWN";
        case 1: return "BINARY";
        case 2: return "UINT8";
        case 4: return "INT16";
        case 8: return "INT32";
        case 16: return "FLOAT32";
        case 32: return "COMPLEX64";
        case 64: return "FLOAT64";
        case 128: return "RGB24";
        case 256: return "INT8";
        case 512: return "UINT16";
        case 768: return "UINT32";
        case 1024: return "INT64";
        case 1280: return "UINT64";
        case 1536: return "FLOAT128";
        case 1792: return "COMPLEX128";
        case 2048: return "COMPLEX256";
        case 2304: return "RGBA32";
        default: return "unknown";
    }
}

std::size_t datatype_bytes(int code) {
    switch (code) {
        case 2:
        case 256: return 1;
        case 4:
        case 512: return 2;
        case 8:
        case 16:
        case 768: return 4;
        case 64:
        case 1024:
        case 1280: return 8;
        default: return 0;  // not supported
    }
}

/// The fields of either header version that the reader uses, as doubles and int64s.
struct Header {
    int version = 1;         // 1 or 2
    std::size_t size = 348;  // header bytes
    std::int64_t dim[8]{};
    int datatype = 0;
    double pixdim[8]{};
    double vox_offset = 0;
    double slope = 0, inter = 0;
    int qform_code = 0, sform_code = 0;
    double quat[3]{};  // b, c, d
    double qoffset[3]{};
    double srow[3][4]{};
};

/// Reads a header field of type T at byte offset off, in the file's byte order.
template <class T>
T field(const unsigned char* h, std::size_t off, bool swap) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, h + off, sizeof(T));
    if (swap) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
}

/// A file read front to back, plain or gzip-compressed; every error names the file.
class Reader {
public:
    explicit Reader(const std::string& path) : path_(path) {}
    ~Reader() {
        if (f_) std::fclose(f_);
#if defined(NORMALFLOW_HAS_ZLIB)
        if (gz_) gzclose(gz_);
#endif
    }
    Reader(const Reader&) = delete;
    Reader& operator=(const Reader&) = delete;

    ScalarImage read();

private:
    [[noreturn]] void bad(const std::string& what) const { throw InvalidInput("read_nifti: " + path_ + ": " + what); }
    [[noreturn]] void io_error(const std::string& what) const { throw IoError("read_nifti: " + path_ + ": " + what); }

    void open();
    /// Reads up to n bytes; returns how many were read (fewer only at the end of the data).
    /// \throw IoError on a read error, InvalidInput for corrupt gzip data.
    std::size_t read_some(void* dst, std::size_t n);
    void skip_to(std::uint64_t offset);
    Header parse_header();
    void set_geometry(const Header& h, ScalarImage& img) const;
    void read_values(const Header& h, ScalarImage& img);
    template <class T>
    void convert(const unsigned char* src, std::size_t n, float* dst, std::uint64_t first, const ScalarImage& img);

    std::string path_;
    std::FILE* f_ = nullptr;
#if defined(NORMALFLOW_HAS_ZLIB)
    gzFile gz_ = nullptr;
#endif
    bool gzip_ = false;
    bool swap_ = false;
    std::uint64_t file_size_ = 0;
    std::uint64_t pos_ = 0;  // bytes consumed (decompressed for gzip)
    double slope_ = 1.0, inter_ = 0.0;
    bool scaled_ = false;
};

void Reader::open() {
    f_ = std::fopen(path_.c_str(), "rb");
    if (!f_) io_error(std::string("cannot open (") + std::strerror(errno) + ")");
    struct stat st {};
    if (fstat(fileno(f_), &st) != 0) io_error(std::string("cannot stat (") + std::strerror(errno) + ")");
    if (!S_ISREG(st.st_mode)) io_error("not a regular file");
    file_size_ = std::uint64_t(st.st_size);
    if (file_size_ == 0) bad("empty file");
    unsigned char magic[2] = {0, 0};
    const std::size_t got = std::fread(magic, 1, 2, f_);
    if (std::ferror(f_)) io_error(std::string("read error (") + std::strerror(errno) + ")");
    gzip_ = got == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
    if (!gzip_) {
        std::rewind(f_);
        return;
    }
#if defined(NORMALFLOW_HAS_ZLIB)
    std::fclose(f_);
    f_ = nullptr;
    gz_ = gzopen(path_.c_str(), "rb");
    if (!gz_) io_error(std::string("cannot open (") + std::strerror(errno) + ")");
    gzbuffer(gz_, 1 << 17);
#else
    bad("gzip-compressed file (.nii.gz), but this build has no zlib; decompress it to .nii first");
#endif
}

std::size_t Reader::read_some(void* dst, std::size_t n) {
    std::size_t got = 0;
    if (!gzip_) {
        got = std::fread(dst, 1, n, f_);
        if (got < n && std::ferror(f_)) io_error(std::string("read error (") + std::strerror(errno) + ")");
    } else {
#if defined(NORMALFLOW_HAS_ZLIB)
        auto* out = static_cast<unsigned char*>(dst);
        while (got < n) {
            const unsigned want = unsigned(std::min<std::size_t>(n - got, kChunkBytes));
            const int r = gzread(gz_, out + got, want);
            if (r < 0 || unsigned(r) < want) {
                int err = Z_OK;
                const char* msg = gzerror(gz_, &err);
                if (err == Z_ERRNO) io_error(std::string("read error (") + std::strerror(errno) + ")");
                if (err != Z_OK)
                    bad("truncated or corrupt gzip data after " +
                        std::to_string(pos_ + got + (r > 0 ? unsigned(r) : 0u)) + " decompressed bytes (" +
                        (msg ? msg : "zlib error") + ")");
                if (r > 0) got += unsigned(r);
                break;  // the stream ended
            }
            got += unsigned(r);
        }
#endif
    }
    pos_ += got;
    return got;
}

void Reader::skip_to(std::uint64_t offset) {
    if (offset == pos_) return;
    if (!gzip_) {
        // The caller has checked offset against the file size.
        if (fseeko(f_, off_t(offset), SEEK_SET) != 0)
            io_error(std::string("cannot seek (") + std::strerror(errno) + ")");
        pos_ = offset;
        return;
    }
    std::vector<unsigned char> scratch(std::size_t(std::min<std::uint64_t>(offset - pos_, kChunkBytes)));
    while (pos_ < offset) {
        const std::size_t n = std::size_t(std::min<std::uint64_t>(offset - pos_, scratch.size()));
        if (read_some(scratch.data(), n) != n)
            bad("truncated file: it ends at byte " + std::to_string(pos_) + ", before vox_offset " +
                std::to_string(offset));
    }
}

Header Reader::parse_header() {
    unsigned char h[540];
    std::memset(h, 0, sizeof h);
    {
        const std::size_t got = read_some(h, 4);
        if (got < 4)
            bad("truncated header (the file holds " + std::to_string(got) + " bytes, a NIfTI header 348 or 540)");
    }
    Header hd;
    const std::int32_t native = field<std::int32_t>(h, 0, false);
    const std::int32_t swapped = field<std::int32_t>(h, 0, true);
    if (native == 348 || native == 540) {
        swap_ = false;
    } else if (swapped == 348 || swapped == 540) {
        swap_ = true;
    } else {
        bad("not a NIfTI file (sizeof_hdr is " + std::to_string(native) +
            ", expected 348 for NIfTI-1 or 540 for NIfTI-2)");
    }
    const std::int32_t size = swap_ ? swapped : native;
    hd.version = size == 348 ? 1 : 2;
    hd.size = std::size_t(size);
    if (read_some(h + 4, hd.size - 4) != hd.size - 4)
        bad("truncated header (the " + std::string(gzip_ ? "decompressed " : "") + "file ends after " +
            std::to_string(pos_) + " bytes, a NIfTI-" + std::to_string(hd.version) + " header has " +
            std::to_string(hd.size) + ")");

    const bool s = swap_;
    if (hd.version == 1) {
        const unsigned char* m = h + 344;
        if (std::memcmp(m, "ni1\0", 4) == 0)
            bad("a NIfTI-1 header/image pair (magic \"ni1\": the samples are in a separate .img file); "
                "only single files (.nii, magic \"n+1\") are read");
        if (std::memcmp(m, "n+1\0", 4) != 0)
            bad("not a NIfTI-1 file (magic \"" + shown_bytes(m, 4) +
                "\" at byte 344, expected \"n+1\"; "
                "Analyze 7.5 files are not read)");
        for (int i = 0; i < 8; ++i) hd.dim[i] = field<std::int16_t>(h, 40 + 2 * std::size_t(i), s);
        hd.datatype = field<std::int16_t>(h, 70, s);
        for (int i = 0; i < 8; ++i) hd.pixdim[i] = field<float>(h, 76 + 4 * std::size_t(i), s);
        hd.vox_offset = field<float>(h, 108, s);
        hd.slope = field<float>(h, 112, s);
        hd.inter = field<float>(h, 116, s);
        hd.qform_code = field<std::int16_t>(h, 252, s);
        hd.sform_code = field<std::int16_t>(h, 254, s);
        for (int i = 0; i < 3; ++i) hd.quat[i] = field<float>(h, 256 + 4 * std::size_t(i), s);
        for (int i = 0; i < 3; ++i) hd.qoffset[i] = field<float>(h, 268 + 4 * std::size_t(i), s);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c)
                hd.srow[r][c] = field<float>(h, 280 + 16 * std::size_t(r) + 4 * std::size_t(c), s);
    } else {
        const unsigned char* m = h + 4;
        if (std::memcmp(m, "ni2\0", 4) == 0)
            bad("a NIfTI-2 header/image pair (magic \"ni2\": the samples are in a separate .img file); "
                "only single files (.nii, magic \"n+2\") are read");
        if (std::memcmp(m, "n+2\0\r\n\032\n", 8) != 0)
            bad("not a NIfTI-2 file (magic \"" + shown_bytes(m, 8) +
                "\" at byte 4, expected \"n+2\\0\\r\\n\\x1a\\n\")");
        hd.datatype = field<std::int16_t>(h, 12, s);
        for (int i = 0; i < 8; ++i) hd.dim[i] = field<std::int64_t>(h, 16 + 8 * std::size_t(i), s);
        for (int i = 0; i < 8; ++i) hd.pixdim[i] = field<double>(h, 104 + 8 * std::size_t(i), s);
        const std::int64_t vo = field<std::int64_t>(h, 168, s);
        if (vo < 0) bad("vox_offset is " + std::to_string(vo) + ", expected >= 540");
        hd.vox_offset = double(vo);
        if (std::uint64_t(vo) > (1ull << 53)) bad("vox_offset " + std::to_string(vo) + " is beyond any file");
        hd.slope = field<double>(h, 176, s);
        hd.inter = field<double>(h, 184, s);
        hd.qform_code = field<std::int32_t>(h, 344, s);
        hd.sform_code = field<std::int32_t>(h, 348, s);
        for (int i = 0; i < 3; ++i) hd.quat[i] = field<double>(h, 352 + 8 * std::size_t(i), s);
        for (int i = 0; i < 3; ++i) hd.qoffset[i] = field<double>(h, 376 + 8 * std::size_t(i), s);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c)
                hd.srow[r][c] = field<double>(h, 400 + 32 * std::size_t(r) + 8 * std::size_t(c), s);
    }
    return hd;
}

void Reader::set_geometry(const Header& h, ScalarImage& img) const {
    auto finite_vec = [&](const Vec3d& v, const std::string& what) {
        if (!is_finite(v)) bad(what + " is not finite (" + num(v.x) + ", " + num(v.y) + ", " + num(v.z) + ")");
        return v;
    };
    if (h.sform_code > 0) {
        for (int a = 0; a < 3; ++a)
            img.axes[std::size_t(a)] =
                finite_vec({h.srow[0][a], h.srow[1][a], h.srow[2][a]}, "sform column " + std::to_string(a));
        img.origin = finite_vec({h.srow[0][3], h.srow[1][3], h.srow[2][3]}, "sform offset (4th column)");
    } else if (h.qform_code > 0) {
        double b = h.quat[0], c = h.quat[1], d = h.quat[2];
        if (!std::isfinite(b) || !std::isfinite(c) || !std::isfinite(d))
            bad("qform quaternion (" + num(b) + ", " + num(c) + ", " + num(d) + ") is not finite");
        // As nifti1_io's nifti_quatern_to_mat44: a unit quaternion (a, b, c, d) with a >= 0.
        double a = 1.0 - (b * b + c * c + d * d);
        if (a < 1e-7) {
            const double n = std::sqrt(b * b + c * c + d * d);
            if (!(n > 0) || !std::isfinite(n))
                bad("qform quaternion (" + num(b) + ", " + num(c) + ", " + num(d) + ") is not a rotation");
            b /= n;
            c /= n;
            d /= n;
            a = 0.0;
        } else {
            a = std::sqrt(a);
        }
        const Vec3d col[3] = {{a * a + b * b - c * c - d * d, 2 * (b * c + a * d), 2 * (b * d - a * c)},
                              {2 * (b * c - a * d), a * a + c * c - b * b - d * d, 2 * (c * d + a * b)},
                              {2 * (b * d + a * c), 2 * (c * d - a * b), a * a + d * d - c * c - b * b}};
        for (int i = 1; i <= 3; ++i)
            if (!(h.pixdim[i] > 0) || !std::isfinite(h.pixdim[i]))
                bad("qform: pixdim[" + std::to_string(i) + "] is " + num(h.pixdim[i]) + ", expected a spacing > 0");
        const double qfac = h.pixdim[0] < 0 ? -1.0 : 1.0;
        for (int a2 = 0; a2 < 3; ++a2)
            img.axes[std::size_t(a2)] = col[a2] * (h.pixdim[a2 + 1] * (a2 == 2 ? qfac : 1.0));
        img.origin = finite_vec({h.qoffset[0], h.qoffset[1], h.qoffset[2]}, "qoffset");
    } else {
        double sp[3];
        for (int i = 1; i <= 3; ++i) {
            sp[i - 1] = std::abs(h.pixdim[i]);
            if (!(sp[i - 1] > 0) || !std::isfinite(sp[i - 1]))
                bad("pixdim[" + std::to_string(i) + "] is " + num(h.pixdim[i]) +
                    ", expected a non-zero spacing (no sform or qform to place the image)");
        }
        img.axes = {Vec3d{sp[0], 0, 0}, Vec3d{0, sp[1], 0}, Vec3d{0, 0, sp[2]}};
        img.origin = Vec3d{};
    }
    for (int a = 0; a < 3; ++a) {
        const Vec3d& v = img.axes[std::size_t(a)];
        finite_vec(v, "axis " + std::to_string(a));
        const double n = norm(v);
        if (!(n > 0) || !std::isfinite(n))
            bad("axis " + std::to_string(a) + " (" + num(v.x) + ", " + num(v.y) + ", " + num(v.z) + ") " +
                (h.sform_code > 0 ? "of the sform " : "") + "has no length");
    }
}

template <class T>
void Reader::convert(const unsigned char* src, std::size_t n, float* dst, std::uint64_t first, const ScalarImage& img) {
    constexpr double kFloatMax = double(std::numeric_limits<float>::max());
    for (std::size_t i = 0; i < n; ++i) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, src + i * sizeof(T), sizeof(T));
        if (swap_ && sizeof(T) > 1) std::reverse(b, b + sizeof(T));
        T raw;
        std::memcpy(&raw, b, sizeof(T));
        double v = double(raw);
        if (scaled_) v = slope_ * v + inter_;
        if (!(std::abs(v) <= kFloatMax)) {
            const std::uint64_t idx = first + i;
            const std::uint64_t nx = std::uint64_t(img.dims[0]), ny = std::uint64_t(img.dims[1]);
            bad("sample " + std::to_string(idx) + " (i, j, k) = (" + std::to_string(idx % nx) + ", " +
                std::to_string(idx / nx % ny) + ", " + std::to_string(idx / (nx * ny)) + ") is " +
                (std::isnan(v)   ? "NaN"
                 : std::isinf(v) ? "infinite"
                                 : "beyond the float range") +
                (scaled_ ? " (after scl_slope and scl_inter)" : ""));
        }
        dst[i] = float(v);
    }
}

void Reader::read_values(const Header& h, ScalarImage& img) {
    const std::size_t sb = datatype_bytes(h.datatype);
    const std::uint64_t count = img.sample_count();
    const std::uint64_t bytes = count * sb;
    std::vector<unsigned char> buf(std::size_t(std::min<std::uint64_t>(bytes, kChunkBytes)));
    if (!gzip_)
        img.values.reserve(std::size_t(count));  // the file holds them (checked)
    else
        img.values.reserve(std::size_t(std::min<std::uint64_t>(count, 1u << 24)));
    std::uint64_t done = 0;
    while (done < count) {
        const std::size_t n = std::size_t(std::min<std::uint64_t>(count - done, kChunkBytes / sb));
        const std::size_t got = read_some(buf.data(), n * sb);
        if (got != n * sb)
            bad("truncated data: the " + std::string(gzip_ ? "decompressed " : "") + "file ends after sample " +
                std::to_string(done + got / sb) + " of " + std::to_string(count));
        img.values.resize(std::size_t(done + n));
        float* dst = img.values.data() + done;
        const unsigned char* src = buf.data();
        switch (h.datatype) {
            case 2: convert<std::uint8_t>(src, n, dst, done, img); break;
            case 256: convert<std::int8_t>(src, n, dst, done, img); break;
            case 4: convert<std::int16_t>(src, n, dst, done, img); break;
            case 512: convert<std::uint16_t>(src, n, dst, done, img); break;
            case 8: convert<std::int32_t>(src, n, dst, done, img); break;
            case 768: convert<std::uint32_t>(src, n, dst, done, img); break;
            case 1024: convert<std::int64_t>(src, n, dst, done, img); break;
            case 1280: convert<std::uint64_t>(src, n, dst, done, img); break;
            case 16: convert<float>(src, n, dst, done, img); break;
            case 64: convert<double>(src, n, dst, done, img); break;
            default: bad("datatype " + std::to_string(h.datatype) + " is not supported");
        }
        done += n;
    }
}

ScalarImage Reader::read() {
    open();
    const Header h = parse_header();
    const std::string v = "NIfTI-" + std::to_string(h.version);

    // Dimensions: a 3-D image, or a 4-D..7-D one whose extra dimensions are all 1.
    const std::int64_t nd = h.dim[0];
    if (nd < 3 || nd > 7)
        bad("dim[0] is " + std::to_string(nd) + ", expected 3 (a 3-D image; 4..7 with the extra dimensions 1)");
    for (int i = 1; i <= 3; ++i)
        if (h.dim[i] < 1 || h.dim[i] > std::int64_t(INT_MAX))
            bad("dim[" + std::to_string(i) + "] is " + std::to_string(h.dim[i]) + ", expected an integer in [1, 2^31)");
    for (int i = 4; i <= nd; ++i)
        if (h.dim[i] != 1)
            bad("dim[" + std::to_string(i) + "] is " + std::to_string(h.dim[i]) + " (dim[0] " + std::to_string(nd) +
                "): only 3-D images are read; every dimension beyond the third must be 1");
    ScalarImage img;
    for (int a = 0; a < 3; ++a) img.dims[std::size_t(a)] = int(h.dim[a + 1]);
    const double samples = double(h.dim[1]) * double(h.dim[2]) * double(h.dim[3]);
    if (samples > kMaxSamples)
        bad("dims " + std::to_string(h.dim[1]) + " x " + std::to_string(h.dim[2]) + " x " + std::to_string(h.dim[3]) +
            " claim more than 2^40 samples");

    // Datatype.
    const std::size_t sb = datatype_bytes(h.datatype);
    if (sb == 0)
        bad("datatype " + std::string(datatype_name(h.datatype)) + " (code " + std::to_string(h.datatype) +
            ") is not supported; expected a scalar type: uint8, int8, int16, uint16, int32, uint32, int64, uint64, "
            "float32 or float64");

    // Scaling.
    if (std::isfinite(h.slope) && h.slope != 0) {
        if (!std::isfinite(h.inter)) bad("scl_slope is " + num(h.slope) + " but scl_inter is " + num(h.inter));
        scaled_ = true;
        slope_ = h.slope;
        inter_ = h.inter;
    }

    set_geometry(h, img);

    // Where the samples start, and whether the file can hold them: checked before allocating.
    if (!std::isfinite(h.vox_offset) || h.vox_offset != std::floor(h.vox_offset))
        bad("vox_offset " + num(h.vox_offset) + " is not a whole number of bytes");
    if (h.vox_offset < double(h.size))
        bad("vox_offset is " + num(h.vox_offset) + ", inside the " + std::to_string(h.size) + "-byte " + v +
            " header (expected >= " + std::to_string(h.size) + ")");
    const double need = h.vox_offset + samples * double(sb);
    if (!gzip_) {
        if (need > double(file_size_))
            bad("dims " + std::to_string(img.dims[0]) + " x " + std::to_string(img.dims[1]) + " x " +
                std::to_string(img.dims[2]) + " of " + datatype_name(h.datatype) + " from vox_offset " +
                num(h.vox_offset) + " need " + num(need) + " bytes, but the file holds only " +
                std::to_string(file_size_) + " (truncated?)");
    } else if (need > double(file_size_) * kMaxDeflateRatio + 1024) {
        bad("dims " + std::to_string(img.dims[0]) + " x " + std::to_string(img.dims[1]) + " x " +
            std::to_string(img.dims[2]) + " of " + datatype_name(h.datatype) + " need " + num(need) +
            " bytes, more than " + std::to_string(file_size_) + " bytes of gzip data can hold (truncated?)");
    }
    skip_to(std::uint64_t(h.vox_offset));
    try {
        read_values(h, img);
    } catch (const std::bad_alloc&) {
        throw OutOfMemory("read_nifti: " + path_ + ": " + num(samples) + " samples (" +
                          num(samples * 4.0 / double(1 << 30)) + " GiB as floats) do not fit in memory");
    }
    return img;
}

}  // namespace

ScalarImage read_nifti(const std::string& path) { return Reader(path).read(); }

}  // namespace normalflow
