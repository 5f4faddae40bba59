// Tests for io/util/isolate.h (crash isolation of third-party decoders). Issue 7.
// The glTF structure checks (io/draco/gltf_check.h) are tested in tests/draco/test_gltf_check.cpp.
#include "io/util/isolate.h"

#include <dirent.h>
#include <gtest/gtest.h>
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
        run_isolated(
            "t",
            []() -> std::string {
                ::sleep(30);
                return "late";
            },
            0.3);
        FAIL() << "no exception";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("did not finish"), std::string::npos) << e.what();
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_LT(s, 5.0);
    EXPECT_TRUE(no_children_left());
    // A generous timeout does not get in the way.
    EXPECT_EQ(run_isolated(
                  "t", [] { return std::string("quick"); }, 30.0),
              "quick");
    EXPECT_THROW(run_isolated(
                     "t", [] { return std::string(); }, -1.0),
                 InvalidInput);
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
        if (i % 3 == 0)
            EXPECT_THROW(run_isolated("t", []() -> std::string { throw InvalidInput("x"); }), InvalidInput);
        else if (i % 3 == 1)
            EXPECT_THROW(run_isolated("t", []() -> std::string { ::_exit(1); }), IoError);
        else
            EXPECT_EQ(run_isolated("t", [] { return std::string(1000, 'a'); }), std::string(1000, 'a'));
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
        EXPECT_THROW(
            {
                get_mesh(short_r);
                short_r.get<std::int32_t>();
            },
            IoError)
            << cut;
    }
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
                for (int i = 0; i < g.dims[0]; ++i)
                    ASSERT_EQ(back.value(i, j, k), v.value(i, j, k)) << i << " " << j << " " << k;
    }
}
#endif

}  // namespace
}  // namespace normalflow
