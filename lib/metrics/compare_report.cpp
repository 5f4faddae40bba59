#include "metrics/compare_report.h"

#include <cassert>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace normalflow {

namespace {

using Row = CompareReportRow;

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

std::string yes_no(bool b) { return b ? "yes" : "no"; }

std::string si(long long n) { return n < 0 ? "-" : std::to_string(n); }

/// The correspondence columns of the tables (with CompareOptions::correspondence): face-by-face normal
/// angle, mean vertex distance (absolute, / diagonal) and max; "-" where a row has none.
const char* kCorrespondenceHeader = " face-by-face angle ° | vertex dist. | vertex dist. / diag | max vertex dist. |";
const char* kCorrespondenceRule = "---|---|---|---|";

std::vector<std::string> correspondence_cells(const MeshComparison& c) {
    if (!c.correspondence) return {"-", "-", "-", "-"};
    const CorrespondenceErrors& e = *c.correspondence;
    return {fmt("%.2f", e.mean_face_angle_deg), fmt("%.4g", e.mean_vertex_distance),
            fmt("%.3e", e.mean_vertex_distance_relative), fmt("%.4g", e.max_vertex_distance)};
}

std::string csv_quote(const std::string& s) {
    std::string o = "\"";
    for (char ch : s) {
        if (ch == '"') o += '"';
        o += ch;
    }
    return o + "\"";
}

std::string report_csv(const std::vector<Row>& rows, bool correspondence) {
    std::string s =
        "candidate,hausdorff,hausdorff_relative,mean_distance,mean_relative,rms_distance,rms_relative,"
        "mean_normal_angle_deg,area_change,volume_change,components,closed,manifold,self_intersecting_pairs,"
        "crease_preservation,crease_mean_angle_deg,";
    if (correspondence)
        s += "face_normal_angle_deg,face_normal_angle_max_deg,degenerate_faces,mean_vertex_distance,"
             "mean_vertex_distance_relative,max_vertex_distance,max_vertex_distance_relative,";
    s += "seconds\n";
    for (const Row& r : rows) {
        const MeshComparison& c = r.comparison;
        s += csv_quote(r.name);
        for (double v : {c.distance.hausdorff, c.hausdorff_relative, c.distance.mean, c.mean_relative, c.distance.rms,
                         c.rms_relative, c.distance.mean_normal_angle_deg, c.area_change, c.volume_change}) {
            s += ',';
            s += fmt("%.9g", v);
        }
        for (const std::string& field :
             {std::to_string(c.components_candidate), yes_no(c.closed_candidate), yes_no(c.manifold_candidate),
              r.self_intersections < 0 ? std::string() : std::to_string(r.self_intersections),
              fmt("%.6g", c.crease.fraction), fmt("%.6g", c.crease.mean_angle_deg)}) {
            s += ',';
            s += field;
        }
        if (correspondence) {  // empty fields for a row without them
            const CorrespondenceErrors* e = c.correspondence ? &*c.correspondence : nullptr;
            for (const std::string& field :
                 {e ? fmt("%.9g", e->mean_face_angle_deg) : "", e ? fmt("%.9g", e->max_face_angle_deg) : "",
                  e ? std::to_string(e->degenerate_faces) : "", e ? fmt("%.9g", e->mean_vertex_distance) : "",
                  e ? fmt("%.9g", e->mean_vertex_distance_relative) : "", e ? fmt("%.9g", e->max_vertex_distance) : "",
                  e ? fmt("%.9g", e->max_vertex_distance_relative) : ""}) {
                s += ',';
                s += field;
            }
        }
        s += ',';
        s += fmt("%.4g", r.seconds);
        s += '\n';
    }
    return s;
}

/// One Markdown table (also what is printed to the terminal).
std::string report_table(const std::vector<Row>& rows, bool correspondence) {
    std::string s =
        "| candidate | Hausdorff | Hausdorff / diag | mean | RMS | normal angle ° | area Δ | volume Δ | components | "
        "closed | manifold | self-int. pairs | crease kept |";
    if (correspondence) s += kCorrespondenceHeader;
    s += "\n|---|---|---|---|---|---|---|---|---|---|---|---|---|";
    if (correspondence) s += kCorrespondenceRule;
    s += '\n';
    for (const Row& r : rows) {
        const MeshComparison& c = r.comparison;
        s += "| " + r.name + " | " + fmt("%.4g", c.distance.hausdorff) + " | " + fmt("%.3e", c.hausdorff_relative) +
             " | " + fmt("%.4g", c.distance.mean) + " | " + fmt("%.4g", c.distance.rms) + " | " +
             fmt("%.2f", c.distance.mean_normal_angle_deg) + " | " + fmt("%+.3f%%", 100 * c.area_change) + " | " +
             fmt("%+.3f%%", 100 * c.volume_change) + " | " + std::to_string(c.components_candidate) + " | " +
             yes_no(c.closed_candidate) + " | " + yes_no(c.manifold_candidate) + " | " + si(r.self_intersections) +
             " | " + fmt("%.1f%%", 100 * c.crease.fraction) + " |";
        if (correspondence)
            for (const std::string& cell : correspondence_cells(c)) s += " " + cell + " |";
        s += '\n';
    }
    return s;
}

std::string report_markdown(const CompareReport& a) {
    const std::vector<Row>& rows = a.rows;
    std::string s = "# normalflow compare\n\nReference: `" + a.reference + "`";
    if (!rows.empty()) {
        const MeshComparison& c = rows.front().comparison;
        s += " (bbox diagonal " + fmt("%.6g", c.reference_diagonal) + ", area " + fmt("%.6g", c.area_reference) +
             ", volume " + fmt("%.6g", c.volume_reference) + ", " + std::to_string(c.components_reference) +
             " components, " + std::to_string(c.crease.feature_edges) + " feature edges of total length " +
             fmt("%.6g", c.crease.feature_length) + ")";
    }
    s += "\n\n" + report_table(rows, a.options.correspondence);
    s += "\nProtocol: distances in world units from " + std::to_string(a.options.sampling.samples) +
         " area-uniform samples on each surface (seed " + std::to_string(a.options.sampling.seed) +
         "), exact closest points; Hausdorff is two-sided; mean and RMS pool both directions; the normal "
         "angle is between the candidate's face normal at a sample and the reference's at its closest point. "
         "Area and volume changes are relative to the reference. Crease kept: fraction of the reference's "
         "feature-edge length (dihedral angle above " +
         fmt("%.3g", a.options.crease.angle_deg) +
         "°) where the candidate's area-weighted mean normals on the two sides, within " +
         fmt("%.3g", 100 * a.options.crease.radius_relative) +
         " % of the reference diagonal, still differ by more than that angle.";
    if (a.options.correspondence)
        s += " Correspondence (the candidate keeps the reference's vertices and triangles in order): the "
             "face-by-face angle is the unweighted mean over triangles of the angle between triangle i's unit "
             "normal on the candidate and on the reference (triangles of zero area in either mesh are left out "
             "and counted in the warnings); vertex distances are |p_i − q_i| over all vertices, their mean "
             "(absolute and / reference diagonal) and their max.";
    s += "\n";
    for (const Row& r : rows)
        for (const auto& w : r.comparison.warnings) s += "\n- " + r.name + ": " + w;
    s += "\n";
    return s;
}

std::string html_escape(const std::string& s) {
    std::string o;
    for (char ch : s) {
        switch (ch) {
            case '&': o += "&amp;"; break;
            case '<': o += "&lt;"; break;
            case '>': o += "&gt;"; break;
            case '"': o += "&quot;"; break;
            case '\'': o += "&#39;"; break;
            default: o += ch;
        }
    }
    return o;
}

/// index.html: the metric table, then a grid of pictures (rows = meshes, columns = views), shaded and
/// coloured by distance. Only relative paths, no external resources; an inline script marks every
/// <img> that decoded (data-loaded="yes") and counts them in #image-status (used by the browser test).
std::string report_html(const CompareReport& a, const CompareReportPictures& pic) {
    const std::vector<Row>& rows = a.rows;
    assert(pic.meshes.size() == rows.size() + 1 &&
           "to_html: pictures.meshes needs the reference and one entry per row");
    std::string s =
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>normalflow compare</title>\n"
        "<style>\nbody{font-family:sans-serif;margin:1em;color:#222;background:#fff}\n"
        "table{border-collapse:collapse;margin-bottom:1em}\ntd,th{border:1px solid #bbb;padding:3px 6px;"
        "text-align:right;font-size:90%}\ntd:first-child,th:first-child{text-align:left}\n"
        "th{background:#eee}\n.grid td{border:none;padding:2px;vertical-align:middle}\n"
        ".grid img{display:block;width:" +
        std::to_string(pic.size) + "px;height:" + std::to_string(pic.size) +
        "px;border:1px solid #ddd}\n"
        ".grid th{text-align:center}\n.grid td.name{min-width:9em;max-width:14em;word-break:break-all;text-align:left;"
        "font-size:90%}\n</style>\n</head>\n<body>\n"
        "<h1>normalflow compare</h1>\n<p>Reference: <code>" +
        html_escape(a.reference) + "</code></p>\n";
    s += "<table id=\"metrics\">\n<tr><th>candidate</th><th>Hausdorff</th><th>Hausdorff / diag</th><th>mean</th>"
         "<th>RMS</th><th>normal angle &deg;</th><th>area &Delta;</th><th>volume &Delta;</th><th>components</th>"
         "<th>closed</th><th>manifold</th><th>self-int. pairs</th><th>crease kept</th>";
    if (a.options.correspondence)
        s += "<th>face-by-face angle &deg;</th><th>vertex dist.</th><th>vertex dist. / diag</th>"
             "<th>max vertex dist.</th>";
    s += "</tr>\n";
    for (const Row& r : rows) {
        const MeshComparison& c = r.comparison;
        s += "<tr><td>" + html_escape(r.name) + "</td>";
        for (const std::string& f :
             {fmt("%.4g", c.distance.hausdorff), fmt("%.3e", c.hausdorff_relative), fmt("%.4g", c.distance.mean),
              fmt("%.4g", c.distance.rms), fmt("%.2f", c.distance.mean_normal_angle_deg),
              fmt("%+.3f%%", 100 * c.area_change), fmt("%+.3f%%", 100 * c.volume_change),
              std::to_string(c.components_candidate), yes_no(c.closed_candidate), yes_no(c.manifold_candidate),
              si(r.self_intersections), fmt("%.1f%%", 100 * c.crease.fraction)})
            s += "<td>" + f + "</td>";
        if (a.options.correspondence)
            for (const std::string& f : correspondence_cells(c)) s += "<td>" + f + "</td>";
        s += "</tr>\n";
    }
    s += "</table>\n<p>Also as <a href=\"compare.md\">Markdown</a>, <a href=\"compare.csv\">CSV</a> and "
         "<a href=\"compare.json\">JSON</a>. <span id=\"image-status\" data-loaded=\"-1\"></span></p>\n";
    auto grid = [&](const char* title, const char* cls, bool distance) {
        std::string g = "<h2>" + std::string(title) + "</h2>\n<table class=\"grid " + cls + "\">\n<tr><th></th>";
        for (const std::string& v : pic.views) g += "<th>" + v + "</th>";
        g += "</tr>\n";
        for (std::size_t i = 0; i < pic.meshes.size(); ++i) {
            const std::string name = i == 0 ? a.reference : rows[i - 1].name;
            const std::string shown = std::filesystem::path(name).filename().string();
            g += "<tr><td class=\"name\" title=\"" + html_escape(name) + "\">" + (i == 0 ? "reference<br>" : "") +
                 html_escape(shown);
            if (distance && i > 0) {
                g += "<br>max " + fmt("%.4g", pic.meshes[i].max_distance);
                if (pic.meshes[i].clipped_fraction > 0)
                    g += "<br>" + fmt("%.2g", 100 * pic.meshes[i].clipped_fraction) + "% above the range";
            }
            g += "</td>";
            const auto& files = distance ? pic.meshes[i].distance : pic.meshes[i].shaded;
            for (std::size_t v = 0; v < files.size(); ++v)
                g += "<td><img src=\"" + html_escape(files[v]) + "\" alt=\"" + html_escape(name) + ", " + pic.views[v] +
                     "\" width=\"" + std::to_string(pic.size) + "\" height=\"" + std::to_string(pic.size) + "\"></td>";
            g += "</tr>\n";
        }
        return g + "</table>\n";
    };
    s += grid("Shaded", "shaded", false);
    s += grid("Distance to the reference", "distance", true);
    const std::string range_why =
        pic.percentile > 0 && pic.percentile < 100
            ? "the " + fmt("%.3g", pic.percentile) +
                  "th percentile of all candidates' vertex distances, so that a few far vertices do not set the "
                  "scale; farther vertices are clipped and drawn magenta, the + swatch of the legend"
            : (pic.percentile >= 100 ? std::string("the largest vertex distance over all candidates")
                                     : std::string("as given"));
    s += "<p>Colour: unsigned distance from each vertex to the reference surface (exact closest point), in the "
         "length unit of the meshes' coordinates (the reference's bounding-box diagonal is " +
         fmt("%.4g", a.rows.empty() ? 0.0 : a.rows[0].comparison.reference_diagonal) + "), viridis from 0 to " +
         fmt("%.4g", pic.distance_max) + ": " + range_why +
         ". The reference row is 0 everywhere. "
         "Cameras: orthographic, fitted to the reference's bounding box, the same for every mesh.</p>\n"
         "<p><img class=\"legend\" src=\"" +
         html_escape(pic.legend) + "\" alt=\"colour legend, 0 to " + fmt("%.4g", pic.distance_max) + "\"></p>\n";
    s += "<script>\nwindow.addEventListener('load', function () {\n"
         "  var imgs = document.images, ok = 0;\n"
         "  for (var i = 0; i < imgs.length; ++i) {\n"
         "    var good = imgs[i].complete && imgs[i].naturalWidth > 0;\n"
         "    imgs[i].setAttribute('data-loaded', good ? 'yes' : 'no');\n"
         "    if (good) ++ok;\n  }\n"
         "  var st = document.getElementById('image-status');\n"
         "  st.setAttribute('data-loaded', String(ok));\n"
         "  st.setAttribute('data-total', String(imgs.length));\n"
         "  st.textContent = ok + ' of ' + imgs.length + ' pictures loaded.';\n"
         "});\n</script>\n</body>\n</html>\n";
    return s;
}

}  // namespace

std::string compare_table_markdown(const CompareReport& r) { return report_table(r.rows, r.options.correspondence); }

std::string to_markdown(const CompareReport& r) { return report_markdown(r); }

std::string to_csv(const CompareReport& r) { return report_csv(r.rows, r.options.correspondence); }

std::string to_html(const CompareReport& r, const CompareReportPictures& pictures) { return report_html(r, pictures); }

}  // namespace normalflow
