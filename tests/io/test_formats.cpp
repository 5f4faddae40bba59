// Tests for io/formats/mesh_formats.h and io/io.h: hand-made fixtures with known contents,
// bit-exact round trips of every format and variant, then real models from shared/data.
#include "io/formats/mesh_formats.h"
#include "support/test_files.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "core/errors.h"
#include "io/io.h"

namespace fs = std::filesystem;
using namespace normalflow;

using normalflow::test::slurp;
using normalflow::test::TempDir;

namespace {

const std::string kFixtures = std::string(NORMALFLOW_TEST_FIXTURES);
const std::string kData = std::string(NORMALFLOW_TEST_DATA);

// The unit cube of the fixtures: 8 corners, 6 quads, split into the fans (0,k,k+1).
const std::vector<Vec3f> kCubeV = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const std::vector<Tri> kCubeT = {{0, 3, 2}, {0, 2, 1}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                 {2, 3, 7}, {2, 7, 6}, {0, 4, 7}, {0, 7, 3}, {1, 2, 6}, {1, 6, 5}};

bool same_bits(const Vec3f& a, const Vec3f& b) { return std::memcmp(&a, &b, sizeof(Vec3f)) == 0; }

void expect_identical(const Mesh& a, const Mesh& b) {
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    for (std::size_t i = 0; i < a.positions.size(); ++i)
        ASSERT_TRUE(same_bits(a.positions[i], b.positions[i]))
            << "vertex " << i << ": " << a.positions[i].x << " " << a.positions[i].y << " " << a.positions[i].z
            << " vs " << b.positions[i].x << " " << b.positions[i].y << " " << b.positions[i].z;
    for (std::size_t i = 0; i < a.triangles.size(); ++i) ASSERT_EQ(a.triangles[i], b.triangles[i]) << "triangle " << i;
}

/// STL stores 3 points per triangle: the soup read back must be m with its corners expanded.
void expect_expanded(const Mesh& m, const Mesh& stl) {
    ASSERT_EQ(stl.triangles.size(), m.triangles.size());
    ASSERT_EQ(stl.positions.size(), 3 * m.triangles.size());
    for (std::size_t i = 0; i < m.triangles.size(); ++i)
        for (std::size_t k = 0; k < 3; ++k) {
            ASSERT_EQ(stl.triangles[i][k], 3 * i + k);
            ASSERT_TRUE(same_bits(stl.positions[3 * i + k], m.positions[m.triangles[i][k]])) << "triangle " << i;
        }
}

/// A mesh whose coordinates exercise float formatting: tiny, huge, subnormal, negative zero,
/// values that need all 9 significant digits, random bits.
Mesh tricky_mesh() {
    Mesh m;
    const float special[] = {0.1f,
                             -0.0f,
                             1e-30f,
                             3.4028235e38f,
                             -3.4028235e38f,
                             1.17549435e-38f,
                             1.4e-45f /* smallest subnormal */,
                             123456.789f,
                             16777217.0f,
                             0.33333334f,
                             -2.5e-3f,
                             7.0f};
    for (std::size_t i = 0; i + 2 < std::size(special); i += 3)
        m.positions.push_back({special[i], special[i + 1], special[i + 2]});
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> u(-1000.f, 1000.f);
    std::uniform_int_distribution<int> expo(-40, 38);
    for (int i = 0; i < 200; ++i) {
        Vec3f v{u(rng), u(rng), u(rng)};
        v.x = std::ldexp(v.x, expo(rng) / 4);
        m.positions.push_back(v);
    }
    const auto n = std::uint32_t(m.positions.size());
    std::uniform_int_distribution<std::uint32_t> pick(0, n - 1);
    for (int i = 0; i < 300; ++i) m.triangles.push_back({pick(rng), pick(rng), pick(rng)});
    m.triangles.push_back({n - 1, 0, n - 2});  // touches the first and last vertex
    return m;
}

}  // namespace

