// One file through a command (run_file.h): the tool's voxelize, extract, smooth and remesh, and batch's files.
#include "pipeline/run_file.h"

#include <string>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "core/stopwatch.h"
#include "io/io.h"
#include "pipeline/pipeline.h"
#include "pipeline/report_json.h"

namespace normalflow {

namespace {

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

void begin(Progress* p, const char* stage) {
    if (p) p->begin(stage);
}

/// A mesh file as read, and the seconds it took.
struct MeshRead {
    Mesh mesh;
    ReadInfo info;
    double seconds = 0;
};

MeshRead read_input(const std::string& input, Progress* p) {
    begin(p, "read");
    Stopwatch clock;
    MeshRead in;
    in.mesh = read_mesh(input, &in.info);
    in.seconds = clock.seconds();
    return in;
}

/// "N triangles", and where the compact default decimated the result, from how many (the line says what was done).
std::string triangles_note(const Mesh& m, const PipelineReport& r) {
    std::string s = std::to_string(m.triangles.size()) + " triangles";
    if (r.compacted)
        s += ", decimated from " + std::to_string(r.decimate.faces_before) + "; --full-density keeps them all";
    return s;
}

/// The "input" object of a mesh file: as read, and what the repair did.
Json mesh_input_json(const std::string& file, const ReadInfo& info, const Mesh& mesh, const PipelineReport& r) {
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

/// run_report_json of a mesh input, with its read seconds in front and the reader's warnings first.
Json mesh_report_json(Command c, const RunOptions& run, const PipelineReport& r, double t_read, const ReadInfo& info) {
    Json j = run_report_json(c, run, r);
    Json sec = Json::object();
    sec.set("read", t_read).set("repair", r.seconds.repair).set("voxelize", r.seconds.voxelize);
    if (r.smoothed) sec.set("smooth", r.seconds.smooth);
    j.set("seconds", sec);
    Json warnings = Json::array(info.warnings);
    for (const auto& w : r.warnings) warnings.push(w);
    j.set("warnings", warnings);
    return j;
}

void write_mesh_result(const std::string& output, const Mesh& m, Progress* progress, FileRun& f,
                       const DracoOptions& draco) {
    Stopwatch clock;
    begin(progress, "write");
    WriteOptions wo;
    wo.glb = GlbEncoding::Draco;  // .glb: KHR_draco_mesh_compression
    wo.draco = draco;
    write_mesh(output, m, wo);
    Json out = to_json(mesh_report(m));
    out.set("file", output).set("vertices", m.positions.size());
    f.report.set("output", out);
    f.report["seconds"].set("write", clock.seconds());
    f.triangles = m.triangles.size();
}

void write_volume_result(const std::string& output, const Volume& v, Progress* progress, FileRun& f,
                         const NormalMap* normals = nullptr) {
    Stopwatch clock;
    begin(progress, "write");
    write_volume(output, v, normals && !(*normals)[0].values.empty() ? normals : nullptr);
    f.report.set("output", Json::object().set("file", output).set("blocks", v.block_count()));
    f.report["seconds"].set("write", clock.seconds());
    f.summary = output + " (the smoothed volume, " + std::to_string(v.block_count()) + " blocks)";
}

/// The notes of an engine that stopped before its last main iteration, or that ran brick by brick.
void stop_notes(const PipelineOptions& opt, const PipelineReport& r, FileRun& f) {
    if (r.bricked)
        f.notes.push_back("the engine ran brick by brick: " + std::to_string(r.bricks.total()) + " bricks of " +
                          std::to_string(r.bricks.brick_voxels) + " voxels with a halo of " +
                          std::to_string(r.bricks.halo_voxels) +
                          (opt.brick_voxels > 0 ? " (--brick-size)"
                                                : ", the whole volume being more than the memory allows (about " +
                                                      format_bytes(r.memory_estimate_bytes) + " in bricks)") +
                          (r.bricks.compact_band ? "; the result's band held in 16 bits between passes to fit" : ""));
    if (r.smooth.stopped_unchanged)
        f.notes.push_back(
            "stopped after main iteration " + std::to_string(r.smooth.iterations_run()) + " of " +
            std::to_string(opt.smooth.iterations > 0 ? opt.smooth.iterations : default_iterations(opt.smooth.mode)) +
            ": its refit kept no step, so the surface no longer changes");
    if (r.smooth.stopped_smooth)
        f.notes.push_back("stopped after main iteration " + std::to_string(r.smooth.iterations_run()) +
                          ": the filtered normal map is smooth at the filter's scale");
    if (r.smooth.stopped_at_checkpoint)
        f.notes.push_back("smoothing stopped after main iteration " + std::to_string(r.smooth.iterations_run()) +
                          ": the mesh is kept on its own faces, which read nothing more of the volume");
}

FileRun voxelize_file(const std::string& input, const std::string& output, const RunOptions& run,
                      const PipelineOptions& opt, Progress* p) {
    if (!is_volume_output_path(output)) throw InvalidInput(output + ": the output must be a .vdb or .nrrd file");
    const MeshRead in = read_input(input, p);
    const Mesh& mesh = in.mesh;
    const ReadInfo& info = in.info;
    const double t_read = in.seconds;
    PipelineReport r;
    const Volume v = naming(input, [&] { return mesh_to_volume(mesh, opt, &r, p); });
    FileRun f;
    f.report = mesh_report_json(Command::Voxelize, run, r, t_read, info);
    f.report.set("input", mesh_input_json(input, info, mesh, r));
    f.report["voxelize"].set("band_half_width", v.half_width).set("memory_bytes", v.memory_bytes());
    Stopwatch clock;
    begin(p, "write");
    write_volume(output, v);
    f.report["seconds"].set("write", clock.seconds());
    f.report.set("output", Json::object().set("file", output));
    f.summary = output + " (" + std::to_string(v.grid.dims[0]) + "x" + std::to_string(v.grid.dims[1]) + "x" +
                std::to_string(v.grid.dims[2]) + " grid, " + std::to_string(v.block_count()) + " blocks)";
    return f;
}

FileRun extract_file(const std::string& input, const std::string& output, const RunOptions& run, PipelineOptions opt,
                     Progress* p) {
    if (mesh_format_from_path(output) == MeshFormat::Unknown)
        throw InvalidInput(output + ": unknown output format (use .ply, .obj, .off, .stl, .glb, .drc)");
    begin(p, "read");
    Stopwatch clock;
    const Volume v = read_volume(input, naming(input, [&] { return volume_input(run); }));
    opt.scan.voxel_size = 0;  // the volume's, resampled by read_volume
    const double t_read = clock.seconds();
    PipelineReport r;
    const Mesh m = naming(input, [&] { return volume_to_mesh(v, opt, &r, p); });
    FileRun f;
    Json& j = f.report;
    j = Json::object();
    j.set("command", "extract").set("extract", to_json(r.extract));
    set_parameters(j, run, Command::Extract, opt, r, v.grid.voxel_size, false);
    if (r.decimated) j.set("decimate", to_json(r.decimate).set("default", r.compacted));
    j.set("seconds",
          Json::object().set("read", t_read).set("extract", r.seconds.extract).set("decimate", r.seconds.decimate));
    j.set("warnings", Json::array(r.warnings));
    write_mesh_result(output, m, p, f, run.draco);
    f.summary = output + " (" + triangles_note(m, r) + ")";
    return f;
}

/// smooth with a volume file in: read (iso, label, resampling, placement), the engine, then the volume or its
/// extracted surface out.
FileRun smooth_volume_file(const std::string& input, const std::string& output, const RunOptions& run,
                           PipelineOptions opt, Progress* p, bool volume_out) {
    const VolumeInput vin = naming(input, [&] { return volume_input(run); });
    opt.scan.voxel_size = 0;
    begin(p, "read");
    Stopwatch clock;
    VolumeReadInfo info;
    Volume v = read_volume(input, vin, &info);
    NormalMap normals;
    const double t_read = clock.lap();
    // The length unit: the file's coarsest spacing (smooth_volume_input's default, the grid's voxels, is the same
    // for isotropic files).
    set_volume_length_scale(opt, info);
    const PipelineResult result = naming(input, [&] {
        return smooth_volume_input(v, opt, p, /*want_mesh=*/!volume_out, run.normal_map ? &normals : nullptr);
    });
    const PipelineReport& r = result.report;
    FileRun f;
    Json& j = f.report;
    j = Json::object();
    j.set("command", "smooth").set("mode", to_string(opt.smooth.mode)).set("input", volume_input_json(input, info, v));
    j.set("smooth", to_json(r.smooth)).set("length_scale", r.length_scale);
    set_parameters(j, run, Command::Smooth, opt, r, v.grid.voxel_size, false);
    if (!volume_out) j.set("extract", to_json(r.extract));
    if (r.decimated) j.set("decimate", to_json(r.decimate));
    Json sec = Json::object();
    sec.set("read", t_read).set("smooth", r.seconds.smooth);
    if (!volume_out) sec.set("extract", r.seconds.extract).set("decimate", r.seconds.decimate);
    j.set("seconds", sec).set("warnings", Json::array(r.warnings));
    stop_notes(opt, r, f);
    if (volume_out) {
        write_volume_result(output, v, p, f, run.normal_map ? &normals : nullptr);
    } else {
        write_mesh_result(output, result.mesh, p, f, run.draco);
        f.summary = output + " (" + triangles_note(result.mesh, r) + ")";
    }
    return f;
}

/// smooth or remesh with a mesh file in.
FileRun mesh_file(Command c, const std::string& input, const std::string& output, const RunOptions& run,
                  const PipelineOptions& opt, Progress* p) {
    const bool volume_out = c == Command::Smooth && is_volume_output_path(output);
    if (!volume_out && mesh_format_from_path(output) == MeshFormat::Unknown)
        throw InvalidInput(output + ": unknown output format (use .ply, .obj, .off, .stl, .glb, .drc" +
                           (c == Command::Smooth ? "; .vdb or .nrrd for the volume)" : ")"));
    if (run.normal_map && !is_vdb_path(output))
        throw InvalidInput(output + ": the normal map is written into a .vdb output");
    if (c == Command::Smooth && is_volume_path(input))
        return smooth_volume_file(input, output, run, opt, p, volume_out);
    naming(input, [&] { refuse_volume_options(run); });
    const MeshRead in = read_input(input, p);
    const Mesh& mesh = in.mesh;
    const ReadInfo& info = in.info;
    const double t_read = in.seconds;
    FileRun f;
    if (volume_out) {  // the smoothed volume itself: scan conversion and the engine, no extraction
        PipelineReport r;
        NormalMap normals;
        const Volume v =
            naming(input, [&] { return smooth_mesh_to_volume(mesh, opt, &r, p, run.normal_map ? &normals : nullptr); });
        f.report = mesh_report_json(c, run, r, t_read, info);
        f.report.set("input", mesh_input_json(input, info, mesh, r));
        stop_notes(opt, r, f);
        write_volume_result(output, v, p, f, &normals);
        return f;
    }
    const PipelineResult result = naming(input, [&] { return smooth_mesh(mesh, opt, p); });
    const PipelineReport& r = result.report;
    f.report = mesh_report_json(c, run, r, t_read, info);
    f.report.set("input", mesh_input_json(input, info, mesh, r));
    f.report["seconds"].set("extract", r.seconds.extract);
    if (r.decimated) f.report["seconds"].set("decimate", r.seconds.decimate);
    stop_notes(opt, r, f);
    write_mesh_result(output, result.mesh, p, f, run.draco);
    f.summary = output + " (" + triangles_note(result.mesh, r) +
                (!r.connectivity_kept ? (r.keep_declined.empty() ? "" : ", re-meshed for " + r.keep_declined)
                 : opt.keep_filter == KeepFilter::Faces ? ", the input's mesh, filtered on its own faces"
                                                        : ", the input's mesh, fitted") +
                ")";
    return f;
}

}  // namespace

FileRun run_file(Command c, const std::string& input, const std::string& output, const RunOptions& run,
                 Progress* progress, std::size_t memory_limit) {
    PipelineOptions opt = pipeline_options(run, c);
    if (memory_limit > 0 && opt.max_memory_bytes == 0) opt.max_memory_bytes = memory_limit;
    validate(opt);
    switch (c) {
        case Command::Voxelize: return voxelize_file(input, output, run, opt, progress);
        case Command::Extract: return extract_file(input, output, run, opt, progress);
        case Command::Smooth:
        case Command::Remesh: return mesh_file(c, input, output, run, opt, progress);
        case Command::Compress: break;
    }
    throw InvalidInput(std::string("run_file: ") + to_string(c) + " is not a pipeline command");
}

}  // namespace normalflow
