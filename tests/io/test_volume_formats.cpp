// Tests for io/formats/nifti.h and the dense/placed parts of io/formats/nrrd.h (issue 23): NIfTI-1/-2
// files written here with known contents (every datatype, scaling, the three geometry methods, both
// byte orders, gzip), the real shared/data scan, NRRD detached headers with anisotropic and flipped
// axes, placed SDF round trips, and bad input, each refused with the file's name and the problem.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#if defined(NORMALFLOW_HAS_ZLIB)
#include <zlib.h>
#endif

#include "core/errors.h"
#include "io/formats/nifti.h"
#include "io/formats/nrrd.h"
#include "support/test_files.h"

namespace fs = std::filesystem;
using namespace normalflow;
using normalflow::test::slurp;
using normalflow::test::TempDir;
using ::testing::HasSubstr;

namespace {

const std::string kData = std::string(NORMALFLOW_TEST_DATA);

// ---------------------------------------------------------------------------------------------
// A tiny NIfTI writer: the fields read_nifti uses, in either version and byte order.

struct Nifti {
    int version = 1;   // 1 or 2
    bool big = false;  // big-endian file
    std::array<std::int64_t, 8> dim{3, 1, 1, 1, 1, 1, 1, 1};
    int datatype = 2;
    int bitpix = 8;
    std::array<double, 8> pixdim{1, 1, 1, 1, 0, 0, 0, 0};
    double vox_offset = -1;  // -1: header size + 4
    double slope = 0, inter = 0;
    int qform_code = 0, sform_code = 0;
    std::array<double, 3> quat{0, 0, 0};
    std::array<double, 3> qoffset{0, 0, 0};
    std::array<std::array<double, 4>, 3> srow{};
    std::string magic;  // "" = the right one
};

template <class T>
void put(std::string& s, std::size_t off, T v, bool big) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
    std::memcpy(s.data() + off, b, sizeof(T));
}

/// The header and its 4 extension bytes, up to vox_offset (zero-filled).
std::string nifti_header(const Nifti& n) {
    const std::size_t size = n.version == 1 ? 348 : 540;
    const std::size_t vo = n.vox_offset < 0 ? size + 4 : std::size_t(std::max(n.vox_offset, double(size)));
    std::string h(vo, '\0');
    const bool b = n.big;
    put<std::int32_t>(h, 0, std::int32_t(size), b);
    if (n.version == 1) {
        for (int i = 0; i < 8; ++i)
            put<std::int16_t>(h, 40 + 2 * std::size_t(i), std::int16_t(n.dim[std::size_t(i)]), b);
        put<std::int16_t>(h, 70, std::int16_t(n.datatype), b);
        put<std::int16_t>(h, 72, std::int16_t(n.bitpix), b);
        for (int i = 0; i < 8; ++i) put<float>(h, 76 + 4 * std::size_t(i), float(n.pixdim[std::size_t(i)]), b);
        put<float>(h, 108, float(n.vox_offset < 0 ? double(size + 4) : n.vox_offset), b);
        put<float>(h, 112, float(n.slope), b);
        put<float>(h, 116, float(n.inter), b);
        put<std::int16_t>(h, 252, std::int16_t(n.qform_code), b);
        put<std::int16_t>(h, 254, std::int16_t(n.sform_code), b);
        for (int i = 0; i < 3; ++i) put<float>(h, 256 + 4 * std::size_t(i), float(n.quat[std::size_t(i)]), b);
        for (int i = 0; i < 3; ++i) put<float>(h, 268 + 4 * std::size_t(i), float(n.qoffset[std::size_t(i)]), b);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c)
                put<float>(h, 280 + 16 * std::size_t(r) + 4 * std::size_t(c),
                           float(n.srow[std::size_t(r)][std::size_t(c)]), b);
        std::memcpy(h.data() + 344, n.magic.empty() ? "n+1\0" : n.magic.c_str(), 4);
    } else {
        std::memcpy(h.data() + 4, n.magic.empty() ? "n+2\0\r\n\032\n" : n.magic.c_str(), 8);
        put<std::int16_t>(h, 12, std::int16_t(n.datatype), b);
        put<std::int16_t>(h, 14, std::int16_t(n.bitpix), b);
        for (int i = 0; i < 8; ++i) put<std::int64_t>(h, 16 + 8 * std::size_t(i), n.dim[std::size_t(i)], b);
        for (int i = 0; i < 8; ++i) put<double>(h, 104 + 8 * std::size_t(i), n.pixdim[std::size_t(i)], b);
        put<std::int64_t>(h, 168, std::int64_t(n.vox_offset < 0 ? double(size + 4) : n.vox_offset), b);
        put<double>(h, 176, n.slope, b);
        put<double>(h, 184, n.inter, b);
        put<std::int32_t>(h, 344, n.qform_code, b);
        put<std::int32_t>(h, 348, n.sform_code, b);
        for (int i = 0; i < 3; ++i) put<double>(h, 352 + 8 * std::size_t(i), n.quat[std::size_t(i)], b);
        for (int i = 0; i < 3; ++i) put<double>(h, 376 + 8 * std::size_t(i), n.qoffset[std::size_t(i)], b);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c)
                put<double>(h, 400 + 32 * std::size_t(r) + 8 * std::size_t(c), n.srow[std::size_t(r)][std::size_t(c)],
                            b);
    }
    return h;
}