// ------------------------------------------------------------------------------------- dispatcher

TEST(MeshFormatFromPath, ExtensionsCaseInsensitive) {
    EXPECT_EQ(mesh_format_from_path("a.obj"), MeshFormat::Obj);
    EXPECT_EQ(mesh_format_from_path("dir.ply/a.OBJ"), MeshFormat::Obj);
    EXPECT_EQ(mesh_format_from_path("/x/y/scan.PlY"), MeshFormat::Ply);
    EXPECT_EQ(mesh_format_from_path("a.off"), MeshFormat::Off);
    EXPECT_EQ(mesh_format_from_path("a.Stl"), MeshFormat::Stl);
    EXPECT_EQ(mesh_format_from_path("a.gltf"), MeshFormat::Gltf);
    EXPECT_EQ(mesh_format_from_path("a.GLB"), MeshFormat::Glb);
    EXPECT_EQ(mesh_format_from_path("a.drc"), MeshFormat::Drc);
    EXPECT_EQ(mesh_format_from_path("a.ply.gz"), MeshFormat::Unknown);
    EXPECT_EQ(mesh_format_from_path("ply"), MeshFormat::Unknown);
    EXPECT_EQ(mesh_format_from_path("a."), MeshFormat::Unknown);
    EXPECT_EQ(mesh_format_from_path(""), MeshFormat::Unknown);
    EXPECT_TRUE(is_volume_path("a.VDB"));
    EXPECT_TRUE(is_volume_path("a.nrrd"));
    EXPECT_FALSE(is_volume_path("a.ply"));
}

// ------------------------------------------------------------------------------------- fixtures

TEST(ReadObj, QuadsWithEveryCornerForm) {
    ReadInfo info;
    const Mesh m = read_mesh(kFixtures + "/cube_quads.obj", &info);
    // The fixture's top face gives vertices 8 and 7 other texture coordinates than the bottom face
    // did: each gets a copy, appended after the file's vertices, and that face uses the copies.
    std::vector<Vec3f> v = kCubeV;
    v.push_back(kCubeV[7]);
    v.push_back(kCubeV[6]);
    EXPECT_EQ(m.positions, v);
    std::vector<Tri> t = kCubeT;
    t[6] = {2, 3, 8};
    t[7] = {2, 8, 9};
    EXPECT_EQ(m.triangles, t);
    const std::vector<TexCoord> vt = {{0, 0}, {0, 0}, {1, 1}, {0, 1}, {0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}, {1, 0}};
    EXPECT_EQ(m.texcoords, vt);
    EXPECT_FALSE(m.has_normals());  // its vn references are out of range: dropped, the file is still read
    EXPECT_EQ(info.format, "obj");
    EXPECT_EQ(info.file_vertices, 8u);
    EXPECT_EQ(info.file_faces, 6u);
    EXPECT_EQ(info.polygons_split, 6u);
    ASSERT_EQ(info.warnings.size(), 3u);
    EXPECT_NE(info.warnings[0].find("6 faces had more than 3 corners"), std::string::npos) << info.warnings[0];
    EXPECT_EQ(info.warnings[1], "normal index 5 at line 23 is out of range (the file has 2); the normals are ignored");
    EXPECT_EQ(info.warnings[2],
              "2 vertices duplicated where their corners have different texture coordinates or normals");
}

TEST(ReadObj, NegativeIndicesCountBackFromTheLastVertexRead) {
    ReadInfo info;
    const Mesh m = read_obj(kFixtures + "/cube_negative.obj", &info);
    EXPECT_EQ(m.positions, kCubeV);
    EXPECT_EQ(m.triangles, kCubeT);
    EXPECT_EQ(info.file_faces, 12u);
    EXPECT_EQ(info.polygons_split, 0u);
    EXPECT_TRUE(info.warnings.empty());
}

