// normalflow tetmesh IN OUT.(mesh|vtu|node) [--edge-length L] [--quality 1.414] [--min-dihedral 15]
//                   [--max-dihedral 150] [--optimize 2] [--max-volume V] [--surface auto|keep|split]
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "commands.h"
#include "core/errors.h"
#include "io/cgal/cleanup.h"  // plain option and report structs; the code needs CGAL
#include "io/io.h"
#include "io/tetgen/tetmesh.h"  // plain option and report structs; the code needs TetGen
#include "pipeline/pipeline.h"

namespace normalflow::cli {
namespace {

struct TetmeshArgs {
    std::string input, output;
    TetmeshOptions tetmesh;    ///< the flags parse straight into it
    double edge_length = 0.0;  ///< > 0: remesh the surface isotropically to this edge length first
    OutputFlags out;
};

const std::map<std::string, TetmeshOptions::Surface> kSurfaces = {{"auto", TetmeshOptions::Surface::Auto},
                                                                  {"keep", TetmeshOptions::Surface::Keep},
                                                                  {"split", TetmeshOptions::Surface::Split}};

int run_tetmesh(const TetmeshArgs& a) {
#ifdef NORMALFLOW_HAS_TETGEN
    Mesh m = read_mesh(a.input);
    std::size_t remeshed_faces = 0;
    if (a.edge_length > 0) {
#ifdef NORMALFLOW_HAS_CGAL
        // Even triangles first: TetGen keeps the surface's triangles (-Y), and a sliver at the surface
        // can only be as good as the triangle it stands on (an extraction's or decimation's thin
        // triangles left 0.02° however TetGen was switched).
        cgal::CleanupOptions co;
        co.reduction = cgal::CleanupReduction::Remesh;
        co.target_edge_length = a.edge_length;
        const cgal::CleanupReport cr = cgal::cleanup_mesh(m, co);
        for (const std::string& w : cr.warnings) std::fprintf(stderr, "tetmesh: %s: %s\n", a.input.c_str(), w.c_str());
        remeshed_faces = m.triangles.size();
#else
        throw InvalidInput("tetmesh: --edge-length needs a build with CGAL");
#endif
    }
    TetmeshReport r;
    const TetMesh t = tetrahedralize(m, a.tetmesh, &r);
    write_tetmesh(a.output, t);
    if (!a.out.quiet && r.min_dihedral_deg < 10.0) {
        if (r.surface_min_angle_deg < 10.0)
            std::fprintf(stderr,
                         "tetmesh: %s: the smallest dihedral angle is %.2f deg: the surface itself folds to %.2f deg "
                         "between two faces, and no tetrahedron there can do better\n",
                         a.input.c_str(), r.min_dihedral_deg, r.surface_min_angle_deg);
        else if (a.edge_length == 0)
            std::fprintf(
                stderr,
                "tetmesh: %s: the smallest dihedral angle is %.2f deg; the tetrahedra at the surface are as "
                "good as its triangles: --edge-length %.3g (its median edge length) remeshes it evenly first\n",
                a.input.c_str(), r.min_dihedral_deg, median_edge_length(m));
    }
    if (a.out.json) {
        Json j = Json::object();
        j.set("command", "tetmesh")
            .set("input", a.input)
            .set("output", a.output)
            .set("tetrahedra", r.tetrahedra)
            .set("points", r.points)
            .set("min_dihedral_deg", r.min_dihedral_deg)
            .set("volume", r.volume)
            .set("surface_volume", r.surface_volume)
            .set("surface_min_angle_deg", r.surface_min_angle_deg)
            .set("remeshed_faces", remeshed_faces)
            .set("seconds", r.seconds)
            .set("switches", r.switches);
        std::printf("%s\n", j.dump().c_str());
    } else if (!a.out.quiet) {
        std::printf(
            "tetmesh: %s -> %s: %zu tetrahedra, %zu points, min dihedral %.2f deg, volume %.6g "
            "(surface encloses %.6g) in %.2f s (TetGen -%s)\n",
            a.input.c_str(), a.output.c_str(), r.tetrahedra, r.points, r.min_dihedral_deg, r.volume, r.surface_volume,
            r.seconds, r.switches.c_str());
    }
    return 0;
#else
    (void)a;
    throw InvalidInput("tetmesh: needs a build with TetGen");
#endif
}

}  // namespace

void add_tetmesh_command(CLI::App& app) {
    auto a = std::make_shared<TetmeshArgs>();
    auto* cmd = app.add_subcommand("tetmesh", "tetrahedralize a closed surface with TetGen (AGPL-3.0)");
    cmd->add_option("IN", a->input, "closed, manifold, self-intersection-free surface")->required();
    cmd->add_option("OUT", a->output, "output .mesh (Medit), .vtu (VTK) or .node (+ .ele)")->required();
    TetmeshOptions& o = a->tetmesh;
    cmd->add_option("--quality", o.radius_edge, "radius-edge ratio bound (>= 1)")->capture_default_str();
    cmd->add_option("--edge-length", a->edge_length,
                    "remesh the surface to even triangles of this edge length first (world units; CGAL isotropic "
                    "remeshing): what a surface from extract, smooth or remesh needs for a good minimum angle")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--min-dihedral", o.min_dihedral_deg,
                    "smallest dihedral angle TetGen aims for, degrees (0 = none; tried, not guaranteed)")
        ->check(CLI::Range(0.0, 69.999))
        ->capture_default_str();
    cmd->add_option("--max-dihedral", o.max_dihedral_deg,
                    "largest dihedral angle TetGen's optimiser aims for, degrees (TetGen's own default is 165; the "
                    "slivers at a kept surface sit at 159-167)")
        ->check(CLI::Range(90.001, 179.999))
        ->capture_default_str();
    cmd->add_option("--optimize", o.optimize_level, "TetGen mesh optimisation level 0..9")
        ->check(CLI::Range(0, 9))
        ->capture_default_str();
    cmd->add_option("--max-volume", o.max_volume, "largest tetrahedron volume, world units^3 (0 = none)");
    add_enum_option(cmd, "--surface", o.surface, kSurfaces,
                    "keep: the input triangles are the boundary faces (TetGen -Y); split: TetGen may split them "
                    "to meet the bounds; auto: keep, or split with --max-volume");
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_tetmesh);
}

}  // namespace normalflow::cli
