// normalflow cleanup IN OUT [--target-faces N | --max-error E | --edge-length L] [--min-component F]
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "core/errors.h"
#include "core/mesh_report.h"
#include "io/cgal/cleanup.h"  // plain option and report structs; the code needs CGAL
#include "io/io.h"
#include "pipeline/pipeline.h"
#include "pipeline/report_json.h"

namespace normalflow::cli {
namespace {

/// The flags parse straight into CleanupOptions; the reduction follows from which of
/// --target-faces, --max-error, --edge-length is given.
struct CleanupArgs {
    std::string input, output;
    cgal::CleanupOptions cleanup;
    Decimator decimator = Decimator::Auto;
    OutputFlags out;
};

int run_cleanup(const CleanupArgs& a) {
#ifdef NORMALFLOW_HAS_CGAL
    if (mesh_format_from_path(a.output) == MeshFormat::Unknown)
        throw InvalidInput("cleanup: " + a.output + ": unknown output format");
    cgal::CleanupOptions o = a.cleanup;
    const int modes = (o.target_faces > 0) + (o.max_error > 0) + (o.target_edge_length > 0);
    if (modes > 1) throw InvalidInput("cleanup: give at most one of --target-faces, --max-error, --edge-length");
    if (o.target_faces > 0) o.reduction = cgal::CleanupReduction::FaceCount;
    if (o.max_error > 0) o.reduction = cgal::CleanupReduction::ErrorBound;
    if (o.target_edge_length > 0) o.reduction = cgal::CleanupReduction::Remesh;
    Mesh m = read_mesh(a.input);
    const bool had_normals = m.has_normals(), had_colors = m.has_colors(), had_texcoords = m.has_texcoords();
    // --target-faces: decimate_mesh first (the quadric collapse by default, checked, CGAL's edge collapse
    // as the fallback), on the welded input, then the repairs on the small result; --decimator cgal keeps
    // CGAL's own FaceCount reduction after the repairs.
    const bool checked = o.reduction == cgal::CleanupReduction::FaceCount && a.decimator != Decimator::Cgal;
    std::string decimator = o.target_faces > 0 ? "cgal" : "";
    cgal::CleanupReport r;
    if (checked) {
        Mesh input = m;
        // welding joins positions only: the report of the welded mesh is this one
        const MeshReport mr = mesh_report(m);
        if (mr.vertices < mr.input_vertices) {
            input = weld_exact(m);  // shared corners written as separate vertices (STL, soups): join them
            m = input;
        }
        // the distance is measured below, after the repairs
        const DecimationReport d = decimate_mesh(
            m,
            {.target_faces = o.target_faces, .decimator = a.decimator, .input_report = &mr, .measure_distance = false});
        decimator = d.decimator;
        o.reduction = cgal::CleanupReduction::None;
        // no needle collapse after it: the decimation made no degenerate face, and its long thin
        // triangles along creases are where they belong (collapsing them moved fandisk's creases by
        // 0.018 against the decimation's 0.007)
        o.remove_degenerate = false;
        r = cgal::cleanup_mesh(m, o);
        r.faces_before = d.faces_before;
        r.vertices_before = d.vertices_before;
        const SampledDistance dist = decimation_distance(m, input);  // as decimate_mesh measures
        r.result_to_input = dist.a_to_b;
        r.input_to_result = dist.b_to_a;
        r.hausdorff = dist.hausdorff;
        r.seconds += d.seconds;
        r.warnings.insert(r.warnings.begin(), d.warnings.begin(), d.warnings.end());
    } else {
        r = cgal::cleanup_mesh(m, o);
    }
    // The repairs merge and renumber vertices, which drops the attributes: normals are recomputed from the result,
    // so that a mesh that shaded smoothly still does (the web route: cleanup, then compress); what cannot be
    // recomputed is said.
    const bool normals_recomputed = had_normals && !m.has_normals();
    if (normals_recomputed) compute_vertex_normals(m);
    if ((had_colors && !m.has_colors()) || (had_texcoords && !m.has_texcoords()))
        r.warnings.push_back(std::string("the input's ") +
                             (had_colors && had_texcoords ? "colours and texture coordinates were"
                              : had_colors                ? "colours were"
                                                          : "texture coordinates were") +
                             " dropped: the repairs renumber the vertices");
    write_mesh(a.output, m);
    if (a.out.json) {
        Json j = to_json(r);
        if (!decimator.empty()) j.set("decimator", decimator);
        if (normals_recomputed) j.set("normals", "recomputed");
        j.set("command", "cleanup").set("input", a.input).set("output", a.output);
        std::printf("%s\n", j.dump().c_str());
    } else if (!a.out.quiet) {
        std::printf(
            "cleanup: %s -> %s: %zu -> %zu faces, Hausdorff %.6g, %s, %s, %zu self-intersections (%zu before "
            "repair) (%.2f s)\n",
            a.input.c_str(), a.output.c_str(), r.faces_before, r.faces_after, r.hausdorff, r.closed ? "closed" : "OPEN",
            r.manifold ? "manifold" : "NON-MANIFOLD", r.self_intersections, r.self_intersections_found, r.seconds);
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
    cgal::CleanupOptions& o = a->cleanup;
    cmd->add_option("--target-faces", o.target_faces,
                    "decimate to at most N faces (quadric edge collapse, checked; see --decimator)");
    add_decimator_option(cmd, a->decimator);
    cmd->add_option("--max-error", o.max_error, "decimate while within E (world units) of the input")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--edge-length", o.target_edge_length, "isotropic remeshing to edge length L (world units)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--min-component", o.min_component_fraction, "drop components below this fraction of the faces")
        ->check(CLI::Range(0.0, 0.999999))
        ->capture_default_str();
    cmd->add_flag("!--no-repair", o.repair_self_intersections,
                  "do not repair self-intersecting faces (only report them)");
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_cleanup);
}

}  // namespace normalflow::cli
