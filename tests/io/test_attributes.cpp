// Per-vertex normals, colours and texture coordinates through PLY and OBJ: exact round trips, the
// names and encodings other tools write, and meshes whose attribute arrays do not fit.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "core/errors.h"
#include "io/formats/mesh_formats.h"
#include "io/io.h"
#include "support/attributed_mesh.h"
#include "support/test_files.h"

using namespace normalflow;
using normalflow::test::attributed_sphere;
using normalflow::test::TempDir;

namespace {

/// m as OBJ gives it back: the `v x y z r g b` extension has no alpha, so colours come back opaque.
Mesh without_alpha(Mesh m) {
    for (Rgba8& c : m.colors) c[3] = 255;
    return m;
}

void expect_same_attributes(const Mesh& a, const Mesh& b) {
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.normals, b.normals);
    EXPECT_EQ(a.colors, b.colors);
    EXPECT_EQ(a.texcoords, b.texcoords);
}

}  // namespace

TEST(Attributes, PlyBinaryAndAsciiRoundTripExactly) {
    TempDir dir;
    const Mesh m = attributed_sphere();
    for (const bool binary : {true, false}) {
        SCOPED_TRACE(binary ? "binary" : "ascii");
        WriteOptions o;
        o.binary = binary;
        write_mesh(dir / "s.ply", m, o);
        expect_same_attributes(read_mesh(dir / "s.ply"), m);
    }
}

TEST(Attributes, ObjRoundTripsExactly) {
    TempDir dir;
    const Mesh m = attributed_sphere();
    write_mesh(dir / "s.obj", m);
    ReadInfo info;
    const Mesh back = read_mesh(dir / "s.obj", &info);
    expect_same_attributes(back, without_alpha(m));
    EXPECT_TRUE(info.warnings.empty()) << info.warnings.front();  // one (vt, vn) per vertex: nothing split
}

TEST(Attributes, EachAttributeAloneRoundTrips) {
    TempDir dir;
    const Mesh full = attributed_sphere(1);
    for (int which = 0; which < 3; ++which) {
        Mesh m = full;
        if (which != 0) m.normals.clear();
        if (which != 1) m.colors.clear();
        if (which != 2) m.texcoords.clear();
        for (const std::string ext : {".ply", ".obj"}) {
            SCOPED_TRACE(ext + " attribute " + std::to_string(which));
            const std::string path = dir / ("m" + ext);
            write_mesh(path, m);
            expect_same_attributes(read_mesh(path), ext == ".obj" ? without_alpha(m) : m);
        }
    }
}

TEST(Attributes, PlyReadsOtherToolsNamesAndTypes) {
    // float colours in 0..1 (as some scanners write), diffuse_* names, s/t texture coordinates, and an
    // unrelated property in between; uint16 colours in 0..65535.
    const std::string a =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "property float quality\nproperty float diffuse_red\nproperty float diffuse_green\n"
        "property float diffuse_blue\nproperty float s\nproperty float t\nproperty float nx\nproperty float ny\n"
        "property float nz\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 7 1 0 0.5 0.25 0.75 0 0 1\n1 0 0 7 0 1 0 1 0 0 0 1\n0 1 0 7 0 0 1 0 1 0 0 1\n3 0 1 2\n";
    const Mesh m = read_ply_memory(a, "a.ply");
    ASSERT_EQ(m.colors.size(), 3u);
    EXPECT_EQ(m.colors[0], (Rgba8{255, 0, 128, 255}));
    EXPECT_EQ(m.colors[2], (Rgba8{0, 0, 255, 255}));
    EXPECT_EQ(m.texcoords[0], (TexCoord{0.25f, 0.75f}));
    EXPECT_EQ(m.normals[1], (Vec3f{0, 0, 1}));

    const std::string b =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "property ushort red\nproperty ushort green\nproperty ushort blue\nproperty float u\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 65535 0 257 0.5\n1 0 0 0 0 0 0\n0 1 0 0 0 0 0\n3 0 1 2\n";
    const Mesh mb = read_ply_memory(b, "b.ply");
    ASSERT_EQ(mb.colors.size(), 3u);
    EXPECT_EQ(mb.colors[0], (Rgba8{255, 0, 1, 255}));
    EXPECT_FALSE(mb.has_texcoords());  // u without v is not a texture coordinate
    EXPECT_FALSE(mb.has_normals());
}