TEST(ReadObj, LenientSyntax) {
    // CRLF, tabs, '+' signs, w coordinate and vertex colours, a pentagon, unknown statements.
    const std::string s =
        "v 0 0 0\r\nv\t1 0 0 1.0\r\nv +1 1 0 0.5 0.5 0.5\r\nv 0 1e0 0\r\nv -0.5 0.5 0\r\n"
        "weird statement\r\nf 1 2 3 4 5 # pentagon\r\n";
    ReadInfo info;
    const Mesh m = read_obj_memory(s, "lenient.obj", &info);
    ASSERT_EQ(m.positions.size(), 5u);
    EXPECT_EQ(m.positions[2], (Vec3f{1, 1, 0}));
    EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}));
    EXPECT_EQ(info.polygons_split, 1u);
    ASSERT_EQ(info.warnings.size(), 2u);
    EXPECT_NE(info.warnings[1].find("line 6"), std::string::npos) << info.warnings[1];
}

TEST(ReadPly, AsciiWithExtraPropertiesAfterTheList) {
    ReadInfo info;
    const Mesh m = read_mesh(kFixtures + "/cube_ascii.ply", &info);
    EXPECT_EQ(m.positions, kCubeV);
    EXPECT_EQ(m.triangles, kCubeT);
    EXPECT_EQ(info.format, "ply-ascii");
    EXPECT_EQ(info.file_vertices, 8u);
    EXPECT_EQ(info.file_faces, 6u);
    EXPECT_EQ(info.polygons_split, 6u);
}

TEST(ReadPly, BigEndianDoublesListsInVertexAndSkippedElement) {
    ReadInfo info;
    const Mesh m = read_mesh(kFixtures + "/cube_be.ply", &info);
    EXPECT_EQ(m.positions, kCubeV);
    EXPECT_EQ(m.triangles, kCubeT);
    EXPECT_EQ(info.format, "ply-binary-be");
    EXPECT_EQ(info.file_faces, 6u);
    EXPECT_EQ(info.polygons_split, 6u);
}

TEST(ReadPly, IntegerAndDoubleCoordinateTypesLittleEndian) {
    // x as short, y as uchar, z as double; indices as uchar count + ushort items
    std::string s =
        "ply\r\nformat binary_little_endian 1.0\r\nelement vertex 3\r\nproperty short x\r\nproperty uchar y\r\n"
        "property double z\r\nelement face 1\r\nproperty list uint8 uint16 vertex_indices\r\nend_header\r\n";
    auto put = [&](auto v) { s.append(reinterpret_cast<const char*>(&v), sizeof v); };
    put(std::int16_t(-3)), put(std::uint8_t(200)), put(0.25);
    put(std::int16_t(1)), put(std::uint8_t(0)), put(-1e10);
    put(std::int16_t(0)), put(std::uint8_t(1)), put(0.0);
    put(std::uint8_t(3)), put(std::uint16_t(2)), put(std::uint16_t(1)), put(std::uint16_t(0));
    ReadInfo info;
    const Mesh m = read_ply_memory(s, "types.ply", &info);
    EXPECT_EQ(info.format, "ply-binary-le");
    EXPECT_EQ(m.positions, (std::vector<Vec3f>{{-3, 200, 0.25f}, {1, 0, -1e10f}, {0, 1, 0}}));
    EXPECT_EQ(m.triangles, (std::vector<Tri>{{2, 1, 0}}));
}

TEST(ReadOff, CommentsBlankLinesAndFaceColours) {
    ReadInfo info;
    const Mesh m = read_mesh(kFixtures + "/cube_colors.off", &info);
    EXPECT_EQ(m.positions, kCubeV);
    EXPECT_EQ(m.triangles, kCubeT);
    EXPECT_EQ(info.format, "off");
    EXPECT_EQ(info.file_faces, 6u);
    EXPECT_EQ(info.polygons_split, 6u);
}

TEST(ReadOff, CountsOnTheHeaderLineAndColouredVertices) {
    const Mesh m = read_off_memory("COFF 3 1 0\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n3 0 1 2\n", "c.off");
    EXPECT_EQ(m.positions, (std::vector<Vec3f>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
    EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}}));
}

