// normalflow voxelize / extract / smooth: the pipeline read → repair → scan_convert → smooth → extract →
// write. The stages between read and write are the library's smooth_mesh (pipeline/pipeline.h);
// the flags parse straight into its PipelineOptions, so every default is the library's.
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "cli_options.h"
#include "commands.h"
#include "core/errors.h"
#include "core/mesh_report.h"
#include "core/version.h"
#include "io/io.h"
#include "pipeline/options.h"
#include "pipeline/pipeline.h"
#include "pipeline/report_json.h"

namespace normalflow::cli {

namespace {

/// "N triangles", and where the compact default decimated the result, from how many (the line says what was done).
std::string triangles_note(const Mesh& m, const PipelineReport& r) {
    std::string s = std::to_string(m.triangles.size()) + " triangles";
    if (r.compacted)
        s += ", decimated from " + std::to_string(r.decimate.faces_before) + "; --full-density keeps them all";
    return s;
}

}  // namespace

namespace {

/// The files and the options of voxelize, extract, smooth or remesh (the command's RunOptions: default_options).
struct PipelineArgs {
    std::string input, output;
    RunOptions run;
    OutputFlags out;
};

/// The "input" object of a volume file.
Json volume_input_json(const std::string& file, const VolumeReadInfo& info, const Volume& v) {
    Json in = Json::object();
    in.set("file", file)
        .set("format", info.format)
        .set("dims", Json::array(std::vector<int>(info.dims.begin(), info.dims.end())))
        .set("spacing", Json::array(std::vector<double>(info.spacing.begin(), info.spacing.end())))
        .set("surface", info.surface)
        .set("resampled", info.resampled)
        .set("placed", info.placed);
    Json grid = Json::object();
    grid.set("dims", Json::array(std::vector<int>(v.grid.dims.begin(), v.grid.dims.end())))
        .set("voxel_size", v.grid.voxel_size)
        .set("blocks", v.block_count());
    in.set("grid", grid);
    return in;
}

/// Writes a volume, timed into j["seconds"]["write"], and j["output"].
void write_volume_result(const std::string& output, const Volume& v, TerminalProgress& progress, Json& j,
                         const NormalMap* normals = nullptr) {
    Stopwatch clock;
    progress.begin("write");
    write_volume(output, v, normals && !(*normals)[0].values.empty() ? normals : nullptr);
    j.set("output", Json::object().set("file", output).set("blocks", v.block_count()));
    j["seconds"].set("write", clock.seconds());
}

/// Runs f; a library error that does not name the file yet gets `file: ` in front.
template <class F>
auto naming(const std::string& file, F&& f) {
    const auto prefix = [&](const char* what) {
        const std::string w(what);
        return w.rfind(file, 0) == 0 ? w : file + ": " + w;
    };
    try {
        return f();
    } catch (const InvalidInput& e) {
        throw InvalidInput(prefix(e.what()));
    } catch (const OutOfMemory& e) {
        throw OutOfMemory(prefix(e.what()));
    }
}

/// The "input" object: the file as read, and what the repair did (as before the library's report).
Json input_json(const std::string& file, const ReadInfo& info, const Mesh& mesh, const PipelineReport& r) {
    Json in = Json::object();
    in.set("file", file)
        .set("format", info.format)
        .set("vertices", mesh.positions.size())
        .set("triangles", mesh.triangles.size());
    if (r.repaired)
        in.set("points_merged", r.repair.points_merged)
            .set("degenerate_removed", r.repair.degenerate_removed)
            .set("duplicates_removed", r.repair.duplicates_removed)
            .set("faces_reversed", r.repair.faces_reversed);
    return in;
}

/// The run's report (run_report_json, the shape batch and Python share), the tool's read seconds in front and the
/// read warnings first.
Json report_json(Command c, const RunOptions& run, const PipelineReport& r, double t_read, const ReadInfo* info) {
    Json j = run_report_json(c, run, r);
    Json sec = Json::object();
    sec.set("read", t_read).set("repair", r.seconds.repair).set("voxelize", r.seconds.voxelize);
    if (r.smoothed) sec.set("smooth", r.seconds.smooth);
    j.set("seconds", sec);
    Json warnings = Json::array(info ? info->warnings : std::vector<std::string>{});
    for (const auto& w : r.warnings) warnings.push(w);
    j.set("warnings", warnings);
    return j;
}

void write_result(const std::string& output, const Mesh& m, TerminalProgress& progress, Json& j,
                  const DracoOptions& draco = {}) {
    Stopwatch clock;
    progress.begin("write");
    WriteOptions wo;
    wo.glb = GlbEncoding::Draco;  // .glb: KHR_draco_mesh_compression
    wo.draco = draco;
    write_mesh(output, m, wo);
    Json out = to_json(mesh_report(m));
    out.set("file", output).set("vertices", m.positions.size());
    j.set("output", out);
    j["seconds"].set("write", clock.seconds());
}

void finish(Json& j, const OutputFlags& f, const Stopwatch& total, TerminalProgress& progress) {
    j["seconds"].set("total", total.seconds());
    j.set("version", version());
    j.set("peak_memory_bytes", peak_memory_bytes());
    if (f.json) std::printf("%s\n", j.dump().c_str());
    for (const std::string& w : j["warnings"].strings()) progress.note("warning: " + w);
}

int run_voxelize(const PipelineArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    if (!is_volume_output_path(a.output))
        throw InvalidInput("voxelize: " + a.output + ": the output must be a .vdb or .nrrd file");
    const PipelineOptions opt = pipeline_options(a.run, Command::Voxelize);
    progress.begin("read");
    Stopwatch clock;
    ReadInfo info;
    const Mesh mesh = read_mesh(a.input, &info);
    const double t_read = clock.lap();
    PipelineReport r;
    const Volume v = naming(a.input, [&] { return mesh_to_volume(mesh, opt, &r, &progress); });
    Json j = report_json(Command::Voxelize, a.run, r, t_read, &info);
    j.set("input", input_json(a.input, info, mesh, r));
    j["voxelize"].set("band_half_width", v.half_width).set("memory_bytes", v.memory_bytes());
    clock.lap();
    progress.begin("write");
    write_volume(a.output, v);
    j["seconds"].set("write", clock.seconds());
    j.set("output", Json::object().set("file", a.output));
    finish(j, a.out, total, progress);
    progress.note("voxelize: " + a.output + " (" + std::to_string(v.grid.dims[0]) + "x" +
                  std::to_string(v.grid.dims[1]) + "x" + std::to_string(v.grid.dims[2]) + " grid, " +
                  std::to_string(v.block_count()) + " blocks)");
    return 0;
}

int run_extract(const PipelineArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    progress.begin("read");
    Stopwatch clock;
    PipelineOptions opt = pipeline_options(a.run, Command::Extract);
    const Volume v = read_volume(a.input, volume_input(a.run));
    opt.scan.voxel_size = 0;  // the volume's, resampled by read_volume
    const double t_read = clock.seconds();
    PipelineReport r;
    const Mesh m = naming(a.input, [&] { return volume_to_mesh(v, opt, &r, &progress); });
    Json j = Json::object();
    j.set("command", "extract").set("extract", to_json(r.extract));
    set_parameters(j, a.run, Command::Extract, opt, r, v.grid.voxel_size, false);
    if (r.decimated) j.set("decimate", to_json(r.decimate).set("default", r.compacted));
    j.set("seconds",
          Json::object().set("read", t_read).set("extract", r.seconds.extract).set("decimate", r.seconds.decimate));
    j.set("warnings", Json::array(r.warnings));
    write_result(a.output, m, progress, j);
    finish(j, a.out, total, progress);
    progress.note("extract: " + a.output + " (" + triangles_note(m, r) + ")");
    return 0;
}

/// smooth with a volume file in: read (iso, label, resampling, placement), the engine, then the volume or
/// its extracted surface out.
int run_smooth_volume(const PipelineArgs& a, PipelineOptions opt, bool volume_out, const Stopwatch& total,
                      TerminalProgress& progress) {
    const VolumeInput vin = naming(a.input, [&] { return volume_input(a.run); });
    opt.scan.voxel_size = 0;
    progress.begin("read");
    Stopwatch clock;
    VolumeReadInfo info;
    Volume v = read_volume(a.input, vin, &info);
    NormalMap normals;
    const double t_read = clock.lap();
    // The length unit: the file's coarsest spacing (smooth_volume_input's default, the grid's voxels, is the same
    // for isotropic files).
    set_volume_length_scale(opt, info);
    const PipelineResult result = naming(a.input, [&] {
        return smooth_volume_input(v, opt, &progress, /*want_mesh=*/!volume_out, a.run.normal_map ? &normals : nullptr);
    });
    const PipelineReport& r = result.report;
    Json j = Json::object();
    j.set("command", "smooth")
        .set("mode", to_string(opt.smooth.mode))
        .set("input", volume_input_json(a.input, info, v));
    j.set("smooth", to_json(r.smooth)).set("length_scale", r.length_scale);
    set_parameters(j, a.run, Command::Smooth, opt, r, v.grid.voxel_size, false);
    if (!volume_out) j.set("extract", to_json(r.extract));
    if (r.decimated) j.set("decimate", to_json(r.decimate));
    Json sec = Json::object();
    sec.set("read", t_read).set("smooth", r.seconds.smooth);
    if (!volume_out) sec.set("extract", r.seconds.extract).set("decimate", r.seconds.decimate);
    j.set("seconds", sec).set("warnings", Json::array(r.warnings));
    if (volume_out) {
        write_volume_result(a.output, v, progress, j, a.run.normal_map ? &normals : nullptr);
    } else {
        write_result(a.output, result.mesh, progress, j, a.run.draco);
    }
    finish(j, a.out, total, progress);
    progress.note("smooth: " + a.output + " (" +
                  (volume_out ? "the smoothed volume, " + std::to_string(v.block_count()) + " blocks"
                              : triangles_note(result.mesh, r)) +
                  ")");
    return 0;
}

int run_smooth(const PipelineArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    const PipelineOptions opt = pipeline_options(a.run, Command::Smooth);
    validate(opt);
    // Fail on a bad output path before the long computation.
    const bool volume_out = is_volume_output_path(a.output);
    if (!volume_out && mesh_format_from_path(a.output) == MeshFormat::Unknown)
        throw InvalidInput(
            "smooth: " + a.output +
            ": unknown output format (use .ply, .obj, .off, .stl, .glb, .drc; .vdb or .nrrd for the volume)");
    if (a.run.normal_map && !is_vdb_path(a.output))
        throw InvalidInput("smooth: " + a.output + ": --normal-map is written into a .vdb output");
    if (is_volume_path(a.input)) return run_smooth_volume(a, opt, volume_out, total, progress);
    naming(a.input, [&] { refuse_volume_options(a.run); });
    progress.begin("read");
    Stopwatch clock;
    ReadInfo info;
    const Mesh mesh = read_mesh(a.input, &info);
    const double t_read = clock.lap();
    if (volume_out) {
        // the smoothed volume itself: scan conversion and the engine, no extraction
        PipelineReport r;
        NormalMap normals;
        Volume v = naming(a.input, [&] { return mesh_to_volume(mesh, opt, &r, &progress); });
        naming(a.input, [&] {
            smooth_volume_stage(v, opt, model_length_scale(mesh), &r, &progress, a.run.normal_map ? &normals : nullptr);
        });
        Json j = report_json(Command::Smooth, a.run, r, t_read, &info);
        j.set("input", input_json(a.input, info, mesh, r));
        write_volume_result(a.output, v, progress, j, &normals);
        finish(j, a.out, total, progress);
        progress.note("smooth: " + a.output + " (the smoothed volume, " + std::to_string(v.block_count()) + " blocks)");
        return 0;
    }
    const PipelineResult result = naming(a.input, [&] { return smooth_mesh(mesh, opt, &progress); });
    const PipelineReport& r = result.report;
    const Mesh& m = result.mesh;
    Json j = report_json(Command::Smooth, a.run, r, t_read, &info);
    j.set("input", input_json(a.input, info, mesh, r));
    j["seconds"].set("extract", r.seconds.extract);
    if (r.decimated) j["seconds"].set("decimate", r.seconds.decimate);
    if (r.smooth.stopped_unchanged)
        progress.note(
            "smooth: stopped after main iteration " + std::to_string(r.smooth.iterations_run()) + " of " +
            std::to_string(opt.smooth.iterations > 0 ? opt.smooth.iterations : default_iterations(opt.smooth.mode)) +
            ": its refit kept no step, so the surface no longer changes");
    if (r.smooth.stopped_smooth)
        progress.note("smooth: stopped after main iteration " + std::to_string(r.smooth.iterations_run()) +
                      ": the filtered normal map is smooth at the filter's scale");
    write_result(a.output, m, progress, j, a.run.draco);
    finish(j, a.out, total, progress);
    progress.note("smooth: " + a.output + " (" + triangles_note(m, r) + ", " +
                  (r.connectivity_kept ? "the input's mesh, fitted, " : "") +
                  std::to_string(int(total.seconds() * 10) / 10.0).substr(0, 5) + " s)");
    return 0;
}

int run_remesh(const PipelineArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    const PipelineOptions opt = pipeline_options(a.run, Command::Remesh);
    validate(opt);
    if (mesh_format_from_path(a.output) == MeshFormat::Unknown)
        throw InvalidInput("remesh: " + a.output + ": unknown output format (use .ply, .obj, .off, .stl, .glb, .drc)");
    progress.begin("read");
    Stopwatch clock;
    ReadInfo info;
    const Mesh mesh = read_mesh(a.input, &info);
    const double t_read = clock.lap();
    const PipelineResult result = naming(a.input, [&] { return smooth_mesh(mesh, opt, &progress); });
    const PipelineReport& r = result.report;
    Json j = report_json(Command::Remesh, a.run, r, t_read, &info);
    j.set("input", input_json(a.input, info, mesh, r));
    j["seconds"].set("extract", r.seconds.extract);
    if (r.decimated) j["seconds"].set("decimate", r.seconds.decimate);
    write_result(a.output, result.mesh, progress, j, a.run.draco);
    finish(j, a.out, total, progress);
    progress.note("remesh: " + a.output + " (" + triangles_note(result.mesh, r) + ")");
    return 0;
}

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
