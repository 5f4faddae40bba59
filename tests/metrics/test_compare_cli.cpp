// The comparison commands end to end: noise, taubin, compare --report (writes the three files).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "io/io.h"
#include "metric_test_meshes.h"
#include "support/test_files.h"

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
        dir = fs::temp_directory_path() /
              ("nf_compare_cli_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
               ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir);
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }
};

TEST_F(CompareCli, NoiseTaubinCompareWritesTheReport) {
    write_mesh((dir / "ref.ply").string(), test::icosphere(1.0, 3));
    ASSERT_EQ(run("noise " + (dir / "ref.ply").string() + " " + (dir / "n1.ply").string() + " --sigma 0.3 --seed 5 -q",
                  dir / "log1"),
              0)
        << slurp(dir / "log1");
    ASSERT_EQ(run("noise " + (dir / "ref.ply").string() + " " + (dir / "n2.ply").string() + " --sigma 0.3 --seed 5 -q",
                  dir / "log2"),
              0);
    EXPECT_EQ(slurp(dir / "n1.ply"), slurp(dir / "n2.ply"));  // deterministic for a seed
    ASSERT_EQ(run("taubin " + (dir / "n1.ply").string() + " " + (dir / "t.ply").string() + " --iterations 5 -q",
                  dir / "log3"),
              0)
        << slurp(dir / "log3");
    ASSERT_EQ(run("compare " + (dir / "ref.ply").string() + " " + (dir / "n1.ply").string() + " " +
                      (dir / "t.ply").string() + " --samples 5000 --report " + (dir / "rep").string() + " --json",
                  dir / "log4"),
              0)
        << slurp(dir / "log4");
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

// The values of every "key": in a JSON text, in order.
std::vector<double> json_numbers(const std::string& json, const std::string& key) {
    std::vector<double> v;
    const std::string k = "\"" + key + "\":";
    for (auto at = json.find(k); at != std::string::npos; at = json.find(k, at + 1))
        v.push_back(std::stod(json.substr(at + k.size())));
    return v;
}

TEST_F(CompareCli, CorrespondenceOnATaubinResultOfTheNoisyMesh) {
    write_mesh((dir / "ref.ply").string(), test::icosphere(1.0, 3));
    ASSERT_EQ(run("noise " + (dir / "ref.ply").string() + " " + (dir / "n.ply").string() + " --sigma 0.3 --seed 5 -q",
                  dir / "log1"),
              0)
        << slurp(dir / "log1");
    ASSERT_EQ(run("taubin " + (dir / "n.ply").string() + " " + (dir / "t.ply").string() + " --iterations 10 -q",
                  dir / "log2"),
              0)
        << slurp(dir / "log2");
    ASSERT_EQ(run("compare " + (dir / "ref.ply").string() + " " + (dir / "ref.ply").string() + " " +
                      (dir / "n.ply").string() + " " + (dir / "t.ply").string() +
                      " --samples 2000 --no-self-intersections --correspondence --json",
                  dir / "log3"),
              0)
        << slurp(dir / "log3");
    const std::string json = slurp(dir / "log3");
    const std::vector<double> angle = json_numbers(json, "mean_face_angle_deg");
    const std::vector<double> dist = json_numbers(json, "mean_vertex_distance");
    ASSERT_EQ(angle.size(), 3u) << json;
    ASSERT_EQ(dist.size(), 3u) << json;
    EXPECT_EQ(angle[0], 0.0);  // the reference against itself
    EXPECT_EQ(dist[0], 0.0);
    EXPECT_GT(angle[1], 5.0);       // the noisy mesh
    EXPECT_LT(angle[2], angle[1]);  // Taubin smoothing turns the faces back
    EXPECT_GT(dist[1], 0.0);
    // The terminal table has the four columns.
    ASSERT_EQ(run("compare " + (dir / "ref.ply").string() + " " + (dir / "t.ply").string() +
                      " --samples 2000 --no-self-intersections --correspondence",
                  dir / "log4"),
              0);
    EXPECT_NE(slurp(dir / "log4").find("| face-by-face angle ° | vertex dist. |"), std::string::npos)
        << slurp(dir / "log4");
}

TEST_F(CompareCli, CorrespondenceMismatchIsOneLineNamingIt) {
    write_mesh((dir / "ref.ply").string(), test::icosphere(1.0, 2));
    write_mesh((dir / "finer.ply").string(), test::icosphere(1.0, 3));
    EXPECT_NE(run("compare " + (dir / "ref.ply").string() + " " + (dir / "finer.ply").string() + " --correspondence -q",
                  dir / "log"),
              0);
    const std::string log = slurp(dir / "log");
    EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << log;
    EXPECT_NE(log.find("--correspondence: candidate " + (dir / "finer.ply").string()), std::string::npos) << log;
    EXPECT_NE(log.find("candidate has 642 vertices, reference 162"), std::string::npos) << log;
    // Without the flag the same pair compares fine.
    EXPECT_EQ(run("compare " + (dir / "ref.ply").string() + " " + (dir / "finer.ply").string() +
                      " --samples 1000 --no-self-intersections -q",
                  dir / "log2"),
              0)
        << slurp(dir / "log2");
}

TEST_F(CompareCli, ErrorsAreOneLineAndNonZero) {
    EXPECT_NE(run("compare " + (dir / "missing.ply").string() + " " + (dir / "missing2.ply").string(), dir / "log"), 0);
    EXPECT_NE(slurp(dir / "log").find("missing.ply"), std::string::npos);
    write_mesh((dir / "ref.ply").string(), test::icosphere(1.0, 1));
    EXPECT_NE(run("taubin " + (dir / "ref.ply").string() + " " + (dir / "t.ply").string() + " --mu 0.2", dir / "log2"),
              0);
    EXPECT_FALSE(fs::exists(dir / "t.ply"));
}

}  // namespace
}  // namespace normalflow
