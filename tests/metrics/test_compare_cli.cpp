// The comparison commands end to end: noise, taubin, compare --report (writes the three files).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "support/test_files.h"
#include "io/io.h"
#include "metric_test_meshes.h"

namespace normalflow {
using normalflow::test::slurp;

namespace {

namespace fs = std::filesystem;

int run(const std::string& args, const fs::path& out) {
    const std::string cmd = std::string(NORMALFLOW_EXE) + " " + args + " > " + out.string() + " 2>&1";
    return std::system(cmd.c_str());
}

class CompareCli : public ::testing::Test {
protected:
    fs::path dir;
    void SetUp() override {
        dir = fs::temp_directory_path() / ("nf_compare_cli_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                           "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir);
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }
};

TEST_F(CompareCli, NoiseTaubinCompareWritesTheReport) {
    write_mesh((dir / "ref.ply").string(), test::icosphere(1.0, 3));
    ASSERT_EQ(run("noise " + (dir / "ref.ply").string() + " " + (dir / "n1.ply").string() + " --sigma 0.3 --seed 5 -q",
                  dir / "log1"), 0) << slurp(dir / "log1");
    ASSERT_EQ(run("noise " + (dir / "ref.ply").string() + " " + (dir / "n2.ply").string() + " --sigma 0.3 --seed 5 -q",
                  dir / "log2"), 0);
    EXPECT_EQ(slurp(dir / "n1.ply"), slurp(dir / "n2.ply"));  // deterministic for a seed
    ASSERT_EQ(run("taubin " + (dir / "n1.ply").string() + " " + (dir / "t.ply").string() + " --iterations 5 -q",
                  dir / "log3"), 0) << slurp(dir / "log3");
    ASSERT_EQ(run("compare " + (dir / "ref.ply").string() + " " + (dir / "n1.ply").string() + " " +
                      (dir / "t.ply").string() + " --samples 5000 --report " + (dir / "rep").string() + " --json",
                  dir / "log4"), 0) << slurp(dir / "log4");
    for (const char* f : {"compare.md", "compare.csv", "compare.json"}) {
        ASSERT_TRUE(fs::exists(dir / "rep" / f)) << f;
        EXPECT_GT(fs::file_size(dir / "rep" / f), 100u) << f;
    }
    const std::string csv = slurp(dir / "rep" / "compare.csv");
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);  // header + two candidates
    EXPECT_NE(slurp(dir / "rep" / "compare.md").find("| candidate |"), std::string::npos);
    const std::string json = slurp(dir / "log4");
    EXPECT_NE(json.find("\"candidates\""), std::string::npos) << json;
    EXPECT_NE(json.find("crease_preservation"), std::string::npos);
}

TEST_F(CompareCli, ErrorsAreOneLineAndNonZero) {
    EXPECT_NE(run("compare " + (dir / "missing.ply").string() + " " + (dir / "missing2.ply").string(), dir / "log"), 0);
    EXPECT_NE(slurp(dir / "log").find("missing.ply"), std::string::npos);
    write_mesh((dir / "ref.ply").string(), test::icosphere(1.0, 1));
    EXPECT_NE(run("taubin " + (dir / "ref.ply").string() + " " + (dir / "t.ply").string() + " --mu 0.2", dir / "log2"), 0);
    EXPECT_FALSE(fs::exists(dir / "t.ply"));
}

}  // namespace
}  // namespace normalflow
