// normalflow convert IN OUT [--repair] [--ascii]: read any supported mesh format, write another.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "core/errors.h"
#include "io/io.h"
#ifdef NORMALFLOW_HAS_CGAL
#include "io/cgal/repair.h"
#endif

namespace normalflow::cli {

namespace {

struct ConvertArgs {
    std::string input, output;
    bool repair = false;  ///< merge points, drop degenerate and duplicate faces, orient
    bool ascii = false;   ///< text output where the format has both (PLY, STL)
    OutputFlags out;
};

int run_convert(const ConvertArgs& a) {
    Stopwatch clock;
    if (mesh_format_from_path(a.output) == MeshFormat::Unknown)
        throw InvalidInput("convert: " + a.output + ": unknown output format (use .ply, .obj, .off, .stl, .glb, .drc)");
    ReadInfo info;
    Mesh m = read_mesh(a.input, &info);
    Json j = Json::object();
    j.set("command", "convert").set("input", a.input).set("format", info.format);
    if (a.repair) {
#ifdef NORMALFLOW_HAS_CGAL
        const RepairReport r = repair_mesh(m);
        j.set("repair", Json::object()
                            .set("points_merged", r.points_merged)
                            .set("degenerate_removed", r.degenerate_removed)
                            .set("duplicates_removed", r.duplicates_removed)
                            .set("faces_reversed", r.faces_reversed)
                            .set("warnings", Json::array(r.warnings)));
#else
        throw InvalidInput("convert: --repair needs a build with CGAL");
#endif
    }
    write_mesh(a.output, m, WriteOptions{!a.ascii});
    j.set("output", a.output).set("vertices", m.positions.size()).set("triangles", m.triangles.size());
    j.set("seconds", clock.seconds());
    if (a.out.json)
        std::printf("%s\n", j.dump().c_str());
    else if (!a.out.quiet)
        std::printf("convert: %s -> %s (%zu vertices, %zu triangles)\n", a.input.c_str(), a.output.c_str(),
                    m.positions.size(), m.triangles.size());
    return 0;
}

}  // namespace

void add_convert_command(CLI::App& app) {
    auto a = std::make_shared<ConvertArgs>();
    auto* cmd = app.add_subcommand("convert", "read a mesh in one format and write it in another");
    cmd->add_option("IN", a->input, "mesh file (obj, ply, off, stl, gltf, glb, drc)")->required();
    cmd->add_option("OUT", a->output, "mesh file (ply, obj, off, stl, glb, drc)")->required();
    cmd->add_flag("--repair", a->repair, "merge duplicate points, drop degenerate/duplicate faces, orient (CGAL)");
    cmd->add_flag("--ascii", a->ascii, "text PLY/STL instead of binary");
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_convert);
}

}  // namespace normalflow::cli