/// Samples of type T in the file's byte order.
template <class T>
std::string samples(const std::vector<T>& v, bool big) {
    std::string s(v.size() * sizeof(T), '\0');
    for (std::size_t i = 0; i < v.size(); ++i) put<T>(s, i * sizeof(T), v[i], big);
    return s;
}

void write_file(const std::string& path, const std::string& bytes) {
    std::ofstream f(path, std::ios::binary);
    f.write(bytes.data(), std::streamsize(bytes.size()));
    ASSERT_TRUE(f.good()) << path;
}

Nifti dims3(int nx, int ny, int nz, int datatype, int bitpix) {
    Nifti n;
    n.dim = {3, nx, ny, nz, 1, 1, 1, 1};
    n.datatype = datatype;
    n.bitpix = bitpix;
    return n;
}

void expect_vec(const Vec3d& a, const Vec3d& b, double tol, const std::string& what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
}

/// f throws E whose message contains every one of parts.
template <class E>
void expect_error(const std::function<void()>& f, const std::vector<std::string>& parts) {
    try {
        f();
        ADD_FAILURE() << "no exception; expected one mentioning " << parts.front();
    } catch (const E& e) {
        const std::string m = e.what();
        for (const std::string& p : parts) EXPECT_THAT(m, HasSubstr(p));
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    } catch (const std::exception& e) {
        ADD_FAILURE() << "wrong exception type: " << e.what();
    }
}

// Values every datatype can hold, 4 x 3 x 2 = 24 of them.
template <class T>
std::vector<T> known_values() {
    std::vector<T> v;
    for (int i = 0; i < 24; ++i) {
        double x = i * 5;
        if (std::numeric_limits<T>::is_signed) x -= 60;
        v.push_back(T(x));
    }
    if constexpr (sizeof(T) >= 4 && std::numeric_limits<T>::is_integer) {
        v[23] = std::numeric_limits<T>::is_signed ? T(-(1 << 24)) : T(1 << 24);  // exact as a float
    }
    return v;
}

template <class T>
void datatype_round_trip(int code, bool big, int version) {
    SCOPED_TRACE("datatype " + std::to_string(code) + (big ? " big-endian" : "") + " NIfTI-" + std::to_string(version));
    TempDir dir;
    Nifti n = dims3(4, 3, 2, code, int(8 * sizeof(T)));
    n.big = big;
    n.version = version;
    const auto v = known_values<T>();
    write_file(dir / "a.nii", nifti_header(n) + samples(v, big));
    const ScalarImage img = read_nifti(dir / "a.nii");
    EXPECT_EQ(img.dims, (std::array<int, 3>{4, 3, 2}));
    ASSERT_EQ(img.values.size(), 24u);
    for (std::size_t i = 0; i < 24; ++i) EXPECT_EQ(img.values[i], float(v[i])) << "sample " << i;
    EXPECT_EQ(img.at(1, 2, 1), float(v[1 + 4 * (2 + 3 * 1)]));
    // pixdim-only geometry: unit axes at 0.
    expect_vec(img.axes[0], {1, 0, 0}, 0, "axis 0");
    expect_vec(img.axes[2], {0, 0, 1}, 0, "axis 2");
    expect_vec(img.origin, {0, 0, 0}, 0, "origin");
}