TEST(ReadStl, AsciiMixedCaseAndNanNormals) {
    ReadInfo info;
    const Mesh m = read_mesh(kFixtures + "/tet_ascii.stl", &info);
    EXPECT_EQ(info.format, "stl-ascii");
    EXPECT_EQ(info.file_faces, 4u);
    EXPECT_EQ(info.file_vertices, 12u);
    ASSERT_EQ(m.triangles.size(), 4u);
    ASSERT_EQ(m.positions.size(), 12u);  // no merging
    EXPECT_EQ(m.triangles[3], (Tri{9, 10, 11}));
    EXPECT_EQ(m.positions[9], (Vec3f{1, 0, 0}));
    EXPECT_EQ(m.positions[11], (Vec3f{0, 0, 1}));
}

TEST(ReadStl, BinaryWhoseHeaderStartsWithSolid) {
    // Many exporters write "solid ..." into the binary header; the exact size 84 + 50 n decides.
    std::string s(80, ' ');
    std::memcpy(s.data(), "solid exported by some CAD tool", 31);
    auto put = [&](auto v) { s.append(reinterpret_cast<const char*>(&v), sizeof v); };
    put(std::uint32_t(2));
    const float tri[2][12] = {{0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 0}};
    for (const auto& t : tri) {
        for (const float f : t) put(f);
        put(std::uint16_t(0));
    }
    ReadInfo info;
    const Mesh m = read_stl_memory(s, "solid.stl", &info);
    EXPECT_EQ(info.format, "stl-binary");
    ASSERT_EQ(m.triangles.size(), 2u);
    EXPECT_EQ(m.positions[3], (Vec3f{1, 0, 0}));
    EXPECT_EQ(m.positions[4], (Vec3f{1, 1, 0}));
}

// ------------------------------------------------------------------------------------- round trips

struct Variant {
    std::string ext;
    bool binary;
    std::string format;  // ReadInfo::format expected
};

class RoundTrip : public ::testing::TestWithParam<Variant> {};

TEST_P(RoundTrip, BitExactPositionsAndTriangles) {
    const Variant& v = GetParam();
    TempDir dir;
    const Mesh m = tricky_mesh();
    const std::string path = dir / ("tricky" + v.ext);
    WriteOptions opt;
    opt.binary = v.binary;
    write_mesh(path, m, opt);
    ReadInfo info;
    const Mesh r = read_mesh(path, &info);
    EXPECT_EQ(info.format, v.format);
    if (v.ext == ".stl") {
        expect_expanded(m, r);
    } else {
        expect_identical(m, r);
        EXPECT_EQ(info.file_vertices, m.positions.size());
    }
    EXPECT_EQ(info.file_faces, m.triangles.size());
    EXPECT_TRUE(info.warnings.empty());
    // nothing but the file itself is left in the folder (no temporary files)
    EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator{}), 1);
}

INSTANTIATE_TEST_SUITE_P(AllFormats, RoundTrip,
                         ::testing::Values(Variant{".obj", true, "obj"}, Variant{".ply", true, "ply-binary-le"},
                                           Variant{".ply", false, "ply-ascii"}, Variant{".off", true, "off"},
                                           Variant{".stl", true, "stl-binary"}, Variant{".stl", false, "stl-ascii"}),
                         [](const auto& p) { return p.param.ext.substr(1) + (p.param.binary ? "_binary" : "_ascii"); });

TEST(WriteStl, BinaryHeaderNeverStartsWithSolidAndNormalsAreUnit) {
    TempDir dir;
    Mesh m;
    m.positions = kCubeV;
    m.triangles = kCubeT;
    write_stl(dir / "cube.stl", m);
    const std::string bytes = slurp(dir / "cube.stl");
    ASSERT_EQ(bytes.size(), 84u + 50u * 12u);
    EXPECT_NE(bytes.substr(0, 5), "solid");
    float n[3];
    std::memcpy(n, bytes.data() + 84, sizeof n);  // first facet: (0,3,2) on z = 0, outward -z
    EXPECT_FLOAT_EQ(n[0], 0.f);
    EXPECT_FLOAT_EQ(n[1], 0.f);
    EXPECT_FLOAT_EQ(n[2], -1.f);
}

