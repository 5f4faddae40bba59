// Tests for io/util/report_json.h: the JSON of a compare report.
#include "io/util/report_json.h"

#include <gtest/gtest.h>

#include <string>

namespace normalflow {
namespace {

TEST(ReportJson, CompareReport) {
    CompareReport r;
    r.reference = "ref.ply";
    r.options.sampling.samples = 10;
    r.options.sampling.seed = 3;
    r.options.crease.angle_deg = 30;
    r.options.crease.radius_relative = 0.5;
    EXPECT_EQ(to_json(r).dump(),
              "{\"command\":\"compare\",\"reference\":\"ref.ply\",\"protocol\":{\"samples_per_mesh\":10,\"seed\":3,"
              "\"crease_angle_deg\":30,\"crease_radius_relative\":0.5},\"candidates\":[]}");
    CompareReportRow row;
    row.name = "a.ply";
    row.comparison.distance.hausdorff = 0.5;
    row.comparison.reference_diagonal = 2;
    row.comparison.warnings = {"w"};
    row.seconds = 0.25;
    r.rows.push_back(row);
    const std::string one = to_json(r).dump();
    EXPECT_NE(one.find("\"reference_stats\":{\"bbox_diagonal\":2,"), std::string::npos) << one;
    EXPECT_NE(one.find("\"candidates\":[{\"candidate\":\"a.ply\",\"hausdorff\":0.5,"), std::string::npos) << one;
    EXPECT_EQ(one.find("self_intersecting_pairs"), std::string::npos) << one;  // not measured
    EXPECT_NE(one.find("\"seconds\":0.25,\"warnings\":[\"w\"]}]}"), std::string::npos) << one;
    r.rows[0].self_intersections = 4;
    EXPECT_NE(to_json(r).dump().find("\"self_intersecting_pairs\":4,"), std::string::npos);
}

TEST(ReportJson, CorrespondenceOnlyWhenMeasured) {
    CompareReport r;
    r.reference = "ref.ply";
    CompareReportRow row;
    row.name = "a.ply";
    r.rows.push_back(row);
    const std::string without = to_json(r).dump();
    EXPECT_EQ(without.find("correspondence"), std::string::npos) << without;
    r.options.correspondence = true;
    CorrespondenceErrors e;
    e.faces = 12;
    e.degenerate_faces = 2;
    e.mean_face_angle_deg = 7.5;
    e.max_face_angle_deg = 45;
    e.vertices = 8;
    e.mean_vertex_distance = 0.125;
    e.mean_vertex_distance_relative = 0.0625;
    e.max_vertex_distance = 1;
    e.max_vertex_distance_relative = 0.5;
    r.rows[0].comparison.correspondence = e;
    const std::string with = to_json(r).dump();
    EXPECT_NE(with.find("\"crease_radius_relative\":0.01,\"correspondence\":true}"), std::string::npos) << with;
    EXPECT_NE(with.find("\"correspondence\":{\"faces\":12,\"degenerate_faces\":2,\"mean_face_angle_deg\":7.5,"
                        "\"max_face_angle_deg\":45,\"vertices\":8,\"mean_vertex_distance\":0.125,"
                        "\"mean_vertex_distance_relative\":0.0625,\"max_vertex_distance\":1,"
                        "\"max_vertex_distance_relative\":0.5},\"seconds\""),
              std::string::npos)
        << with;
}

}  // namespace
}  // namespace normalflow