#if defined(NORMALFLOW_HAS_ZLIB)
void write_gzip(const std::string& path, const std::string& bytes) {
    gzFile gz = gzopen(path.c_str(), "wb");
    ASSERT_NE(gz, nullptr);
    ASSERT_EQ(gzwrite(gz, bytes.data(), unsigned(bytes.size())), int(bytes.size()));
    ASSERT_EQ(gzclose(gz), Z_OK);
}
#endif

}  // namespace

// ---------------------------------------------------------------------------------------------
// NIfTI: known answers

TEST(Nifti, EveryDatatypeRoundTrips) {
    for (const bool big : {false, true})
        for (const int version : {1, 2}) {
            datatype_round_trip<std::uint8_t>(2, big, version);
            datatype_round_trip<std::int8_t>(256, big, version);
            datatype_round_trip<std::int16_t>(4, big, version);
            datatype_round_trip<std::uint16_t>(512, big, version);
            datatype_round_trip<std::int32_t>(8, big, version);
            datatype_round_trip<std::uint32_t>(768, big, version);
            datatype_round_trip<std::int64_t>(1024, big, version);
            datatype_round_trip<std::uint64_t>(1280, big, version);
            datatype_round_trip<float>(16, big, version);
            datatype_round_trip<double>(64, big, version);
        }
}

TEST(Nifti, SlopeAndIntercept) {
    TempDir dir;
    Nifti n = dims3(2, 2, 1, 4, 16);
    n.slope = 0.5;
    n.inter = -3;
    write_file(dir / "s.nii", nifti_header(n) + samples<std::int16_t>({0, 1, -4, 100}, false));
    const ScalarImage img = read_nifti(dir / "s.nii");
    EXPECT_EQ(img.values, (std::vector<float>{-3.f, -2.5f, -5.f, 47.f}));

    n.slope = 0;  // 0: no scaling, the intercept is not used either
    n.inter = 7;
    write_file(dir / "z.nii", nifti_header(n) + samples<std::int16_t>({0, 1, -4, 100}, false));
    EXPECT_EQ(read_nifti(dir / "z.nii").values, (std::vector<float>{0.f, 1.f, -4.f, 100.f}));
}

TEST(Nifti, SformGivesAxesAndOrigin) {
    TempDir dir;
    for (const int version : {1, 2}) {
        Nifti n = dims3(2, 1, 1, 16, 32);
        n.version = version;
        n.sform_code = 2;
        n.qform_code = 1;  // sform wins
        n.quat = {0.5, 0.5, 0.5};
        n.srow = {{{0, -1.5, 0.25, 10}, {2, 0, 0, -5}, {0, 0.5, 3, 7.5}}};
        write_file(dir / "f.nii", nifti_header(n) + samples<float>({1.f, 2.f}, false));
        const ScalarImage img = read_nifti(dir / "f.nii");
        expect_vec(img.axes[0], {0, 2, 0}, 0, "axis 0");
        expect_vec(img.axes[1], {-1.5, 0, 0.5}, 0, "axis 1");
        expect_vec(img.axes[2], {0.25, 0, 3}, 0, "axis 2");
        expect_vec(img.origin, {10, -5, 7.5}, 0, "origin");
    }
}

TEST(Nifti, QformRotationAndQfac) {
    TempDir dir;
    for (const int version : {1, 2}) {
        // 90 degrees about z: (b, c, d) = (0, 0, sin 45°); qfac -1 flips k.
        Nifti n = dims3(1, 1, 2, 2, 8);
        n.version = version;
        n.qform_code = 1;
        n.quat = {0, 0, std::sqrt(0.5)};
        n.pixdim = {-1, 0.5, 0.75, 2, 0, 0, 0, 0};
        n.qoffset = {1, 2, 3};
        write_file(dir / "q.nii", nifti_header(n) + samples<std::uint8_t>({3, 4}, false));
        const ScalarImage img = read_nifti(dir / "q.nii");
        expect_vec(img.axes[0], {0, 0.5, 0}, 1e-6, "axis 0");
        expect_vec(img.axes[1], {-0.75, 0, 0}, 1e-6, "axis 1");
        expect_vec(img.axes[2], {0, 0, -2}, 1e-6, "axis 2");
        expect_vec(img.origin, {1, 2, 3}, 0, "origin");

        n.pixdim[0] = 0;  // qfac 0 means 1
        write_file(dir / "q.nii", nifti_header(n) + samples<std::uint8_t>({3, 4}, false));
        expect_vec(read_nifti(dir / "q.nii").axes[2], {0, 0, 2}, 1e-6, "axis 2, qfac 0");
    }
}

