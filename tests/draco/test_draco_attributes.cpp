// Per-vertex normals, colours and texture coordinates through glTF (plain and Draco-compressed GLB,
// with and without the uncompressed fallback) and .drc: what comes back, within what each format's
// quantisation allows, and that --normal-bits acts on the normals.
#include <gtest/gtest.h>

#include <string>

#include "io/draco/draco_io.h"
#include "io/formats/gltf.h"
#include "io/io.h"
#include "support/attributed_mesh.h"
#include "support/test_files.h"

using namespace normalflow;
using normalflow::test::attribute_errors;
using normalflow::test::attributed_sphere;
using normalflow::test::TempDir;

TEST(DracoAttributes, PlainGlbKeepsEveryAttribute) {
    TempDir dir;
    const Mesh m = attributed_sphere();
    write_glb(dir / "p.glb", m);
    const Mesh back = read_gltf(dir / "p.glb");
    ASSERT_EQ(back.positions.size(), m.positions.size());
    ASSERT_EQ(back.triangles.size(), m.triangles.size());
    const auto e = attribute_errors(m, back, 0.0);
    EXPECT_LE(e.normal_deg, 1e-3);
    EXPECT_EQ(e.color, 0.0);      // sRGB bytes -> linear float -> the same bytes
    EXPECT_LE(e.texcoord, 1e-6);  // v flipped on writing and on reading
}

TEST(DracoAttributes, DrcKeepsAttributesWithinQuantisation) {
    TempDir dir;
    const Mesh m = attributed_sphere();
    DracoOptions o;
    write_drc(dir / "s.drc", m, o);
    const Mesh back = read_drc(dir / "s.drc");
    ASSERT_EQ(back.triangles.size(), m.triangles.size());
    const auto e = attribute_errors(m, back, 2.0 / ((1 << o.position_bits) - 1));
    EXPECT_LE(e.normal_deg, 0.5);  // 10 bits
    EXPECT_EQ(e.color, 0.0);       // .drc keeps the 8-bit sRGB values
    EXPECT_LE(e.texcoord, 1.0 / ((1 << o.texcoord_bits) - 1));
}

TEST(DracoAttributes, DracoGlbKeepsAttributesWithAndWithoutFallback) {
    TempDir dir;
    const Mesh m = attributed_sphere();
    for (const bool fallback : {false, true}) {
        SCOPED_TRACE(fallback ? "with fallback" : "Draco only");
        DracoOptions o;
        o.fallback = fallback;
        write_draco_glb(dir / "d.glb", m, o);
        const Mesh back = read_gltf(dir / "d.glb");
        ASSERT_EQ(back.triangles.size(), m.triangles.size());
        const auto e = attribute_errors(m, back, 2.0 / ((1 << o.position_bits) - 1));
        EXPECT_LE(e.normal_deg, 0.5);
        EXPECT_EQ(e.color, 0.0);  // 16-bit linear: every sRGB byte, dark ones included, comes back
        EXPECT_LE(e.texcoord, 1.0 / ((1 << o.texcoord_bits) - 1));
    }
}

TEST(DracoAttributes, NormalBitsTradeSizeForNormalAccuracy) {
    TempDir dir;
    const Mesh m = attributed_sphere(3);
    double err[2];
    std::size_t size[2];
    for (int k = 0; k < 2; ++k) {
        DracoOptions o;
        o.normal_bits = k == 0 ? 5 : 12;
        write_draco_glb(dir / "n.glb", m, o);
        size[k] = normalflow::test::slurp(dir / "n.glb").size();
        err[k] = attribute_errors(m, read_gltf(dir / "n.glb"), 1e-3).normal_deg;
    }
    EXPECT_GT(err[0], 4 * err[1]) << "5 bits: " << err[0] << " deg, 12 bits: " << err[1] << " deg";
    EXPECT_LT(size[0], size[1]);
}

TEST(DracoAttributes, MeshWithoutAttributesStaysWithout) {
    TempDir dir;
    Mesh m = attributed_sphere(1);
    m.clear_attributes();
    write_draco_glb(dir / "a.glb", m);
    write_drc(dir / "a.drc", m);
    write_glb(dir / "b.glb", m);
    for (const char* f : {"a.glb", "b.glb", "a.drc"}) {
        const Mesh back = read_mesh(dir / f);
        EXPECT_FALSE(back.has_attributes()) << f;
        EXPECT_EQ(back.positions.size(), m.positions.size()) << f;
    }
}
