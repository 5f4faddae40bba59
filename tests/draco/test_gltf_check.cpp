// Tests for io/draco/gltf_check.h (glTF structure checked before Draco sees it) and the glTF reader's use
// of it. Issue 7.
// GCC 12 at -O3 reports a bogus -Wrestrict inside std::string::operator=(const char*) here
// (GCC bug 105329); the same code compiled silently while it lived in tests/io/test_isolate.cpp.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wrestrict"
#endif
#include "io/draco/gltf_check.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>

#include "core/errors.h"
#include "io/io.h"
#include "support/test_files.h"

namespace normalflow {
namespace {

/// A one-triangle glTF: 3 float VEC3 positions (36 bytes) then 3 uint32 indices (12 bytes).
struct Gltf {
    std::string position_count = "3";
    std::string index_count = "3";
    std::string index_offset = "36";
    std::string extra_nodes = "";
    std::uint32_t third_index = 2;
    std::string component_type = "5126";

    std::string json() const {
        return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0})" + extra_nodes +
               R"(],"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],)"
               R"("accessors":[{"bufferView":0,"componentType":)" +
               component_type + R"(,"count":)" + position_count +
               R"(,"type":"VEC3"},{"bufferView":1,"componentType":5125,"count":)" + index_count +
               R"(,"type":"SCALAR"}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},)"
               R"({"buffer":0,"byteOffset":)" +
               index_offset + R"(,"byteLength":12}],"buffers":[{"byteLength":48}]})";
    }
    std::string bin() const {
        std::string b(48, '\0');
        const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        std::memcpy(b.data(), p, 36);
        const std::uint32_t idx[3] = {0, 1, third_index};
        std::memcpy(b.data() + 36, idx, 12);
        return b;
    }
    std::string glb() const {
        std::string j = json();
        while (j.size() % 4) j.push_back(' ');
        const std::string b = bin();
        std::string out;
        auto u32 = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
        u32(0x46546C67);
        u32(2);
        u32(std::uint32_t(12 + 8 + j.size() + 8 + b.size()));
        u32(std::uint32_t(j.size()));
        u32(0x4E4F534A);
        out += j;
        u32(std::uint32_t(b.size()));
        u32(0x004E4942);
        out += b;
        return out;
    }
};

std::string gltf_error(const Gltf& g) {
    const std::string b = g.bin();
    try {
        check_gltf(g.json(), std::string_view(b), "", "read_gltf: t.glb");
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "";
}

TEST(GltfCheck, ValidAssetPasses) { EXPECT_EQ(gltf_error(Gltf{}), ""); }

TEST(GltfCheck, AccessorCountBeyondItsBufferView) {
    Gltf g;
    g.position_count = "4";  // 4 * 12 = 48 bytes > 36
    const std::string e = gltf_error(g);
    EXPECT_NE(e.find("read_gltf: t.glb: accessor 0: count 4"), std::string::npos) << e;
    EXPECT_NE(e.find("needs 48 bytes"), std::string::npos) << e;
    EXPECT_NE(e.find("bufferView 0 has 36"), std::string::npos) << e;
}

TEST(GltfCheck, OtherStructuralErrors) {
    Gltf g;
    g.third_index = 3;  // the fuzz finding: an index past the last point
    EXPECT_NE(gltf_error(g).find("index 2 is 3, but POSITION has 3 elements"), std::string::npos) << gltf_error(g);
    g = Gltf{};
    g.index_offset = "40";  // bufferView 1 ends at 52 > 48
    EXPECT_NE(gltf_error(g).find("bufferView 1: bytes [40, 52) lie outside buffer 0"), std::string::npos)
        << gltf_error(g);
    g = Gltf{};
    g.component_type = "5127";
    EXPECT_NE(gltf_error(g).find("componentType 5127 is not valid"), std::string::npos) << gltf_error(g);
    g = Gltf{};
    g.extra_nodes = R"(,{"children":[2]},{"children":[1]})";
    EXPECT_NE(gltf_error(g).find("cycle"), std::string::npos) << gltf_error(g);
    // Bad JSON and a BIN chunk shorter than the buffer.
    EXPECT_THROW(check_gltf("{\"a\":[1,2", std::nullopt, "", "w"), InvalidInput);
    EXPECT_THROW(check_gltf(std::string(200, '['), std::nullopt, "", "w"), InvalidInput);
    EXPECT_THROW(check_gltf(Gltf{}.json(), std::string_view("short"), "", "w"), InvalidInput);
    EXPECT_THROW(check_gltf(Gltf{}.json(), std::nullopt, "", "w"), InvalidInput);  // buffer 0 has no data
}

TEST(GltfRead, MalformedAccessorIsRefusedBeforeDraco) {
    test::TempDir dir;
    Gltf g;
    { std::ofstream(dir / "ok.glb", std::ios::binary) << g.glb(); }
    EXPECT_EQ(read_mesh(dir / "ok.glb").triangles.size(), 1u);
    g.position_count = "1000";
    { std::ofstream(dir / "bad.glb", std::ios::binary) << g.glb(); }
    try {
        read_mesh(dir / "bad.glb");
        FAIL() << "no exception";
    } catch (const InvalidInput& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("bad.glb"), std::string::npos) << m;
        EXPECT_NE(m.find("accessor 0: count 1000"), std::string::npos) << m;
    }
}

TEST(GltfRead, FuzzFindingsGiveCleanErrors) {
    const std::string root = NORMALFLOW_SOURCE_DIR "/fuzz/regressions/";
    EXPECT_THROW(read_mesh(root + "glb/glb-e1f699a682e059976110d1d6e9d5c913db6e74d5.glb"), InvalidInput);
    try {
        read_mesh(root + "drc/drc-80305ea16b7105675d33939fe7ec2e96f52b1831.drc");
    } catch (const InvalidInput&) {
    } catch (const IoError&) {}
    SUCCEED();
}

}  // namespace
}  // namespace normalflow