TEST(Nifti, PixdimOnlyGeometry) {
    TempDir dir;
    Nifti n = dims3(1, 1, 1, 2, 8);
    n.pixdim = {0, 2, -3, 4, 0, 0, 0, 0};
    write_file(dir / "p.nii", nifti_header(n) + samples<std::uint8_t>({9}, false));
    const ScalarImage img = read_nifti(dir / "p.nii");
    expect_vec(img.axes[0], {2, 0, 0}, 0, "axis 0");
    expect_vec(img.axes[1], {0, 3, 0}, 0, "axis 1");
    expect_vec(img.axes[2], {0, 0, 4}, 0, "axis 2");
    expect_vec(img.origin, {0, 0, 0}, 0, "origin");
}

TEST(Nifti, TrailingUnitDimensionsAndExtensionsAccepted) {
    TempDir dir;
    Nifti n = dims3(2, 1, 1, 2, 8);
    n.dim = {5, 2, 1, 1, 1, 1, 0, 0};  // dims beyond dim[0] are not used
    n.vox_offset = 400;                // 48 bytes of extensions to skip
    std::string h = nifti_header(n);
    std::fill(h.begin() + 352, h.end(), 'x');
    write_file(dir / "e.nii", h + samples<std::uint8_t>({5, 6}, false));
    EXPECT_EQ(read_nifti(dir / "e.nii").values, (std::vector<float>{5.f, 6.f}));
}

TEST(Nifti, Gzip) {
#if !defined(NORMALFLOW_HAS_ZLIB)
    GTEST_SKIP() << "built without zlib";
#else
    TempDir dir;
    for (const int version : {1, 2}) {
        Nifti n = dims3(3, 2, 2, 16, 32);
        n.version = version;
        n.big = version == 2;
        std::vector<float> v;
        for (int i = 0; i < 12; ++i) v.push_back(0.25f * float(i) - 1.f);
        const std::string bytes = nifti_header(n) + samples(v, n.big);
        write_gzip(dir / "g.nii.gz", bytes);
        const ScalarImage img = read_nifti(dir / "g.nii.gz");
        EXPECT_EQ(img.dims, (std::array<int, 3>{3, 2, 2}));
        EXPECT_EQ(img.values, v);

        // Truncated: the compressed stream cut short.
        const std::string gz = slurp(dir / "g.nii.gz");
        write_file(dir / "cut.nii.gz", gz.substr(0, gz.size() - 20));
        expect_error<InvalidInput>([&] { (void)read_nifti(dir / "cut.nii.gz"); }, {"cut.nii.gz", "truncated"});
        // The data ends early inside a complete gzip stream.
        write_gzip(dir / "short.nii.gz", bytes.substr(0, bytes.size() - 8));
        expect_error<InvalidInput>([&] { (void)read_nifti(dir / "short.nii.gz"); }, {"short.nii.gz", "truncated data"});
    }
    // Sizes beyond what the compressed bytes can hold: refused before allocating.
    Nifti big = dims3(30000, 30000, 100, 16, 32);
    write_gzip(dir / "huge.nii.gz", nifti_header(big));
    expect_error<InvalidInput>([&] { (void)read_nifti(dir / "huge.nii.gz"); }, {"huge.nii.gz", "gzip data can hold"});
#endif
}

TEST(Nifti, SharedWhiteMatterProbabilityMap) {
    const std::string path = kData + "/medical/pve_2_whitematter.nii.gz";
    if (!fs::exists(path)) GTEST_SKIP() << path << " not found (shared/data is not shipped)";
#if !defined(NORMALFLOW_HAS_ZLIB)
    GTEST_SKIP() << "built without zlib";
#else
    const ScalarImage img = read_nifti(path);
    EXPECT_EQ(img.dims, (std::array<int, 3>{142, 178, 142}));
    ASSERT_EQ(img.values.size(), 142u * 178u * 142u);
    // uint8 with scl_slope 1/255: 255 becomes 1.
    EXPECT_NEAR(*std::max_element(img.values.begin(), img.values.end()), 1.0, 1e-6);
    EXPECT_EQ(*std::min_element(img.values.begin(), img.values.end()), 0.0f);
    EXPECT_EQ(std::count_if(img.values.begin(), img.values.end(), [](float x) { return x != 0; }), 704351);
    EXPECT_NEAR(img.at(69, 75, 3), 1.0, 1e-6);  // the first sample at 255
    double sum = 0;
    for (const float x : img.values) sum += x;
    EXPECT_NEAR(sum, 150978045.0 * double(0.003921568859368563f), 1e-6 * sum);  // floats, rounded one by one
    // sform_code 2: the axes are the sform's columns, the origin its fourth column.
    expect_vec(img.axes[0], {0.9973992109298706, 0.038681745529174805, -0.06081497669219971}, 1e-7, "axis 0");
    expect_vec(img.axes[1], {-0.038610100746154785, 0.9992516040802002, 0.0023542046546936035}, 1e-7, "axis 1");
    expect_vec(img.axes[2], {0.060860514640808105, 0.0, 0.9981462955474854}, 1e-7, "axis 2");
    expect_vec(img.origin, {-69.86038970947266, -101.27803802490234, -30.634437561035156}, 1e-5, "origin");
#endif
}

