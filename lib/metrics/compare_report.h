#pragma once
/// \file compare_report.h
/// The report of `normalflow compare` as text: a Markdown table and page, CSV, and the HTML page
/// (index.html) that shows the table above the comparison pictures. Pure string rendering: no file
/// I/O (io/render/compare_report.h writes the files, io/util/report_json.h gives the JSON).

#include <string>
#include <vector>

#include "metrics/compare.h"

namespace normalflow {

/// One candidate of a comparison.
struct CompareReportRow {
    std::string name;                   ///< the candidate as the user named it (a path)
    MeshComparison comparison;          ///< compare_meshes(candidate, reference)
    long long self_intersections = -1;  ///< intersecting triangle pairs; -1: not measured
    double seconds = 0.0;               ///< wall time of reading and measuring this candidate
};

/// A whole comparison: one reference, any number of candidates, the protocol used.
struct CompareReport {
    std::string reference;               ///< the reference as the user named it (a path)
    CompareOptions options;              ///< the protocol (samples, seed, crease angle and radius)
    std::vector<CompareReportRow> rows;  ///< one per candidate, in the user's order
};

/// Where the pictures of a report are, for the HTML page; paths relative to the page's folder.
struct CompareReportPictures {
    struct Row {
        std::vector<std::string> shaded;    ///< one picture per view
        std::vector<std::string> distance;  ///< one picture per view, coloured by distance
        double max_distance = 0.0;          ///< largest vertex distance of this mesh, world units
        double clipped_fraction = 0.0;      ///< fraction of its vertices above distance_max (drawn magenta)
    };
    int size = 400;                  ///< width and height of each picture, pixels
    std::vector<std::string> views;  ///< view names, the columns ("front", "side", "oblique")
    std::vector<Row> meshes;         ///< the reference first, then one per candidate (rows order)
    std::string legend;              ///< the colour legend picture
    double distance_max = 0.0;       ///< top of the colour range, world units
    double percentile = 0.0;         ///< the percentile of all candidates' vertex distances distance_max is (0: given)
};

/// The metric table in Markdown, header and separator lines included, one line per candidate
/// (what `normalflow compare` prints to the terminal). With options.correspondence, four more columns:
/// face-by-face angle, mean vertex distance (absolute and / diagonal), max vertex distance ("-" where a
/// row has no MeshComparison::correspondence); the same in the CSV and HTML tables.
std::string compare_table_markdown(const CompareReport& r);

/// compare.md: a title, the reference with its statistics (when there is a candidate), the table,
/// a paragraph stating the protocol, then one bullet per candidate warning.
std::string to_markdown(const CompareReport& r);

/// compare.csv: a header line, then one line per candidate; the candidate name quoted (RFC 4180),
/// distances with 9 significant digits, self_intersecting_pairs empty when not measured. With
/// options.correspondence, before seconds: face_normal_angle_deg, face_normal_angle_max_deg,
/// degenerate_faces, mean_vertex_distance(_relative), max_vertex_distance(_relative), empty when not measured.
std::string to_csv(const CompareReport& r);

/// index.html: the metric table, then grids of shaded and distance pictures (rows = meshes,
/// columns = views), a legend and a small inline script that marks which pictures loaded. Only
/// relative paths, no external resources. Names are HTML-escaped.
/// pictures.meshes must hold r.rows.size() + 1 entries (asserted).
std::string to_html(const CompareReport& r, const CompareReportPictures& pictures);

}  // namespace normalflow
