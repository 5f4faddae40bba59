#include "io/formats/nrrd.h"

// read_nrrd and read_nrrd_image: the data of a NRRD file (raw, gzip or ascii samples, attached or
// in a detached data file) into a Volume or a ScalarImage, after the header (nrrd_header.cpp);
// write_nrrd.

#include <sys/stat.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <vector>

#if defined(NORMALFLOW_HAS_ZLIB)
#include <zlib.h>
#endif

#include "core/errors.h"
#include "io/formats/nrrd_reader.h"
#include "io/util/atomic_file.h"

namespace normalflow {

namespace detail {

namespace {
constexpr double kMaxDeflateRatio = 1100.0;  // deflate cannot expand more than ~1032:1
}  // namespace

#if defined(NORMALFLOW_HAS_ZLIB)
struct NrrdReader::Inflater {
    z_stream zs{};
    bool init = false;
    bool done = false;
    std::vector<unsigned char> in;
    ~Inflater() {
        if (init) inflateEnd(&zs);
    }
};
#else
struct NrrdReader::Inflater {};
#endif

NrrdReader::NrrdReader(const std::string& path, const char* who) : path_(path), who_(who) {}
NrrdReader::~NrrdReader() = default;

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

namespace {

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

}  // namespace

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

}  // namespace detail

namespace {

std::string num(double x) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    return buf;
}

}  // namespace

Volume read_nrrd(const std::string& path, const VolumeReadOptions& opt) {
    return detail::NrrdReader(path, "read_nrrd").read_volume(opt);
}

Volume read_nrrd(const std::string& path) { return read_nrrd(path, VolumeReadOptions{}); }

ScalarImage read_nrrd_image(const std::string& path) {
    return detail::NrrdReader(path, "read_nrrd_image").read_image();
}

void write_nrrd(const std::string& path, const Volume& v) {
    v.check("write_nrrd: " + path);
    const Grid& g = v.grid;
    const Placement& pl = g.placement;
    // The file's frame is the world: directions h · rotation columns, origin the world position of
    // sample (0, 0, 0). With the identity placement these are (h,0,0) (0,h,0) (0,0,h) and grid.origin.
    // "(x,y,z)", appended piece by piece (GCC 12's -Wrestrict misreads a chain of + on temporaries here)
    const auto vector = [](const Vec3d& v) {
        std::string t = "(";
        t.append(num(v.x)).append(",").append(num(v.y)).append(",").append(num(v.z)).append(")");
        return t;
    };
    std::string dirs;
    for (int a = 0; a < 3; ++a) {
        if (a) dirs += ' ';
        dirs += vector(pl.is_identity() ? Vec3d{a == 0 ? g.voxel_size : 0.0, a == 1 ? g.voxel_size : 0.0,
                                                a == 2 ? g.voxel_size : 0.0}
                                        : pl.rotation[std::size_t(a)] * g.voxel_size);
    }
    const std::string origin = vector(pl.is_identity() ? g.origin : pl.point(g.origin));
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