// ---------------------------------------------------------------------------------------------
// NIfTI: bad input, each refused with the file's name and the problem

TEST(Nifti, BadInput) {
    TempDir dir;
    const Nifti good = dims3(4, 3, 2, 2, 8);
    const std::string data(24, '\x07');
    auto refuse = [&](const std::string& name, const std::string& bytes, const std::vector<std::string>& problem) {
        SCOPED_TRACE(name);
        write_file(dir / name, bytes);
        std::vector<std::string> parts = problem;
        parts.insert(parts.begin(), {"read_nifti", name});
        expect_error<InvalidInput>([&] { (void)read_nifti(dir / name); }, parts);
    };
    refuse("empty.nii", "", {"empty"});
    refuse("short_header.nii", nifti_header(good).substr(0, 100), {"truncated header"});
    refuse("short_header2.nii",
           nifti_header([] {
               Nifti n;
               n.version = 2;
               return n;
           }())
               .substr(0, 300),
           {"truncated header"});
    refuse("truncated_data.nii", nifti_header(good) + data.substr(0, 20), {"truncated"});
    {
        Nifti n = good;
        n.magic = "abc";
        refuse("magic.nii", nifti_header(n) + data, {"not a NIfTI-1 file", "magic"});
        n.magic = std::string("ni1\0", 4);
        refuse("pair.nii", nifti_header(n) + data, {".img"});
        n.version = 2;
        n.magic = "n+2_____";
        refuse("magic2.nii", nifti_header(n) + data, {"not a NIfTI-2 file"});
    }
    refuse("not_nifti.nii", std::string(400, 'A'), {"not a NIfTI file", "sizeof_hdr"});
    {
        Nifti n = good;
        n.dim = {5, 4, 3, 2, 2, 1, 1, 1};
        refuse("four_d.nii", nifti_header(n) + data + data, {"dim[4] is 2", "3-D"});
        n.dim = {2, 4, 3, 1, 1, 1, 1, 1};
        refuse("two_d.nii", nifti_header(n) + data, {"dim[0] is 2"});
        n.dim = {3, 4, 0, 2, 1, 1, 1, 1};
        refuse("zero_dim.nii", nifti_header(n) + data, {"dim[2] is 0"});
        n.dim = {3, 4, -3, 2, 1, 1, 1, 1};
        refuse("negative_dim.nii", nifti_header(n) + data, {"dim[2] is -3"});
    }
    {
        Nifti n = good;
        n.datatype = 128;
        n.bitpix = 24;
        refuse("rgb.nii", nifti_header(n) + data + data + data, {"RGB24", "128", "not supported"});
        n.datatype = 32;
        refuse("complex.nii", nifti_header(n) + std::string(24 * 8, '\0'), {"COMPLEX64", "not supported"});
        n.datatype = 3;
        refuse("odd_type.nii", nifti_header(n) + data, {"datatype", "(code 3)"});
    }
    {
        Nifti n = dims3(1000, 1000, 1000, 16, 32);
        refuse("too_big.nii", nifti_header(n) + data, {"the file holds only"});
        n.version = 2;
        n.dim = {3, 1 << 20, 1 << 20, 1 << 20, 1, 1, 1, 1};
        refuse("beyond_2_40.nii", nifti_header(n) + data, {"2^40"});
    }
    {
        Nifti n = dims3(2, 2, 1, 16, 32);
        refuse("nan.nii", nifti_header(n) + samples<float>({1.f, 2.f, std::nanf(""), 4.f}, false),
               {"sample 2", "(0, 1, 0)", "NaN"});
        refuse("inf.nii",
               nifti_header(n) + samples<float>({1.f, std::numeric_limits<float>::infinity(), 0.f, 4.f}, false),
               {"sample 1", "infinite"});
        n.datatype = 64;
        n.bitpix = 64;
        refuse("beyond_float.nii", nifti_header(n) + samples<double>({1, 2, 3, 1e300}, false),
               {"sample 3", "float range"});
        n.datatype = 2;
        n.bitpix = 8;
        n.slope = 1e38f;
        refuse("scaled_beyond.nii", nifti_header(n) + samples<std::uint8_t>({0, 1, 2, 200}, false),
               {"sample 3", "scl_slope"});
    }
    {
        Nifti n = good;
        n.vox_offset = 100;
        std::string h = nifti_header(n);
        refuse("vox_offset.nii", h + std::string(400, '\0'), {"vox_offset", "header"});
        n.vox_offset = 352.5;
        refuse("vox_offset_frac.nii", nifti_header(n) + data + "x", {"vox_offset"});
    }
    {
        Nifti n = good;
        n.qform_code = 1;
        n.pixdim = {1, 1, 0, 1, 0, 0, 0, 0};
        refuse("qform_pixdim.nii", nifti_header(n) + data, {"pixdim[2]", "> 0"});
        n.qform_code = 0;
        refuse("pixdim_zero.nii", nifti_header(n) + data, {"pixdim[2]"});
        n.pixdim = {1, 1, 1, 1, 0, 0, 0, 0};
        n.sform_code = 1;  // all-zero srow
        refuse("sform_zero.nii", nifti_header(n) + data, {"axis 0", "no length"});
        n.srow = {{{1, 0, 0, std::nan("")}, {0, 1, 0, 0}, {0, 0, 1, 0}}};
        refuse("sform_nan.nii", nifti_header(n) + data, {"sform offset", "not finite"});
    }
    expect_error<IoError>([&] { (void)read_nifti(dir / "missing.nii"); }, {"read_nifti", "missing.nii", "cannot open"});
    expect_error<IoError>([&] { (void)read_nifti(dir.path().string()); }, {"read_nifti", "not a regular file"});
}

