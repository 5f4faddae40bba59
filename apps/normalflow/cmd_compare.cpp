// normalflow compare REFERENCE CANDIDATE... [--report DIR] [--json] [--correspondence]: metrics without
// vertex correspondence (lib/metrics/compare.h), a table on stdout (lib/metrics/compare_report.h) and
// compare.{md,csv,json}, pictures and index.html in DIR (io/render/compare_report.h). With
// --correspondence, for candidates that kept the reference's connectivity, also the face-by-face normal
// angle and the vertex-by-vertex distance (correspondence_errors).
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "core/errors.h"
#include "io/io.h"
#include "io/render/compare_report.h"
#include "io/util/report_json.h"
#include "metrics/compare_report.h"
#ifdef NORMALFLOW_HAS_CGAL
#include "io/cgal/repair.h"
#endif

namespace normalflow::cli {

namespace {

struct CompareArgs {
    std::string reference;
    std::vector<std::string> candidates;
    std::string report_dir;  ///< where compare.md/.csv/.json go (none if empty)
    CompareOptions options;
    bool self_intersections = true;  ///< count intersecting triangle pairs (CGAL builds)
    bool pictures = true;            ///< with --report: PNG pictures and index.html
    int picture_size = 400;          ///< pixels, width and height of each picture
    OutputFlags out;
};

int run_compare(const CompareArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    const Mesh reference = read_mesh(a.reference);
    CompareReport report;
    report.reference = a.reference;
    report.options = a.options;
    const bool pictures = !a.report_dir.empty() && a.pictures;
    std::vector<Mesh> kept;  // candidates, kept for the pictures
    for (std::size_t i = 0; i < a.candidates.size(); ++i) {
        progress.begin("compare " + a.candidates[i]);
        Stopwatch clock;
        CompareReportRow r;
        r.name = a.candidates[i];
        Mesh cand = read_mesh(a.candidates[i]);
        if (a.options.correspondence) {  // refused here, with the file names, before anything is measured
            const std::string mismatch = correspondence_mismatch(cand, reference);
            if (!mismatch.empty())
                throw InvalidInput("--correspondence: candidate " + a.candidates[i] + " vs reference " + a.reference +
                                   ": " + mismatch);
        }
        r.comparison = compare_meshes(cand, reference, a.options);
#ifdef NORMALFLOW_HAS_CGAL
        if (a.self_intersections) r.self_intersections = static_cast<long long>(count_self_intersections(cand));
#endif
        r.seconds = clock.seconds();
        report.rows.push_back(std::move(r));
        if (pictures) kept.push_back(std::move(cand));
        progress.progress(double(i + 1) / double(a.candidates.size()));
        if (progress.should_stop()) throw Cancelled("compare: cancelled");
    }
    double pictures_seconds = -1;  // -1: none drawn
    if (!a.report_dir.empty()) {
        CompareReportOptions ro;
        ro.pictures = a.pictures;
        ro.picture_size = a.picture_size;
        pictures_seconds = write_compare_report(a.report_dir, report, reference, kept, ro, &progress).pictures_seconds;
    }
    if (a.out.json) {
        Json j = to_json(report);
        if (!a.report_dir.empty()) j.set("report", a.report_dir);
        if (pictures_seconds >= 0) j.set("pictures_seconds", pictures_seconds);
        j.set("seconds", total.seconds());
        std::printf("%s\n", j.dump().c_str());
    } else if (!a.out.quiet) {
        std::printf("reference: %s\n%s", a.reference.c_str(), compare_table_markdown(report).c_str());
        if (!a.report_dir.empty())
            std::printf("report: %s/compare.{md,csv,json}%s\n", a.report_dir.c_str(), pictures ? ", index.html" : "");
    }
    return 0;
}

}  // namespace

void add_compare_command(CLI::App& app) {
    auto args = std::make_shared<CompareArgs>();
    auto* cmd =
        app.add_subcommand("compare", "compare candidate meshes with a reference (no vertex correspondence needed)");
    cmd->add_option("REFERENCE", args->reference, "reference mesh (ground truth or input)")->required();
    cmd->add_option("CANDIDATE", args->candidates, "one or more candidate meshes")->required();
    cmd->add_option("--report", args->report_dir,
                    "write compare.md, compare.csv, compare.json, index.html and pictures/ into this folder");
    cmd->add_option("--samples", args->options.sampling.samples, "surface samples per mesh")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--seed", args->options.sampling.seed, "sampling seed")->capture_default_str();
    cmd->add_option("--crease-angle", args->options.crease.angle_deg, "feature-edge dihedral threshold, degrees")
        ->check(CLI::Range(0.001, 179.999))
        ->capture_default_str();
    cmd->add_option("--crease-radius", args->options.crease.radius_relative,
                    "crease neighbourhood radius, fraction of the reference bbox diagonal")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_flag("--correspondence", args->options.correspondence,
                  "also face-by-face normal angle and vertex-by-vertex distance; the candidates must have the "
                  "reference's vertex count and triangles, in order (e.g. a mesh-side smoothing of the noisy "
                  "mesh vs its ground truth)");
    cmd->add_flag("!--no-self-intersections", args->self_intersections, "skip counting self-intersections (CGAL)");
    cmd->add_flag("!--no-pictures", args->pictures, "with --report: skip the PNG pictures and index.html");
    cmd->add_option("--picture-size", args->picture_size, "with --report: picture width and height, pixels")
        ->check(CLI::Range(32, 4096))
        ->capture_default_str();
    add_output_flags(cmd, args->out);
    on_run(cmd, args, run_compare);
}

}  // namespace normalflow::cli
