// Tests for io/formats/isolate.h (crash isolation of third-party decoders) and io/formats/gltf_check.h
// (glTF structure checked before Draco sees it). Issue 7.
#include "io/formats/isolate.h"

#include <gtest/gtest.h>
#include <dirent.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

#include "core/errors.h"
#include "io/formats/gltf_check.h"
#include "io/io.h"
#include "support/test_files.h"

namespace normalflow {
namespace {

int open_fds() {
    int n = 0;
    if (DIR* d = ::opendir("/proc/self/fd")) {
        while (::readdir(d)) ++n;
        ::closedir(d);
    }
    return n;
}

bool no_children_left() {
    int status = 0;
    return ::waitpid(-1, &status, WNOHANG) == -1 && errno == ECHILD;
}

TEST(Isolate, ReturnsTheChildsBytes) {
    const std::string want("hello\0world\xff", 12);
    EXPECT_EQ(run_isolated("t", [&] { return want; }), want);
    EXPECT_EQ(run_isolated("t", [] { return std::string(); }), "");
}

TEST(Isolate, ChildMemoryStaysInTheChild) {
    int x = 1;
    run_isolated("t", [&] {
        x = 2;
        return std::string();
    });
    EXPECT_EQ(x, 1);
}

TEST(Isolate, RethrowsTheSameExceptionTypeAndMessage) {
    const std::string msg = "read_ply: scan.ply, line 12: face has 5 indices, expected 3";
    try {
        run_isolated("t", [&]() -> std::string { throw InvalidInput(msg); });
        FAIL() << "no exception";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()), msg);
    }
    EXPECT_THROW(run_isolated("t", []() -> std::string { throw IoError("io"); }), IoError);
    EXPECT_THROW(run_isolated("t", []() -> std::string { throw NumericalError("num"); }), NumericalError);
    EXPECT_THROW(run_isolated("t", []() -> std::string { throw Cancelled("stop"); }), Cancelled);
    EXPECT_THROW(run_isolated("t", []() -> std::string { throw OutOfMemory("oom"); }), OutOfMemory);
    EXPECT_THROW(run_isolated("t", []() -> std::string { throw std::bad_alloc(); }), OutOfMemory);
    try {
        run_isolated("who: f.drc", []() -> std::string { throw std::logic_error("odd"); });
        FAIL() << "no exception";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("who: f.drc"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("odd"), std::string::npos) << e.what();
    }
}

TEST(Isolate, CrashBecomesIoErrorNamingTheSignal) {
    try {
        run_isolated("read_drc: bad.drc", []() -> std::string {
            std::raise(SIGSEGV);
            return "not reached";
        });
        FAIL() << "no exception";
    } catch (const IoError& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind("read_drc: bad.drc: ", 0), 0u) << m;
        EXPECT_NE(m.find("signal 11, SIGSEGV"), std::string::npos) << m;
        EXPECT_NE(m.find("crashed"), std::string::npos) << m;
    }
    try {
        run_isolated("t", []() -> std::string { std::abort(); });
        FAIL() << "no exception";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("SIGABRT"), std::string::npos) << e.what();
    }
    // The parent is still here and isolation still works.
    EXPECT_EQ(run_isolated("t", [] { return std::string("ok"); }), "ok");
}

TEST(Isolate, ExitWithoutResultIsIoError) {
    try {
        run_isolated("t", []() -> std::string { ::_exit(7); });
        FAIL() << "no exception";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("status 7"), std::string::npos) << e.what();
    }
}

TEST(Isolate, TimeoutKillsTheChild) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
        run_isolated("t", []() -> std::string {
            ::sleep(30);
            return "late";
        }, 0.3);
        FAIL() << "no exception";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("did not finish"), std::string::npos) << e.what();
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_LT(s, 5.0);
    EXPECT_TRUE(no_children_left());
    // A generous timeout does not get in the way.
    EXPECT_EQ(run_isolated("t", [] { return std::string("quick"); }, 30.0), "quick");
    EXPECT_THROW(run_isolated("t", [] { return std::string(); }, -1.0), InvalidInput);
}

TEST(Isolate, LargePayloadRoundTrip) {
    const std::size_t n = 50u << 20;
    const std::string got = run_isolated("t", [&] {
        std::string s(n, '\0');
        for (std::size_t i = 0; i < n; ++i) s[i] = char((i * 2654435761u) >> 13);
        return s;
    });
    ASSERT_EQ(got.size(), n);
    for (std::size_t i = 0; i < n; i += 4099) ASSERT_EQ(got[i], char((i * 2654435761u) >> 13)) << i;
    EXPECT_EQ(got[n - 1], char(((n - 1) * 2654435761u) >> 13));
}

TEST(Isolate, NoFdLeakNoZombies) {
    run_isolated("t", [] { return std::string("warm-up"); });
    const int before = open_fds();
    for (int i = 0; i < 100; ++i) {
        if (i % 3 == 0) EXPECT_THROW(run_isolated("t", []() -> std::string { throw InvalidInput("x"); }), InvalidInput);
        else if (i % 3 == 1) EXPECT_THROW(run_isolated("t", []() -> std::string { ::_exit(1); }), IoError);
        else EXPECT_EQ(run_isolated("t", [] { return std::string(1000, 'a'); }), std::string(1000, 'a'));
    }
    EXPECT_EQ(open_fds(), before);
    EXPECT_TRUE(no_children_left());
}