// ---------------------------------------------------------------------------------------------
// NRRD: dense images with any spacing and orientation, detached headers

TEST(NrrdImage, DetachedAnisotropicFlipped) {
    TempDir dir;
    fs::create_directories(dir.path() / "sub");
    // 3 x 2 x 2 big-endian int16, x flipped, z spacing 2.5; 6 bytes to skip, then the samples.
    std::vector<std::int16_t> v;
    for (int i = 0; i < 12; ++i) v.push_back(std::int16_t(i * 10 - 30));
    write_file((dir.path() / "sub" / "img.raw").string(), "skip!!" + samples(v, true));
    write_file(dir / "a.nhdr",
               "NRRD0004\n# detached\ntype: short\ndimension: 3\nspace: right-anterior-superior\n"
               "sizes: 3 2 2\nspace directions: (-1,0,0) (0,1,0) (0,0,2.5)\nendian: big\nencoding: raw\n"
               "byte skip: 6\nspace origin: (10,20,30)\ndata file: sub/img.raw\n");
    const ScalarImage img = read_nrrd_image(dir / "a.nhdr");
    EXPECT_EQ(img.dims, (std::array<int, 3>{3, 2, 2}));
    ASSERT_EQ(img.values.size(), 12u);
    for (std::size_t i = 0; i < 12; ++i) EXPECT_EQ(img.values[i], float(v[i]));
    expect_vec(img.axes[0], {-1, 0, 0}, 0, "axis 0");
    expect_vec(img.axes[1], {0, 1, 0}, 0, "axis 1");
    expect_vec(img.axes[2], {0, 0, 2.5}, 0, "axis 2");
    expect_vec(img.origin, {10, 20, 30}, 0, "origin");

    // read_nrrd (the signed-distance reader) still refuses anisotropic voxels, with its message.
    expect_error<InvalidInput>([&] { (void)read_nrrd(dir / "a.nhdr"); }, {"read_nrrd", "a.nhdr", "anisotropic"});
}