TEST(Attributes, ObjColoursInEitherRangeAndShortTexcoords) {
    const std::string s =
        "v 0 0 0 1 0 0.5\nv 1 0 0 0 255 0\nv 0 1 0\nvt 0.25\nvt 0.5 0.75\nvt 1 1\n"
        "vn 0 0 2\nf 1/1/1 2/2/1 3/3/1\n";
    const Mesh m = read_obj_memory(s, "c.obj");
    ASSERT_EQ(m.colors.size(), 3u);
    EXPECT_EQ(m.colors[0], (Rgba8{255, 0, 128, 255}));
    EXPECT_EQ(m.colors[1], (Rgba8{0, 255, 0, 255}));      // a value above 1: the line is in 0..255
    EXPECT_EQ(m.colors[2], (Rgba8{255, 255, 255, 255}));  // no colour on its line: white
    EXPECT_EQ(m.texcoords[0], (TexCoord{0.25f, 0.0f}));
    EXPECT_EQ(m.texcoords[1], (TexCoord{0.5f, 0.75f}));
    EXPECT_EQ(m.normals[2], (Vec3f{0, 0, 2}));  // as written: normals are not renormalised on reading
}

TEST(Attributes, ObjSharedCornersAreNotSplitConflictingOnesAre) {
    // Two triangles sharing edge 2-3: the same (vt, vn) on both sides keeps 4 vertices; a seam in vt
    // on vertex 3 gives it one copy, used by the second triangle only.
    const std::string same =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvt 9 9\n"
        "f 1/1 2/2 3/3\nf 2/2 4/4 3/3\n";
    ReadInfo info;
    const Mesh a = read_obj_memory(same, "same.obj", &info);
    EXPECT_EQ(a.positions.size(), 4u);
    EXPECT_TRUE(info.warnings.empty());
    const std::string seam =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvt 9 9\n"
        "f 1/1 2/2 3/3\nf 2/2 4/4 3/5\n";
    const Mesh b = read_obj_memory(seam, "seam.obj", &info);
    ASSERT_EQ(b.positions.size(), 5u);
    EXPECT_EQ(b.positions[4], b.positions[2]);
    EXPECT_EQ(b.triangles[0], (Tri{0, 1, 2}));
    EXPECT_EQ(b.triangles[1], (Tri{1, 3, 4}));
    EXPECT_EQ(b.texcoords[2], (TexCoord{0, 1}));
    EXPECT_EQ(b.texcoords[4], (TexCoord{9, 9}));
    ASSERT_EQ(info.warnings.size(), 1u);
    EXPECT_EQ(info.warnings[0],
              "1 vertices duplicated where their corners have different texture coordinates or normals");
}

TEST(Attributes, ObjBrokenAttributeReferencesDropTheAttributeNotTheFile) {
    ReadInfo info;
    const Mesh m = read_obj_memory("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/-3 3/1\n", "neg.obj", &info);
    EXPECT_EQ(m.positions.size(), 3u);
    EXPECT_FALSE(m.has_texcoords());
    ASSERT_EQ(info.warnings.size(), 1u);
    EXPECT_EQ(
        info.warnings[0],
        "texture coordinate index -3 at line 5 reaches before the first one; the texture coordinates are ignored");
}

TEST(Attributes, MisSizedAttributesAreRefusedAndNothingIsWritten) {
    TempDir dir;
    Mesh m = attributed_sphere(1);
    m.colors.pop_back();
    EXPECT_THROW(check_mesh(m, "t"), InvalidInput);
    for (const char* ext : {".ply", ".obj", ".glb"}) {
        const std::string path = dir / ("bad" + std::string(ext));
        try {
            write_mesh(path, m);
            ADD_FAILURE() << ext << " accepted " << m.colors.size() << " colours for " << m.positions.size()
                          << " vertices";
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find(std::to_string(m.colors.size()) + " colours for " +
                                                 std::to_string(m.positions.size()) + " vertices"),
                      std::string::npos)
                << e.what();
        }
        EXPECT_FALSE(std::filesystem::exists(path)) << ext;
    }
    Mesh nan = attributed_sphere(1);
    nan.texcoords[3][1] = std::nanf("");
    EXPECT_THROW(write_mesh(dir / "nan.ply", nan), InvalidInput);
}