TEST(Isolate, EnvironmentVariableRunsInProcess) {
    ::setenv("NORMALFLOW_NO_ISOLATION", "1", 1);
    int x = 1;
    const std::string r = run_isolated("t", [&] {
        x = 2;
        return std::string("in");
    });
    EXPECT_THROW(run_isolated("t", []() -> std::string { throw InvalidInput("same"); }), InvalidInput);
    ::unsetenv("NORMALFLOW_NO_ISOLATION");
    EXPECT_EQ(r, "in");
    EXPECT_EQ(x, 2);
    EXPECT_FALSE(isolation_disabled());
}

TEST(Isolate, MeshLayoutRoundTripAndTruncation) {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    ByteWriter w;
    put_mesh(w, m);
    w.put(std::int32_t(42));
    const std::string bytes = w.take();
    ByteReader r(bytes, "t");
    const Mesh back = get_mesh(r);
    EXPECT_EQ(back.positions.size(), 3u);
    EXPECT_EQ(back.positions[1].x, 1.0f);
    EXPECT_EQ(back.triangles[0][2], 2u);
    EXPECT_EQ(r.get<std::int32_t>(), 42);
    EXPECT_TRUE(r.at_end());
    for (std::size_t cut : {std::size_t(0), std::size_t(7), bytes.size() / 2, bytes.size() - 5}) {
        ByteReader short_r(std::string_view(bytes).substr(0, cut), "who");
        EXPECT_THROW({ get_mesh(short_r); short_r.get<std::int32_t>(); }, IoError) << cut;
    }
}

// ---- glTF structure checks ----

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
               R"("accessors":[{"bufferView":0,"componentType":)" + component_type + R"(,"count":)" + position_count +
               R"(,"type":"VEC3"},{"bufferView":1,"componentType":5125,"count":)" + index_count +
               R"(,"type":"SCALAR"}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},)"
               R"({"buffer":0,"byteOffset":)" + index_offset + R"(,"byteLength":12}],"buffers":[{"byteLength":48}]})";
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
    EXPECT_NE(gltf_error(g).find("bufferView 1: bytes [40, 52) lie outside buffer 0"), std::string::npos) << gltf_error(g);
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

#ifdef NORMALFLOW_HAS_OPENVDB
// read_vdb reads in a forked child and rebuilds the grid here: values must survive exactly, also after
// TBB's workers exist in the parent (the child must not need them).
TEST(VdbRead, IsolatedReadRoundTripsExactlyAfterTbbStarted) {
    test::TempDir dir;
    Grid g;
    g.origin = {1, 2, 3};
    g.voxel_size = 0.5;
    g.dims = {16, 16, 12};
    Volume v(g, 3.0f);
    for (int bk = 0; bk < v.block_dims[2]; ++bk)
        for (int bj = 0; bj < v.block_dims[1]; ++bj)
            for (int bi = 0; bi < v.block_dims[0]; ++bi) {
                const std::int32_t b = v.allocate_block(bi, bj, bk);
                float* d = v.block_values(b);
                for (int lk = 0; lk < 8; ++lk)
                    for (int lj = 0; lj < 8; ++lj)
                        for (int li = 0; li < 8; ++li) {
                            const double x = (bi * 8 + li) - 7.5, y = (bj * 8 + lj) - 7.5, z = (bk * 8 + lk) - 6.0;
                            const float phi = float(0.5 * (std::sqrt(x * x + y * y + z * z) - 5.0));
                            d[Volume::local_index(li, lj, lk)] = std::clamp(phi, -1.5f, 1.5f);
                        }
            }
    write_volume(dir / "s.vdb", v);
    for (int round = 0; round < 2; ++round) {  // round 1: TBB has run in this process (voxelizeActiveTiles)
        const Volume back = read_volume(dir / "s.vdb");
        ASSERT_EQ(back.grid.dims, g.dims);
        EXPECT_DOUBLE_EQ(back.grid.voxel_size, 0.5);
        EXPECT_NEAR(back.grid.origin.x, 1.0, 1e-12);
        EXPECT_NEAR(back.grid.origin.z, 3.0, 1e-12);
        for (int k = 0; k < g.dims[2]; ++k)
            for (int j = 0; j < g.dims[1]; ++j)
                for (int i = 0; i < g.dims[0]; ++i) ASSERT_EQ(back.value(i, j, k), v.value(i, j, k)) << i << " " << j << " " << k;
    }
}
#endif

#ifdef NORMALFLOW_HAS_DRACO
TEST(GltfRead, MalformedAccessorIsRefusedBeforeDraco) {
    test::TempDir dir;
    Gltf g;
    {
        std::ofstream(dir / "ok.glb", std::ios::binary) << g.glb();
    }
    EXPECT_EQ(read_mesh(dir / "ok.glb").triangles.size(), 1u);
    g.position_count = "1000";
    {
        std::ofstream(dir / "bad.glb", std::ios::binary) << g.glb();
    }
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
    } catch (const IoError&) {
    }
    SUCCEED();
}
#endif

}  // namespace
}  // namespace normalflow