TEST(NrrdImage, SpacingsAxisMinsAndAttachedAscii) {
    TempDir dir;
    write_file(dir / "s.nrrd",
               "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 1 2\nspacings: 0.5 1 -2\naxis mins: 1 2 3\n"
               "encoding: ascii\n\n1.5 -2\n3 4e1\n");
    const ScalarImage img = read_nrrd_image(dir / "s.nrrd");
    EXPECT_EQ(img.values, (std::vector<float>{1.5f, -2.f, 3.f, 40.f}));
    expect_vec(img.axes[0], {0.5, 0, 0}, 0, "axis 0");
    expect_vec(img.axes[2], {0, 0, -2}, 0, "axis 2");
    expect_vec(img.origin, {1, 2, 3}, 0, "origin");
}

TEST(NrrdImage, BadDetachedHeaders) {
    TempDir dir;
    const std::string head = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n";
    write_file(dir / "missing.nhdr", head + "data file: nowhere.raw\n");
    for (const bool image : {true, false}) {
        try {
            if (image)
                (void)read_nrrd_image(dir / "missing.nhdr");
            else
                (void)read_nrrd(dir / "missing.nhdr");
            ADD_FAILURE() << "a missing data file was read";
        } catch (const IoError& e) {
            EXPECT_THAT(std::string(e.what()), HasSubstr("nowhere.raw"));
            EXPECT_THAT(std::string(e.what()), HasSubstr("missing.nhdr"));
        } catch (const InvalidInput& e) {
            EXPECT_THAT(std::string(e.what()), HasSubstr("nowhere.raw"));
        }
    }
    write_file(dir / "list.nhdr", head + "data file: LIST\na.raw\nb.raw\n");
    expect_error<InvalidInput>([&] { (void)read_nrrd_image(dir / "list.nhdr"); },
                               {"list.nhdr", "LIST", "single data file"});
    write_file(dir / "fmt.nhdr", head + "data file: slice%03d.raw 1 2 1\n");
    expect_error<InvalidInput>([&] { (void)read_nrrd_image(dir / "fmt.nhdr"); }, {"fmt.nhdr", "format string"});
    write_file(dir / "short.raw", std::string(7, '\1'));
    write_file(dir / "short.nhdr", head + "data file: short.raw\n");
    expect_error<InvalidInput>([&] { (void)read_nrrd_image(dir / "short.nhdr"); }, {"short.nhdr", "holds only 7"});
    write_file(dir / "zero.nrrd", head + "spacings: 1 0 1\n\n" + std::string(8, '\0'));
    expect_error<InvalidInput>([&] { (void)read_nrrd_image(dir / "zero.nrrd"); },
                               {"zero.nrrd", "spacings: axis 1 is 0"});
}

// ---------------------------------------------------------------------------------------------
// NRRD: placed signed-distance volumes

namespace {

/// A small valid volume: one allocated block of known values, the rest outside.
Volume small_volume(const Placement& pl, const Vec3d& origin, double h) {
    Grid g;
    g.origin = origin;
    g.voxel_size = h;
    g.dims = {5, 4, 3};
    g.placement = pl;
    Volume v(g, 3.f);
    for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 5; ++i) v.set(i, j, k, float(h * (i - 2 + 0.25 * j - 0.5 * k)));
    return v;
}

Vec3d world_of(const Grid& g, int i, int j, int k) { return g.placement.point(g.world(Vec3d(i, j, k))); }

void expect_same_world(const Volume& a, const Volume& b) {
    ASSERT_EQ(a.grid.dims, b.grid.dims);
    EXPECT_NEAR(a.grid.voxel_size, b.grid.voxel_size, 1e-12);
    for (int k = 0; k < a.grid.dims[2]; ++k)
        for (int j = 0; j < a.grid.dims[1]; ++j)
            for (int i = 0; i < a.grid.dims[0]; ++i) {
                expect_vec(world_of(a.grid, i, j, k), world_of(b.grid, i, j, k), 1e-12, "sample position");
                EXPECT_EQ(a.value(i, j, k), b.value(i, j, k));
            }
}

}  // namespace

TEST(NrrdPlacement, IdentityPlacementWritesAsBefore) {
    TempDir dir;
    const Volume v = small_volume(Placement{}, {-1.5, 2, 0.25}, 0.5);
    write_nrrd(dir / "v.nrrd", v);
    const std::string text = slurp(dir / "v.nrrd");
    EXPECT_THAT(text, HasSubstr("space directions: (0.5,0,0) (0,0.5,0) (0,0,0.5)\n"));
    EXPECT_THAT(text, HasSubstr("space origin: (-1.5,2,0.25)\n"));
    const Volume r = read_nrrd(dir / "v.nrrd");
    EXPECT_TRUE(r.grid.placement.is_identity());
    EXPECT_EQ(r.grid.origin, v.grid.origin);
    EXPECT_EQ(r.grid.voxel_size, v.grid.voxel_size);
    expect_same_world(v, r);
}

