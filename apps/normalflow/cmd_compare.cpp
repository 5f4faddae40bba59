// normalflow compare REFERENCE CANDIDATE... [--report DIR] [--json]: metrics without vertex
// correspondence (lib/metrics/compare.h), a table on stdout and compare.{md,csv,json} in DIR, plus
// pictures (io/render/comparison_pictures.h) and an index.html that shows them under the table.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "commands.h"
#include "core/errors.h"
#include "io/util/atomic_file.h"
#include "io/io.h"
#include "io/render/comparison_pictures.h"
#include "metrics/compare.h"
#ifdef NORMALFLOW_HAS_CGAL
#include "io/cgal/repair.h"
#endif

namespace normalflow::cli {

namespace {

struct CompareArgs {
    std::string reference;
    std::vector<std::string> candidates;
    std::string report_dir;               ///< where compare.md/.csv/.json go (none if empty)
    CompareOptions options;
    bool self_intersections = true;       ///< count intersecting triangle pairs (CGAL builds)
    bool pictures = true;                 ///< with --report: PNG pictures and index.html
    int picture_size = 400;               ///< pixels, width and height of each picture
    OutputFlags out;
};

struct Row {
    std::string name;
    MeshComparison c;
    long long self_intersections = -1;  ///< -1: not measured
    double seconds = 0;
};

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

std::string yes_no(bool b) { return b ? "yes" : "no"; }

std::string si(long long n) { return n < 0 ? "-" : std::to_string(n); }

Json row_json(const Row& r) {
    const MeshComparison& c = r.c;
    Json j = Json::object();
    j.set("candidate", r.name);
    j.set("hausdorff", c.distance.hausdorff).set("hausdorff_relative", c.hausdorff_relative);
    j.set("mean_distance", c.distance.mean).set("mean_relative", c.mean_relative);
    j.set("rms_distance", c.distance.rms).set("rms_relative", c.rms_relative);
    j.set("max_candidate_to_reference", c.distance.max_a_to_b).set("max_reference_to_candidate", c.distance.max_b_to_a);
    j.set("mean_normal_angle_deg", c.distance.mean_normal_angle_deg);
    j.set("area", c.area_candidate).set("area_change", c.area_change);
    j.set("volume", c.volume_candidate).set("volume_change", c.volume_change);
    j.set("vertices", c.vertices_candidate).set("triangles", c.faces_candidate);
    j.set("components", c.components_candidate).set("closed", c.closed_candidate).set("manifold", c.manifold_candidate);
    if (r.self_intersections >= 0) j.set("self_intersecting_pairs", r.self_intersections);
    j.set("crease_preservation", c.crease.fraction).set("crease_mean_angle_deg", c.crease.mean_angle_deg);
    j.set("seconds", r.seconds).set("warnings", Json::array(c.warnings));
    return j;
}

Json report_json(const CompareArgs& a, const std::vector<Row>& rows) {
    Json j = Json::object();
    j.set("command", "compare").set("reference", a.reference);
    if (!rows.empty()) {
        const MeshComparison& c = rows.front().c;
        Json ref = Json::object();
        ref.set("bbox_diagonal", c.reference_diagonal).set("area", c.area_reference).set("volume", c.volume_reference);
        ref.set("components", c.components_reference).set("closed", c.closed_reference).set("manifold", c.manifold_reference);
        ref.set("feature_edges", c.crease.feature_edges).set("feature_length", c.crease.feature_length);
        j.set("reference_stats", ref);
    }
    Json proto = Json::object();
    proto.set("samples_per_mesh", a.options.sampling.samples).set("seed", static_cast<unsigned long long>(a.options.sampling.seed));
    proto.set("crease_angle_deg", a.options.crease.angle_deg).set("crease_radius_relative", a.options.crease.radius_relative);
    j.set("protocol", proto);
    Json arr = Json::array();
    for (const Row& r : rows) arr.push(row_json(r));
    j.set("candidates", arr);
    return j;
}

std::string csv_quote(const std::string& s) {
    std::string o = "\"";
    for (char ch : s) {
        if (ch == '"') o += '"';
        o += ch;
    }
    return o + "\"";
}

std::string report_csv(const std::vector<Row>& rows) {
    std::string s =
        "candidate,hausdorff,hausdorff_relative,mean_distance,mean_relative,rms_distance,rms_relative,"
        "mean_normal_angle_deg,area_change,volume_change,components,closed,manifold,self_intersecting_pairs,"
        "crease_preservation,crease_mean_angle_deg,seconds\n";
    for (const Row& r : rows) {
        const MeshComparison& c = r.c;
        s += csv_quote(r.name);
        for (double v : {c.distance.hausdorff, c.hausdorff_relative, c.distance.mean, c.mean_relative, c.distance.rms,
                         c.rms_relative, c.distance.mean_normal_angle_deg, c.area_change, c.volume_change})
        {
            s += ',';
            s += fmt("%.9g", v);
        }
        for (const std::string& field :
             {std::to_string(c.components_candidate), yes_no(c.closed_candidate), yes_no(c.manifold_candidate),
              r.self_intersections < 0 ? std::string() : std::to_string(r.self_intersections),
              fmt("%.6g", c.crease.fraction), fmt("%.6g", c.crease.mean_angle_deg), fmt("%.4g", r.seconds)}) {
            s += ',';
            s += field;
        }
        s += '\n';
    }
    return s;
}

/// One Markdown table (also what is printed to the terminal).
std::string report_table(const std::vector<Row>& rows) {
    std::string s =
        "| candidate | Hausdorff | Hausdorff / diag | mean | RMS | normal angle ° | area Δ | volume Δ | components | "
        "closed | manifold | self-int. pairs | crease kept |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows) {
        const MeshComparison& c = r.c;
        s += "| " + r.name + " | " + fmt("%.4g", c.distance.hausdorff) + " | " + fmt("%.3e", c.hausdorff_relative) +
             " | " + fmt("%.4g", c.distance.mean) + " | " + fmt("%.4g", c.distance.rms) + " | " +
             fmt("%.2f", c.distance.mean_normal_angle_deg) + " | " + fmt("%+.3f%%", 100 * c.area_change) + " | " +
             fmt("%+.3f%%", 100 * c.volume_change) + " | " + std::to_string(c.components_candidate) + " | " +
             yes_no(c.closed_candidate) + " | " + yes_no(c.manifold_candidate) + " | " + si(r.self_intersections) +
             " | " + fmt("%.1f%%", 100 * c.crease.fraction) + " |\n";
    }
    return s;
}

std::string report_markdown(const CompareArgs& a, const std::vector<Row>& rows) {
    std::string s = "# normalflow compare\n\nReference: `" + a.reference + "`";
    if (!rows.empty()) {
        const MeshComparison& c = rows.front().c;
        s += " (bbox diagonal " + fmt("%.6g", c.reference_diagonal) + ", area " + fmt("%.6g", c.area_reference) +
             ", volume " + fmt("%.6g", c.volume_reference) + ", " + std::to_string(c.components_reference) +
             " components, " + std::to_string(c.crease.feature_edges) + " feature edges of total length " +
             fmt("%.6g", c.crease.feature_length) + ")";
    }
    s += "\n\n" + report_table(rows);
    s += "\nProtocol: distances in world units from " + std::to_string(a.options.sampling.samples) +
         " area-uniform samples on each surface (seed " + std::to_string(a.options.sampling.seed) +
         "), exact closest points; Hausdorff is two-sided; mean and RMS pool both directions; the normal "
         "angle is between the candidate's face normal at a sample and the reference's at its closest point. "
         "Area and volume changes are relative to the reference. Crease kept: fraction of the reference's "
         "feature-edge length (dihedral angle above " + fmt("%.3g", a.options.crease.angle_deg) +
         "°) where the candidate's area-weighted mean normals on the two sides, within " +
         fmt("%.3g", 100 * a.options.crease.radius_relative) +
         " % of the reference diagonal, still differ by more than that angle.\n";
    for (const Row& r : rows)
        for (const auto& w : r.c.warnings) s += "\n- " + r.name + ": " + w;
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
std::string report_html(const CompareArgs& a, const std::vector<Row>& rows, const ComparisonPictures& pic) {
    std::string s =
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>normalflow compare</title>\n"
        "<style>\nbody{font-family:sans-serif;margin:1em;color:#222;background:#fff}\n"
        "table{border-collapse:collapse;margin-bottom:1em}\ntd,th{border:1px solid #bbb;padding:3px 6px;"
        "text-align:right;font-size:90%}\ntd:first-child,th:first-child{text-align:left}\n"
        "th{background:#eee}\n.grid td{border:none;padding:2px;vertical-align:middle}\n"
        ".grid img{display:block;width:" + std::to_string(a.picture_size) + "px;height:" +
        std::to_string(a.picture_size) + "px;border:1px solid #ddd}\n"
        ".grid th{text-align:center}\n.grid td.name{min-width:9em;max-width:14em;word-break:break-all;text-align:left;"
        "font-size:90%}\n</style>\n</head>\n<body>\n"
        "<h1>normalflow compare</h1>\n<p>Reference: <code>" + html_escape(a.reference) + "</code></p>\n";
    s += "<table id=\"metrics\">\n<tr><th>candidate</th><th>Hausdorff</th><th>Hausdorff / diag</th><th>mean</th>"
         "<th>RMS</th><th>normal angle &deg;</th><th>area &Delta;</th><th>volume &Delta;</th><th>components</th>"
         "<th>closed</th><th>manifold</th><th>self-int. pairs</th><th>crease kept</th></tr>\n";
    for (const Row& r : rows) {
        const MeshComparison& c = r.c;
        s += "<tr><td>" + html_escape(r.name) + "</td>";
        for (const std::string& f :
             {fmt("%.4g", c.distance.hausdorff), fmt("%.3e", c.hausdorff_relative), fmt("%.4g", c.distance.mean),
              fmt("%.4g", c.distance.rms), fmt("%.2f", c.distance.mean_normal_angle_deg),
              fmt("%+.3f%%", 100 * c.area_change), fmt("%+.3f%%", 100 * c.volume_change),
              std::to_string(c.components_candidate), yes_no(c.closed_candidate), yes_no(c.manifold_candidate),
              si(r.self_intersections), fmt("%.1f%%", 100 * c.crease.fraction)})
            s += "<td>" + f + "</td>";
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
            if (distance && i > 0) g += "<br>max " + fmt("%.4g", pic.meshes[i].max_distance);
            g += "</td>";
            const auto& files = distance ? pic.meshes[i].distance : pic.meshes[i].shaded;
            for (std::size_t v = 0; v < files.size(); ++v)
                g += "<td><img src=\"" + html_escape(files[v]) + "\" alt=\"" + html_escape(name) + ", " + pic.views[v] +
                     "\" width=\"" + std::to_string(a.picture_size) + "\" height=\"" +
                     std::to_string(a.picture_size) + "\"></td>";
            g += "</tr>\n";
        }
        return g + "</table>\n";
    };
    s += grid("Shaded", "shaded", false);
    s += grid("Distance to the reference", "distance", true);
    s += "<p>Colour: unsigned distance from each vertex to the reference surface (exact closest point), "
         "world units, viridis from 0 to " + fmt("%.4g", pic.distance_max) +
         " (the largest vertex distance over all candidates); the reference row is 0 everywhere. "
         "Cameras: orthographic, fitted to the reference's bounding box, the same for every mesh.</p>\n"
         "<p><img class=\"legend\" src=\"" + html_escape(pic.legend) + "\" alt=\"colour legend, 0 to " +
         fmt("%.4g", pic.distance_max) + "\"></p>\n";
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

void write_text(const std::string& path, const std::string& text) {
    AtomicFile f(path, "compare");
    f.write(text);
    f.commit();
}

int run_compare(const CompareArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    const Mesh reference = read_mesh(a.reference);
    std::vector<Row> rows;
    const bool pictures = !a.report_dir.empty() && a.pictures;
    std::vector<Mesh> kept;  // candidates, kept for the pictures
    for (std::size_t i = 0; i < a.candidates.size(); ++i) {
        progress.begin("compare " + a.candidates[i]);
        Stopwatch clock;
        Row r;
        r.name = a.candidates[i];
        Mesh cand = read_mesh(a.candidates[i]);
        r.c = compare_meshes(cand, reference, a.options);
#ifdef NORMALFLOW_HAS_CGAL
        if (a.self_intersections) r.self_intersections = static_cast<long long>(count_self_intersections(cand));
#endif
        r.seconds = clock.seconds();
        rows.push_back(std::move(r));
        if (pictures) kept.push_back(std::move(cand));
        progress.progress(double(i + 1) / double(a.candidates.size()));
        if (progress.should_stop()) throw Cancelled("compare: cancelled");
    }
    double pictures_seconds = -1;  // -1: none drawn
    if (!a.report_dir.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(a.report_dir, ec);
        if (ec) throw IoError("compare: " + a.report_dir + ": cannot create the report folder: " + ec.message());
        const std::filesystem::path dir(a.report_dir);
        write_text((dir / "compare.md").string(), report_markdown(a, rows));
        write_text((dir / "compare.csv").string(), report_csv(rows));
        write_text((dir / "compare.json").string(), report_json(a, rows).dump() + "\n");
        if (pictures) {
            progress.begin("pictures");
            ComparisonPicturesOptions po;
            po.render.width = po.render.height = a.picture_size;
            const ComparisonPictures pic = write_comparison_pictures(a.report_dir, reference, kept, po);
            write_text((dir / "index.html").string(), report_html(a, rows, pic));
            pictures_seconds = pic.seconds;
            progress.progress(1.0);
        }
    }
    if (a.out.json) {
        Json j = report_json(a, rows);
        if (!a.report_dir.empty()) j.set("report", a.report_dir);
        if (pictures_seconds >= 0) j.set("pictures_seconds", pictures_seconds);
        j.set("seconds", total.seconds());
        std::printf("%s\n", j.dump().c_str());
    } else if (!a.out.quiet) {
        std::printf("reference: %s\n%s", a.reference.c_str(), report_table(rows).c_str());
        if (!a.report_dir.empty())
            std::printf("report: %s/compare.{md,csv,json}%s\n", a.report_dir.c_str(), pictures ? ", index.html" : "");
    }
    return 0;
}

}  // namespace

void add_compare_command(CLI::App& app) {
    auto args = std::make_shared<CompareArgs>();
    auto* cmd = app.add_subcommand("compare", "compare candidate meshes with a reference (no vertex correspondence needed)");
    cmd->add_option("REFERENCE", args->reference, "reference mesh (ground truth or input)")->required();
    cmd->add_option("CANDIDATE", args->candidates, "one or more candidate meshes")->required();
    cmd->add_option("--report", args->report_dir,
                    "write compare.md, compare.csv, compare.json, index.html and pictures/ into this folder");
    cmd->add_option("--samples", args->options.sampling.samples, "surface samples per mesh")
        ->check(CLI::PositiveNumber)->capture_default_str();
    cmd->add_option("--seed", args->options.sampling.seed, "sampling seed")->capture_default_str();
    cmd->add_option("--crease-angle", args->options.crease.angle_deg, "feature-edge dihedral threshold, degrees")
        ->check(CLI::Range(0.001, 179.999))->capture_default_str();
    cmd->add_option("--crease-radius", args->options.crease.radius_relative,
                    "crease neighbourhood radius, fraction of the reference bbox diagonal")
        ->check(CLI::PositiveNumber)->capture_default_str();
    cmd->add_flag("!--no-self-intersections", args->self_intersections, "skip counting self-intersections (CGAL)");
    cmd->add_flag("!--no-pictures", args->pictures, "with --report: skip the PNG pictures and index.html");
    cmd->add_option("--picture-size", args->picture_size, "with --report: picture width and height, pixels")
        ->check(CLI::Range(32, 4096))->capture_default_str();
    add_output_flags(cmd, args->out);
    on_run(cmd, args, run_compare);
}

}  // namespace normalflow::cli
