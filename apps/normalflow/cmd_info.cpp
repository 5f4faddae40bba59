// normalflow info IN [--self-intersections] [--repair] [--json]: what a mesh file holds, and its defects.
// With --repair the mesh is repaired with CGAL's polygon-soup tools (repair_mesh) and the report is of
// the repaired mesh, next to what the repair did.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "core/mesh_report.h"
#include "io/io.h"
#include "pipeline/report_json.h"
#ifdef NORMALFLOW_HAS_CGAL
#include "io/cgal/repair.h"
#endif

namespace normalflow::cli {

namespace {

struct InfoArgs {
    std::string input;
    bool self_intersections = false;  ///< also count intersecting triangle pairs (CGAL; slower)
    bool repair = false;              ///< repair first (merge points, drop degenerate/duplicate faces, orient)
    OutputFlags out;
};

int run_info(const InfoArgs& a) {
    Stopwatch clock;
    ReadInfo info;
    Mesh mesh = read_mesh(a.input, &info);
    const std::vector<std::string> attributes = attribute_names(mesh);  // before --repair drops them
    const std::string attribute_text = attribute_words(mesh);
    bool repaired = false;
#ifdef NORMALFLOW_HAS_CGAL
    RepairReport rep;
    if (a.repair) {
        rep = repair_mesh(mesh);
        repaired = true;
    }
#else
    if (a.repair) throw InvalidInput("info: --repair needs a build with CGAL");
#endif
    const MeshReport r = mesh_report(mesh);
    long long self_intersections = -1;
#ifdef NORMALFLOW_HAS_CGAL
    if (a.self_intersections) self_intersections = static_cast<long long>(count_self_intersections(mesh));
#else
    if (a.self_intersections) throw InvalidInput("info: --self-intersections needs a build with CGAL");
#endif
    if (a.out.json) {
        Json j = to_json(r);  // every MeshReport field
        j.set("command", "info").set("input", a.input).set("format", info.format);
        j.set("file_vertices", info.file_vertices).set("file_faces", info.file_faces);
        j.set("polygons_split", info.polygons_split).set("attributes", Json::array(attributes));
        if (self_intersections >= 0) j.set("self_intersecting_pairs", self_intersections);
#ifdef NORMALFLOW_HAS_CGAL
        if (repaired) j.set("repair", to_json(rep));
#endif
        j.set("repaired", repaired);
        Json w = Json::array(info.warnings);
        for (const auto& s : r.warnings) w.push(s);
        j.set("warnings", w).set("seconds", clock.seconds());
        std::printf("%s\n", j.dump().c_str());
        return 0;
    }
    if (a.out.quiet) return 0;
    std::printf("%s (%s)\n", a.input.c_str(), info.format.c_str());
    std::printf("  in file          %zu points, %zu faces%s\n", info.file_vertices, info.file_faces,
                info.polygons_split ? " (polygons split into triangles)" : "");
    std::printf("  attributes       %s\n", attribute_text.c_str());
#ifdef NORMALFLOW_HAS_CGAL
    if (repaired) {
        std::printf("  repair           %zu points merged, %zu degenerate and %zu duplicate faces removed,\n",
                    rep.points_merged, rep.degenerate_removed, rep.duplicates_removed);
        std::printf("                   %zu faces reversed, %zu closed patches turned outward, %zu open patches%s\n",
                    rep.faces_reversed, rep.patches_inverted, rep.open_patches,
                    rep.orientable ? "" : " (not orientable without splitting)");
        for (const auto& s : rep.warnings) std::printf("  repair warning: %s\n", s.c_str());
        std::printf("  after repair:\n");
    }
#endif
    std::printf("  vertices         %zu unique positions\n", r.vertices);
    std::printf("  triangles        %zu\n", r.faces);
    std::printf("  components       %zu\n", r.components);
    std::printf("  boundary edges   %zu (%zu loops)\n", r.boundary_edges, r.boundary_loops);
    std::printf("  non-manifold     %zu edges, %zu vertices\n", r.non_manifold_edges, r.non_manifold_vertices);
    std::printf("  degenerate       %zu faces\n", r.degenerate_faces);
    std::printf("  duplicate        %zu faces\n", r.duplicate_faces);
    std::printf("  inconsistent     %zu edges (orientation)\n", r.inconsistent_edges);
    if (self_intersections >= 0) std::printf("  self-intersecting %lld triangle pairs\n", self_intersections);
    std::printf("  closed           %s\n  manifold         %s\n", r.closed ? "yes" : "no", r.manifold ? "yes" : "no");
    std::printf("  euler char.      %ld\n", r.euler_characteristic);
    std::printf("  area, volume     %.6g, %.6g\n", r.area, r.volume);
    std::printf("  bounding box     [%.6g %.6g %.6g] - [%.6g %.6g %.6g]\n", r.bbox.min.x, r.bbox.min.y, r.bbox.min.z,
                r.bbox.max.x, r.bbox.max.y, r.bbox.max.z);
    for (const auto& s : info.warnings) std::printf("  warning: %s\n", s.c_str());
    for (const auto& s : r.warnings) std::printf("  warning: %s\n", s.c_str());
    return 0;
}

}  // namespace

void add_info_command(CLI::App& app) {
    auto args = std::make_shared<InfoArgs>();
    auto* cmd = app.add_subcommand("info", "report what a mesh file holds: counts, defects, topology");
    cmd->add_option("IN", args->input, "mesh file (obj, ply, off, stl, gltf, glb, drc)")->required();
    cmd->add_flag("--self-intersections", args->self_intersections, "also count intersecting triangle pairs (slower)");
    cmd->add_flag("--repair", args->repair,
                  "repair first (merge duplicate points, remove degenerate and duplicate faces, orient) and "
                  "report the repaired mesh");
    add_output_flags(cmd, args->out);
    on_run(cmd, args, run_info);
}

}  // namespace normalflow::cli