TEST(NrrdPlacement, RotatedIsotropicRoundTrip) {
    TempDir dir;
    // A rotation of 30 degrees about (1, 1, 1)/sqrt(3) (Rodrigues), then with the y axis flipped.
    const Vec3d ax = normalized(Vec3d{1, 1, 1});
    const double c = std::cos(std::numbers::pi / 6), s = std::sin(std::numbers::pi / 6);
    Placement pl;
    for (int a = 0; a < 3; ++a) {
        Vec3d e{};
        e[a] = 1;
        pl.rotation[std::size_t(a)] = e * c + cross(ax, e) * s + ax * (dot(ax, e) * (1 - c));
    }
    pl.translation = {10, -20, 5};
    for (const bool flip : {false, true}) {
        SCOPED_TRACE(flip ? "reflection" : "rotation");
        Placement p = pl;
        if (flip) p.rotation[1] = -p.rotation[1];
        const Volume v = small_volume(p, {0.5, -1, 2}, 0.25);
        write_nrrd(dir / "r.nrrd", v);
        const Volume r = read_nrrd(dir / "r.nrrd");
        EXPECT_EQ(r.grid.origin, Vec3d{});  // the whole offset moves into the placement
        EXPECT_EQ(r.grid.placement.reflects(), flip);
        expect_same_world(v, r);
        r.check("test");
    }
    // A translation alone stays axis-aligned: identity placement, the offset in grid.origin.
    Placement t;
    t.translation = {1, 2, 3};
    const Volume v = small_volume(t, {0.5, -1, 2}, 0.25);
    write_nrrd(dir / "t.nrrd", v);
    const Volume r = read_nrrd(dir / "t.nrrd");
    EXPECT_TRUE(r.grid.placement.is_identity());
    EXPECT_EQ(r.grid.origin, (Vec3d{1.5, 1, 5}));
    expect_same_world(v, r);
}

TEST(NrrdPlacement, FlippedDetachedSdfAndRefusals) {
    TempDir dir;
    std::vector<float> v(8);
    for (int i = 0; i < 8; ++i) v[std::size_t(i)] = float(i) - 3.5f;
    write_file(dir / "d.raw", samples(v, false));
    const std::string head =
        "NRRD0005\ntype: float\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n"
        "data file: d.raw\nspace origin: (1,2,3)\n";
    write_file(dir / "flip.nhdr", head + "space directions: (0,0,-2) (0,2,0) (2,0,0)\n");
    const Volume r = read_nrrd(dir / "flip.nhdr");
    EXPECT_EQ(r.grid.voxel_size, 2.0);
    EXPECT_EQ(r.grid.origin, Vec3d{});
    expect_vec(r.grid.placement.rotation[0], {0, 0, -1}, 0, "rotation 0");
    expect_vec(r.grid.placement.rotation[1], {0, 1, 0}, 0, "rotation 1");
    expect_vec(r.grid.placement.rotation[2], {1, 0, 0}, 0, "rotation 2");
    expect_vec(world_of(r.grid, 1, 1, 1), {3, 4, 1}, 1e-12, "sample (1,1,1)");
    EXPECT_EQ(r.value(1, 0, 1), 1.5f);

    write_file(dir / "skew.nhdr", head + "space directions: (1,0,0) (0.6,0.8,0) (0,0,1)\n");
    expect_error<InvalidInput>([&] { (void)read_nrrd(dir / "skew.nhdr"); }, {"skew.nhdr", "orthogonal"});
    write_file(dir / "aniso.nhdr", head + "space directions: (0,1,0) (1,0,0) (0,0,1.5)\n");
    expect_error<InvalidInput>([&] { (void)read_nrrd(dir / "aniso.nhdr"); }, {"aniso.nhdr", "anisotropic"});
    // read_nrrd_image takes both as written.
    const ScalarImage img = read_nrrd_image(dir / "skew.nhdr");
    expect_vec(img.axes[1], {0.6, 0.8, 0}, 0, "skewed axis");
}