// ------------------------------------------------------------------------------------- real models

namespace {
bool have_data() { return fs::exists(kData + "/pairs_gnf/fandisk_gt.ply"); }
}  // namespace

TEST(RealModels, FandiskPly) {
    if (!have_data()) GTEST_SKIP() << "no shared/data at " << kData;
    ReadInfo info;
    const Mesh m = read_mesh(kData + "/pairs_gnf/fandisk_gt.ply", &info);
    EXPECT_EQ(m.positions.size(), 6475u);
    EXPECT_EQ(m.triangles.size(), 12946u);
    EXPECT_EQ(info.format, "ply-binary-le");
    EXPECT_EQ(info.file_faces, 12946u);
    // every format round trip of a real model is exact
    TempDir dir;
    for (const std::string ext : {".obj", ".ply", ".off"})
        for (const bool binary : {true, false}) {
            WriteOptions opt;
            opt.binary = binary;
            write_mesh(dir / ("f" + ext), m, opt);
            SCOPED_TRACE(ext);
            expect_identical(m, read_mesh(dir / ("f" + ext)));
        }
    write_mesh(dir / "f.stl", m);
    expect_expanded(m, read_mesh(dir / "f.stl"));
}

TEST(RealModels, ThingiAsciiStl) {
    if (!have_data()) GTEST_SKIP() << "no shared/data at " << kData;
    ReadInfo info;
    const Mesh m = read_mesh(kData + "/dirty/thingi10k/138201.stl", &info);
    EXPECT_EQ(info.format, "stl-ascii");
    EXPECT_EQ(m.triangles.size(), 672u);
    EXPECT_EQ(m.positions.size(), 3u * 672u);
    EXPECT_EQ(info.file_faces, 672u);
}

TEST(RealModels, AllThingiStlFilesRead) {
    if (!have_data()) GTEST_SKIP() << "no shared/data at " << kData;
    int n = 0;
    for (const auto& e : fs::directory_iterator(kData + "/dirty/thingi10k")) {
        if (e.path().extension() != ".stl") continue;
        SCOPED_TRACE(e.path().string());
        const Mesh m = read_mesh(e.path().string());
        EXPECT_GT(m.triangles.size(), 0u);
        ++n;
    }
    EXPECT_GE(n, 1);
}

TEST(RealModels, SimplifyBrainObj) {
    if (!have_data()) GTEST_SKIP() << "no shared/data at " << kData;
    ReadInfo info;
    const Mesh m = read_mesh(kData + "/dirty/simplify_brain.obj", &info);
    EXPECT_EQ(info.format, "obj");
    EXPECT_EQ(info.file_faces, 9064u);
    EXPECT_EQ(m.triangles.size(), 9064u + info.polygons_split);  // all triangles in this file
    EXPECT_EQ(info.polygons_split, 0u);
    EXPECT_EQ(m.positions.size(), info.file_vertices);
}

TEST(RealModels, LargestPlyReadsFast) {
    // iron.ply: 85574 vertices, 168285 faces. The time is printed, not asserted (a loaded CI machine
    // must not fail the test); benchmarks/ has the timing.
    const std::string path = kData + "/real_scans/iron.ply";
    if (!fs::exists(path)) GTEST_SKIP() << "no " << path;
    const auto t0 = std::chrono::steady_clock::now();
    const Mesh m = read_mesh(path);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(m.positions.size(), 85574u);
    EXPECT_EQ(m.triangles.size(), 168285u);
    std::printf("read_ply iron.ply (168285 faces): %.4f s\n", s);
}
