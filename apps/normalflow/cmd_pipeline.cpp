// normalflow voxelize / extract / smooth / remesh: one file through the library's run_file (pipeline/run_file.h:
// read → repair → scan_convert → smooth → extract → decimate → write); the flags come from the options table
// (pipeline/options.h), so every default is the library's.
#include <cstdio>
#include <memory>
#include <string>

#include "cli_options.h"
#include "commands.h"
#include "core/version.h"
#include "pipeline/options.h"
#include "pipeline/run_file.h"

namespace normalflow::cli {

namespace {

/// The files and the options of voxelize, extract, smooth or remesh (the command's RunOptions: default_options).
struct PipelineArgs {
    std::string input, output;
    RunOptions run;
    OutputFlags out;
};

/// The command c on the files: the library's run_file, then the report (--json), the warnings and notes, and a
/// line that says what was written.
int run_command(const PipelineArgs& a, Command c) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    FileRun f = run_file(c, a.input, a.output, a.run, &progress);
    Json& j = f.report;
    j["seconds"].set("total", total.seconds());
    j.set("version", version());
    j.set("peak_memory_bytes", peak_memory_bytes());
    if (a.out.json) std::printf("%s\n", j.dump().c_str());
    for (const std::string& w : j["warnings"].strings()) progress.note("warning: " + w);
    for (const std::string& n : f.notes) progress.note(std::string(to_string(c)) + ": " + n);
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, ", %.1f s", total.seconds());
    std::string line = std::string(to_string(c)) + ": " + f.summary;
    if (c == Command::Smooth && !line.empty() && line.back() == ')') line.insert(line.size() - 1, seconds);
    progress.note(line);
    return 0;
}

int run_voxelize(const PipelineArgs& a) { return run_command(a, Command::Voxelize); }
int run_extract(const PipelineArgs& a) { return run_command(a, Command::Extract); }
int run_smooth(const PipelineArgs& a) { return run_command(a, Command::Smooth); }
int run_remesh(const PipelineArgs& a) { return run_command(a, Command::Remesh); }

}  // namespace

namespace {

/// Registers cmd's files and options (the table's, cli_options.h) to run fn.
void add_pipeline_command(CLI::App* cmd, Command c, const char* in, const char* out, int (*fn)(const PipelineArgs&)) {
    auto a = std::make_shared<PipelineArgs>();
    a->run = default_options(c);
    cmd->add_option("IN", a->input, in)->required();
    cmd->add_option("OUT", a->output, out)->required();
    add_run_options(cmd, a->run, c, a->out);
    on_run(cmd, a, fn);
}

}  // namespace

void add_voxelize_command(CLI::App& app) {
    add_pipeline_command(
        app.add_subcommand("voxelize", "scan-convert a mesh into a narrow-band signed distance volume"),
        Command::Voxelize, "mesh file (obj, ply, off, stl, gltf, glb, drc)", "volume file (.vdb or .nrrd)",
        run_voxelize);
}

void add_extract_command(CLI::App& app) {
    add_pipeline_command(
        app.add_subcommand("extract", "extract the zero level set of a volume as a closed manifold mesh"),
        Command::Extract, "volume file (.vdb, .nrrd, .nhdr, .nii, .nii.gz)", "mesh file (ply, obj, off, stl, glb, drc)",
        run_extract);
}

void add_remesh_command(CLI::App& app) {
    add_pipeline_command(
        app.add_subcommand(
            "remesh", "re-mesh any mesh as a closed manifold surface through its volume, creases and corners kept"),
        Command::Remesh, "mesh file (obj, ply, off, stl, gltf, glb, drc)", "mesh file (ply, obj, off, stl, glb, drc)",
        run_remesh);
}

void add_smooth_command(CLI::App& app) {
    add_pipeline_command(
        app.add_subcommand("smooth", "voxelize, filter the normal map and refit, extract (the whole pipeline)"),
        Command::Smooth, "mesh file (obj, ply, off, stl, gltf, glb, drc) or volume file (vdb, nrrd, nhdr, nii, nii.gz)",
        "mesh file (ply, obj, off, stl, glb, drc) or volume file (vdb, nrrd)", run_smooth);
}

}  // namespace normalflow::cli
