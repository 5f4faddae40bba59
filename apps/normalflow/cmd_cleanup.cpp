// normalflow cleanup IN OUT [--target-faces N | --max-error E | --edge-length L] [--min-component F]
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "core/errors.h"
#include "io/io.h"
#ifdef NORMALFLOW_HAS_CGAL
#include "io/cgal/cleanup.h"
#endif

namespace normalflow::cli {
namespace {

struct CleanupArgs {
    std::string input, output;
    std::size_t target_faces = 0;
    double max_error = 0.0, edge_length = 0.0, min_component = 0.0;
    bool no_repair = false;
    OutputFlags out;
};

int run_cleanup(const CleanupArgs& a) {
#ifdef NORMALFLOW_HAS_CGAL
    if (mesh_format_from_path(a.output) == MeshFormat::Unknown)
        throw InvalidInput("cleanup: " + a.output + ": unknown output format");
    const int modes = (a.target_faces > 0) + (a.max_error > 0) + (a.edge_length > 0);
    if (modes > 1) throw InvalidInput("cleanup: give at most one of --target-faces, --max-error, --edge-length");
    Mesh m = read_mesh(a.input);
    cgal::CleanupOptions o;
    o.min_component_fraction = a.min_component;
    o.repair_self_intersections = !a.no_repair;
    if (a.target_faces > 0) { o.reduction = cgal::CleanupReduction::FaceCount; o.target_faces = a.target_faces; }
    if (a.max_error > 0) { o.reduction = cgal::CleanupReduction::ErrorBound; o.max_error = a.max_error; }
    if (a.edge_length > 0) { o.reduction = cgal::CleanupReduction::Remesh; o.target_edge_length = a.edge_length; }
    const cgal::CleanupReport r = cgal::cleanup_mesh(m, o);
    write_mesh(a.output, m);
    if (a.out.json) {
        Json j = Json::object();
        j.set("command", "cleanup").set("input", a.input).set("output", a.output)
            .set("faces_before", r.faces_before).set("faces_after", r.faces_after)
            .set("degenerate_removed", r.degenerate_removed).set("components_removed", r.components_removed)
            .set("components_reversed", r.components_reversed).set("hausdorff", r.hausdorff)
            .set("result_to_input", r.result_to_input).set("input_to_result", r.input_to_result)
            .set("closed", r.closed).set("manifold", r.manifold).set("self_intersections", r.self_intersections)
            .set("self_intersections_found", r.self_intersections_found)
            .set("seconds", r.seconds).set("warnings", Json::array(r.warnings));
        std::printf("%s\n", j.dump().c_str());
    } else if (!a.out.quiet) {
        std::printf("cleanup: %s -> %s: %zu -> %zu faces, Hausdorff %.6g, %s, %s, %zu self-intersections (%zu before "
                    "repair) (%.2f s)\n",
                    a.input.c_str(), a.output.c_str(), r.faces_before, r.faces_after, r.hausdorff,
                    r.closed ? "closed" : "OPEN", r.manifold ? "manifold" : "NON-MANIFOLD", r.self_intersections,
                    r.self_intersections_found, r.seconds);
        for (const auto& w : r.warnings) std::fprintf(stderr, "cleanup: warning: %s\n", w.c_str());
    }
    return 0;
#else
    (void)a;
    throw InvalidInput("cleanup: needs a build with CGAL");
#endif
}

}  // namespace

void add_cleanup_command(CLI::App& app) {
    auto a = std::make_shared<CleanupArgs>();
    auto* cmd = app.add_subcommand("cleanup", "remove slivers and small parts, orient, decimate or remesh (CGAL)");
    cmd->add_option("IN", a->input, "mesh file")->required();
    cmd->add_option("OUT", a->output, "mesh file")->required();
    cmd->add_option("--target-faces", a->target_faces, "decimate to at most N faces (edge collapse)");
    cmd->add_option("--max-error", a->max_error, "decimate while within E (world units) of the input")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--edge-length", a->edge_length, "isotropic remeshing to edge length L (world units)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--min-component", a->min_component, "drop components below this fraction of the faces")
        ->check(CLI::Range(0.0, 0.999999));
    cmd->add_flag("--no-repair", a->no_repair, "do not repair self-intersecting faces (only report them)");
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_cleanup);
}

}  // namespace normalflow::cli
