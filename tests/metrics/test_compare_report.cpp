// Tests for lib/metrics/compare_report.h: a known small report rendered as a Markdown table and page,
// CSV and HTML, compared line by line with hand-written expectations.
#include "metrics/compare_report.h"

#include <gtest/gtest.h>

#include <string>

namespace normalflow {
namespace {

CompareReport small_report() {
    CompareReport r;
    r.reference = "ref.ply";
    r.options.sampling.samples = 1000;
    r.options.sampling.seed = 7;
    r.options.crease.angle_deg = 30;
    r.options.crease.radius_relative = 0.01;
    CompareReportRow a;
    a.name = "a.ply";
    MeshComparison& c = a.comparison;
    c.distance.hausdorff = 0.5;
    c.distance.mean = 0.1;
    c.distance.rms = 0.2;
    c.distance.mean_normal_angle_deg = 3.25;
    c.reference_diagonal = 10;
    c.hausdorff_relative = 0.05;
    c.mean_relative = 0.01;
    c.rms_relative = 0.02;
    c.area_reference = 6;
    c.volume_reference = 1;
    c.area_change = 0.01;
    c.volume_change = -0.02;
    c.components_reference = 1;
    c.components_candidate = 1;
    c.closed_candidate = c.manifold_candidate = true;
    c.crease.feature_edges = 12;
    c.crease.feature_length = 12;
    c.crease.fraction = 0.875;
    c.crease.mean_angle_deg = 40;
    c.warnings = {"candidate is open"};
    a.seconds = 1.5;
    CompareReportRow b = a;
    b.name = "b \"<x>\".obj";
    b.self_intersections = 7;
    b.comparison.closed_candidate = false;
    b.comparison.warnings.clear();
    r.rows = {a, b};
    return r;
}

const char* kHeader =
    "| candidate | Hausdorff | Hausdorff / diag | mean | RMS | normal angle ° | area Δ | volume Δ | components | "
    "closed | manifold | self-int. pairs | crease kept |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
const char* kRowA = "| a.ply | 0.5 | 5.000e-02 | 0.1 | 0.2 | 3.25 | +1.000% | -2.000% | 1 | yes | yes | - | 87.5% |\n";
const char* kRowB =
    "| b \"<x>\".obj | 0.5 | 5.000e-02 | 0.1 | 0.2 | 3.25 | +1.000% | -2.000% | 1 | no | yes | 7 | 87.5% |\n";

TEST(CompareReport, MarkdownTableRows) {
    EXPECT_EQ(compare_table_markdown(small_report()), std::string(kHeader) + kRowA + kRowB);
    CompareReport empty;
    EXPECT_EQ(compare_table_markdown(empty), kHeader);
}

TEST(CompareReport, MarkdownPage) {
    const std::string md = to_markdown(small_report());
    EXPECT_EQ(
        md.rfind("# normalflow compare\n\nReference: `ref.ply` (bbox diagonal 10, area 6, volume 1, 1 components, "
                 "12 feature edges of total length 12)\n\n",
                 0),
        0u)
        << md;
    EXPECT_NE(md.find(std::string(kHeader) + kRowA + kRowB), std::string::npos) << md;
    EXPECT_NE(md.find("from 1000 area-uniform samples on each surface (seed 7)"), std::string::npos) << md;
    EXPECT_NE(md.find("(dihedral angle above 30°)"), std::string::npos) << md;
    EXPECT_NE(md.find("within 1 % of the reference diagonal"), std::string::npos) << md;
    // The warnings come last, one bullet each, after a blank line.
    const std::string tail = " diagonal, still differ by more than that angle.\n\n- a.ply: candidate is open\n";
    ASSERT_GT(md.size(), tail.size());
    EXPECT_EQ(md.substr(md.size() - tail.size()), tail) << md;
    // Without candidates there are no reference statistics.
    CompareReport none;
    none.reference = "r.obj";
    EXPECT_EQ(to_markdown(none).rfind("# normalflow compare\n\nReference: `r.obj`\n\n", 0), 0u);
}

TEST(CompareReport, CsvHeaderAndRows) {
    EXPECT_EQ(to_csv(small_report()),
              "candidate,hausdorff,hausdorff_relative,mean_distance,mean_relative,rms_distance,rms_relative,"
              "mean_normal_angle_deg,area_change,volume_change,components,closed,manifold,self_intersecting_pairs,"
              "crease_preservation,crease_mean_angle_deg,seconds\n"
              "\"a.ply\",0.5,0.05,0.1,0.01,0.2,0.02,3.25,0.01,-0.02,1,yes,yes,,0.875,40,1.5\n"
              "\"b \"\"<x>\"\".obj\",0.5,0.05,0.1,0.01,0.2,0.02,3.25,0.01,-0.02,1,no,yes,7,0.875,40,1.5\n");
}

// With --correspondence: four more columns, "-" (empty in the CSV) for a row without them.
CompareReport correspondence_report() {
    CompareReport r = small_report();
    r.options.correspondence = true;
    CorrespondenceErrors e;
    e.faces = 12;
    e.degenerate_faces = 2;
    e.mean_face_angle_deg = 7.5;
    e.max_face_angle_deg = 45;
    e.vertices = 8;
    e.mean_vertex_distance = 0.125;
    e.mean_vertex_distance_relative = 0.0125;
    e.max_vertex_distance = 1;
    e.max_vertex_distance_relative = 0.1;
    r.rows[0].comparison.correspondence = e;
    return r;
}

TEST(CompareReport, CorrespondenceColumns) {
    const CompareReport r = correspondence_report();
    EXPECT_EQ(
        compare_table_markdown(r),
        "| candidate | Hausdorff | Hausdorff / diag | mean | RMS | normal angle ° | area Δ | volume Δ | components | "
        "closed | manifold | self-int. pairs | crease kept | face-by-face angle ° | vertex dist. | "
        "vertex dist. / diag | max vertex dist. |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
        "| a.ply | 0.5 | 5.000e-02 | 0.1 | 0.2 | 3.25 | +1.000% | -2.000% | 1 | yes | yes | - | 87.5% | 7.50 | "
        "0.125 | 1.250e-02 | 1 |\n"
        "| b \"<x>\".obj | 0.5 | 5.000e-02 | 0.1 | 0.2 | 3.25 | +1.000% | -2.000% | 1 | no | yes | 7 | 87.5% | - | - "
        "| - | - |\n");
    EXPECT_EQ(
        to_csv(r),
        "candidate,hausdorff,hausdorff_relative,mean_distance,mean_relative,rms_distance,rms_relative,"
        "mean_normal_angle_deg,area_change,volume_change,components,closed,manifold,self_intersecting_pairs,"
        "crease_preservation,crease_mean_angle_deg,face_normal_angle_deg,face_normal_angle_max_deg,"
        "degenerate_faces,mean_vertex_distance,mean_vertex_distance_relative,max_vertex_distance,"
        "max_vertex_distance_relative,seconds\n"
        "\"a.ply\",0.5,0.05,0.1,0.01,0.2,0.02,3.25,0.01,-0.02,1,yes,yes,,0.875,40,7.5,45,2,0.125,0.0125,1,0.1,1.5\n"
        "\"b \"\"<x>\"\".obj\",0.5,0.05,0.1,0.01,0.2,0.02,3.25,0.01,-0.02,1,no,yes,7,0.875,40,,,,,,,,1.5\n");
    const std::string md = to_markdown(r);
    EXPECT_NE(md.find("the face-by-face angle is the unweighted mean over triangles"), std::string::npos) << md;
    EXPECT_EQ(to_markdown(small_report()).find("face-by-face"), std::string::npos);
    CompareReportPictures p;
    p.meshes.resize(3);
    const std::string h = to_html(r, p);
    EXPECT_NE(h.find("<th>crease kept</th><th>face-by-face angle &deg;</th>"), std::string::npos) << h;
    EXPECT_NE(h.find("<td>87.5%</td><td>7.50</td><td>0.125</td><td>1.250e-02</td><td>1</td></tr>"), std::string::npos)
        << h;
    EXPECT_EQ(to_html(small_report(), p).find("face-by-face"), std::string::npos);
}

TEST(CompareReport, HtmlHasTheTableAndThePictures) {
    CompareReportPictures p;
    p.size = 64;
    p.views = {"front", "side"};
    for (int i = 0; i < 3; ++i) {
        const std::string m = "pictures/mesh" + std::to_string(i);
        p.meshes.push_back(
            {{m + "_front.png", m + "_side.png"}, {m + "_front_distance.png", m + "_side_distance.png"}, 0.25 * i});
    }
    p.legend = "pictures/legend.png";
    p.distance_max = 0.5;
    p.percentile = 99;
    p.meshes[2].clipped_fraction = 0.004;
    const std::string h = to_html(small_report(), p);
    // The colour range says what it is, its unit, and what was clipped.
    EXPECT_NE(h.find("viridis from 0 to 0.5: the 99th percentile of all candidates' vertex distances"),
              std::string::npos)
        << h;
    EXPECT_NE(h.find("in the length unit of the meshes' coordinates"), std::string::npos);
    EXPECT_NE(h.find("<br>max 0.5<br>0.4% above the range</td>"), std::string::npos) << h;
    EXPECT_EQ(h.find("<br>max 0.25<br>"), std::string::npos);  // nothing clipped there
    EXPECT_EQ(h.rfind("<!DOCTYPE html>\n", 0), 0u);
    EXPECT_EQ(h.substr(h.size() - 16), "</body>\n</html>\n");
    EXPECT_NE(h.find("<p>Reference: <code>ref.ply</code></p>"), std::string::npos);
    EXPECT_NE(
        h.find("<tr><td>a.ply</td><td>0.5</td><td>5.000e-02</td><td>0.1</td><td>0.2</td><td>3.25</td>"
               "<td>+1.000%</td><td>-2.000%</td><td>1</td><td>yes</td><td>yes</td><td>-</td><td>87.5%</td></tr>\n"),
        std::string::npos)
        << h;
    // Names are escaped, in the table and in the grids.
    EXPECT_NE(h.find("<tr><td>b &quot;&lt;x&gt;&quot;.obj</td>"), std::string::npos) << h;
    EXPECT_EQ(h.find("<x>"), std::string::npos);
    // Every picture, the views as column heads, the size, the legend and the distance maxima.
    for (const auto& m : p.meshes)
        for (int v = 0; v < 2; ++v) {
            EXPECT_NE(h.find("<img src=\"" + m.shaded[v] + "\""), std::string::npos) << m.shaded[v];
            EXPECT_NE(h.find("<img src=\"" + m.distance[v] + "\""), std::string::npos) << m.distance[v];
        }
    EXPECT_NE(h.find("<th>front</th><th>side</th>"), std::string::npos);
    EXPECT_NE(h.find("width=\"64\" height=\"64\""), std::string::npos);
    EXPECT_NE(h.find(".grid img{display:block;width:64px;height:64px;"), std::string::npos);
    EXPECT_NE(h.find("<img class=\"legend\" src=\"pictures/legend.png\" alt=\"colour legend, 0 to 0.5\">"),
              std::string::npos);
    EXPECT_NE(h.find("<br>max 0.25</td>"), std::string::npos);
    EXPECT_NE(h.find("<td class=\"name\" title=\"ref.ply\">reference<br>ref.ply</td>"), std::string::npos) << h;
    EXPECT_NE(h.find("<a href=\"compare.csv\">CSV</a>"), std::string::npos);
}

}  // namespace
}  // namespace normalflow
