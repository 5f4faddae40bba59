// normalflow voxelize / extract / smooth: the pipeline read → repair → scan_convert → smooth → extract →
// write. The stages between read and write are the library's smooth_mesh (io/pipeline/pipeline.h);
// the flags parse straight into its PipelineOptions, so every default is the library's.
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "commands.h"
#include "core/errors.h"
#include "core/mesh_report.h"
#include "io/io.h"
#include "io/pipeline/pipeline.h"
#include "io/pipeline/report_json.h"

namespace normalflow::cli {

namespace {

struct VoxelizeArgs {
    std::string input, output;
    PipelineOptions pipeline;
    OutputFlags out;
};

struct ExtractArgs {
    std::string input, output;
    PipelineOptions pipeline;  ///< its decimation options; extraction runs without smoothing
    VolumeInput volume;        ///< how a dense volume file's values are read
    OutputFlags out;
};

struct SmoothArgs {
    std::string input, output;
    PipelineOptions pipeline;
    VolumeInput volume;                ///< how a dense volume file's values are read (a volume input)
    bool normal_map = false;           ///< a .vdb output also holds the filtered normal map
    DracoOptions draco;                ///< quantization and level for .drc / .glb outputs
    OutputFlags out;
};

/// Flags of voxelize and smooth, straight into PipelineOptions (its defaults are the help's).
void add_grid_options(CLI::App* cmd, PipelineOptions& p) {
    auto* res = cmd->add_option("--resolution", p.scan.resolution,
                                p.scan.resolution == 0
                                    ? "voxels along the longest bounding-box side (default: automatic, 5 per median "
                                      "edge length of the input, 128 to 512, within the memory available)"
                                    : "voxels along the longest bounding-box side")
                    ->check(CLI::Range(8, 8192));
    if (p.scan.resolution != 0) res->capture_default_str();
    cmd->add_option("--voxel-size", p.scan.voxel_size, "voxel size in world units (overrides --resolution; a volume input is resampled to it)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--shell", p.scan.shell_thickness,
                    "process an open sheet as a shell of this thickness (world units)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_flag("!--no-repair", p.repair, "do not merge points, drop degenerate faces and orient first");
    std::map<std::string, DistanceQuery> queries;
    for (DistanceQuery q : {DistanceQuery::EngineBvh, DistanceQuery::CgalAabb}) queries[to_string(q)] = q;
    add_enum_option(cmd, "--distance", p.distance, queries,
                    "closest-triangle search: bvh (the engine's) or aabb (CGAL's AABB tree); same distances");
    cmd->add_option("--max-memory", p.max_memory_bytes,
                    "refuse a run estimated to need more than this (e.g. 4G; default: the memory available)")
        ->transform(CLI::Validator(
            [](std::string& s) {
                try {
                    s = std::to_string(parse_bytes(s, "--max-memory"));
                    return std::string();
                } catch (const InvalidInput& e) {  // CLI11 puts the flag's name in front itself
                    const std::string m = e.what();
                    return m.substr(m.find(": ") + 2);
                }
            },
            "SIZE"));
    cmd->add_option("--threads", p.scan.threads, "worker threads (0: all cores); results do not depend on it")
        ->check(CLI::NonNegativeNumber);
}

/// --iso, --label, --negate (and --voxel-size for extract): how a dense volume file's values are read.
void add_volume_input_options(CLI::App* cmd, VolumeInput& v, bool voxel_size) {
    cmd->add_option("--iso", v.iso,
                    "volume input: a scalar image (CT, MRI, probability): the surface where the value is V, inside "
                    "where it is above");
    cmd->add_option("--label", v.label, "volume input: a label map: the surface of the voxels labelled L");
    cmd->add_flag("--negate", v.negate,
                  "volume input: flip the inside (with --iso: below V; a signed distance: positive inside)");
    if (voxel_size)
        cmd->add_option("--voxel-size", v.voxel_size,
                        "volume input: resample to this voxel size (world units; default: the smallest spacing)")
            ->check(CLI::PositiveNumber);
}

/// The "input" object of a volume file.
Json volume_input_json(const std::string& file, const VolumeReadInfo& info, const Volume& v) {
    Json in = Json::object();
    in.set("file", file).set("format", info.format)
        .set("dims", Json::array(std::vector<int>(info.dims.begin(), info.dims.end())))
        .set("spacing", Json::array(std::vector<double>(info.spacing.begin(), info.spacing.end())))
        .set("surface", info.surface).set("resampled", info.resampled).set("placed", info.placed);
    Json grid = Json::object();
    grid.set("dims", Json::array(std::vector<int>(v.grid.dims.begin(), v.grid.dims.end())))
        .set("voxel_size", v.grid.voxel_size).set("blocks", v.block_count());
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
    in.set("file", file).set("format", info.format).set("vertices", mesh.positions.size())
        .set("triangles", mesh.triangles.size());
    if (r.repaired)
        in.set("points_merged", r.repair.points_merged).set("degenerate_removed", r.repair.degenerate_removed)
            .set("duplicates_removed", r.repair.duplicates_removed).set("faces_reversed", r.repair.faces_reversed);
    return in;
}

/// The pipeline report's keys, the tool's read seconds in front and the read warnings first.
Json report_json(const char* command, const PipelineReport& r, double t_read, const ReadInfo* info) {
    Json j = to_json(r);
    j.set("command", command);
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
    j.set("peak_memory_bytes", peak_memory_bytes());
    if (f.json) std::printf("%s\n", j.dump().c_str());
    for (const std::string& w : j["warnings"].strings()) progress.note("warning: " + w);
}

int run_voxelize(const VoxelizeArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    if (!is_volume_output_path(a.output))
        throw InvalidInput("voxelize: " + a.output + ": the output must be a .vdb or .nrrd file");
    PipelineOptions opt = a.pipeline;
    opt.smoothing = false;
    progress.begin("read");
    Stopwatch clock;
    ReadInfo info;
    const Mesh mesh = read_mesh(a.input, &info);
    const double t_read = clock.lap();
    PipelineReport r;
    const Volume v = naming(a.input, [&] { return mesh_to_volume(mesh, opt, &r, &progress); });
    Json j = report_json("voxelize", r, t_read, &info);
    j.set("input", input_json(a.input, info, mesh, r));
    j["voxelize"].set("band_half_width", v.half_width).set("memory_bytes", v.memory_bytes());
    clock.lap();
    progress.begin("write");
    write_volume(a.output, v);
    j["seconds"].set("write", clock.seconds());
    j.set("output", Json::object().set("file", a.output));
    finish(j, a.out, total, progress);
    progress.note("voxelize: " + a.output + " (" + std::to_string(v.grid.dims[0]) + "x" + std::to_string(v.grid.dims[1]) +
                  "x" + std::to_string(v.grid.dims[2]) + " grid, " + std::to_string(v.block_count()) + " blocks)");
    return 0;
}

int run_extract(const ExtractArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    progress.begin("read");
    Stopwatch clock;
    const Volume v = read_volume(a.input, a.volume);
    const double t_read = clock.seconds();
    PipelineOptions opt = a.pipeline;
    opt.smoothing = false;
    PipelineReport r;
    const Mesh m = naming(a.input, [&] { return volume_to_mesh(v, opt, &r, &progress); });
    Json j = Json::object();
    j.set("command", "extract").set("extract", to_json(r.extract));
    if (r.decimated) j.set("decimate", to_json(r.decimate));
    j.set("seconds", Json::object().set("read", t_read).set("extract", r.seconds.extract).set("decimate", r.seconds.decimate));
    j.set("warnings", Json::array(r.warnings));
    write_result(a.output, m, progress, j);
    finish(j, a.out, total, progress);
    progress.note("extract: " + a.output + " (" + std::to_string(m.triangles.size()) + " triangles)");
    return 0;
}

/// smooth with a volume file in: read (iso, label, resampling, placement), the engine, then the volume or
/// its extracted surface out.
int run_smooth_volume(const SmoothArgs& a, PipelineOptions opt, bool volume_out, const Stopwatch& total,
                      TerminalProgress& progress) {
    if (opt.scan.resolution != 0)
        throw InvalidInput("smooth: " + a.input +
                           ": --resolution applies to a mesh input; a volume keeps its grid (--voxel-size resamples it)");
    VolumeInput vin = a.volume;
    vin.voxel_size = opt.scan.voxel_size;
    opt.scan.voxel_size = 0;
    progress.begin("read");
    Stopwatch clock;
    VolumeReadInfo info;
    Volume v = read_volume(a.input, vin, &info);
    NormalMap normals;
    const double t_read = clock.lap();
    // The length unit: kVolumeLengthScaleVoxels of the file's coarsest spacing, the scale of its staircase
    // (smooth_volume_input's default, the grid's voxels, is the same for isotropic files).
    if (opt.length_scale == 0 && opt.smooth.length_scale == 0)
        opt.length_scale = kVolumeLengthScaleVoxels * std::max({info.spacing[0], info.spacing[1], info.spacing[2]});
    const PipelineResult result =
        naming(a.input, [&] { return smooth_volume_input(v, opt, &progress, /*want_mesh=*/!volume_out,
                                                         a.normal_map ? &normals : nullptr); });
    const PipelineReport& r = result.report;
    Json j = Json::object();
    j.set("command", "smooth").set("mode", to_string(opt.smooth.mode)).set("input", volume_input_json(a.input, info, v));
    j.set("smooth", to_json(r.smooth)).set("length_scale", r.length_scale);
    if (!volume_out) j.set("extract", to_json(r.extract));
    if (r.decimated) j.set("decimate", to_json(r.decimate));
    Json sec = Json::object();
    sec.set("read", t_read).set("smooth", r.seconds.smooth);
    if (!volume_out) sec.set("extract", r.seconds.extract).set("decimate", r.seconds.decimate);
    j.set("seconds", sec).set("warnings", Json::array(r.warnings));
    if (volume_out) {
        write_volume_result(a.output, v, progress, j, a.normal_map ? &normals : nullptr);
    } else {
        write_result(a.output, result.mesh, progress, j, a.draco);
    }
    finish(j, a.out, total, progress);
    progress.note("smooth: " + a.output + " (" +
                  (volume_out ? "the smoothed volume, " + std::to_string(v.block_count()) + " blocks"
                              : std::to_string(result.mesh.triangles.size()) + " triangles") +
                  ")");
    return 0;
}

int run_smooth(const SmoothArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    PipelineOptions opt = a.pipeline;
    opt.smoothing = true;
    opt.smooth.threads = opt.scan.threads;  // --threads sets both stages
    validate(opt);
    // Fail on a bad output path before the long computation.
    const bool volume_out = is_volume_output_path(a.output);
    if (!volume_out && mesh_format_from_path(a.output) == MeshFormat::Unknown)
        throw InvalidInput("smooth: " + a.output +
                           ": unknown output format (use .ply, .obj, .off, .stl, .glb, .drc; .vdb or .nrrd for the volume)");
    if (a.normal_map && !is_vdb_path(a.output))
        throw InvalidInput("smooth: " + a.output + ": --normal-map is written into a .vdb output");
    if (is_volume_path(a.input)) return run_smooth_volume(a, opt, volume_out, total, progress);
    if (a.volume.iso || a.volume.label || a.volume.negate)
        throw InvalidInput("smooth: " + a.input + ": --iso, --label and --negate apply to a volume input");
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
            smooth_volume_stage(v, opt, model_length_scale(mesh), &r, &progress, a.normal_map ? &normals : nullptr);
        });
        Json j = report_json("smooth", r, t_read, &info);
        j.set("mode", to_string(opt.smooth.mode)).set("input", input_json(a.input, info, mesh, r));
        write_volume_result(a.output, v, progress, j, &normals);
        finish(j, a.out, total, progress);
        progress.note("smooth: " + a.output + " (the smoothed volume, " + std::to_string(v.block_count()) + " blocks)");
        return 0;
    }
    const PipelineResult result = naming(a.input, [&] { return smooth_mesh(mesh, opt, &progress); });
    const PipelineReport& r = result.report;
    const Mesh& m = result.mesh;
    Json j = report_json("smooth", r, t_read, &info);
    j.set("mode", to_string(opt.smooth.mode)).set("input", input_json(a.input, info, mesh, r));
    j["seconds"].set("extract", r.seconds.extract);
    if (r.decimated) j["seconds"].set("decimate", r.seconds.decimate);
    if (r.smooth.stopped_unchanged)
        progress.note("smooth: stopped after main iteration " + std::to_string(r.smooth.iterations_run()) + " of " +
                      std::to_string(opt.smooth.iterations > 0 ? opt.smooth.iterations
                                                               : default_iterations(opt.smooth.mode)) +
                      ": its refit kept no step, so the surface no longer changes");
    if (r.smooth.stopped_smooth)
        progress.note("smooth: stopped after main iteration " + std::to_string(r.smooth.iterations_run()) +
                      ": the filtered normal map is smooth at the filter's scale");
    write_result(a.output, m, progress, j, a.draco);
    finish(j, a.out, total, progress);
    progress.note("smooth: " + a.output + " (" + std::to_string(m.triangles.size()) + " triangles, " +
                  (r.connectivity_kept ? "the input's mesh, fitted, " : "") +
                  std::to_string(int(total.seconds() * 10) / 10.0).substr(0, 5) + " s)");
    return 0;
}

}  // namespace

/// --target-faces, --max-error and --decimator: the decimation of a re-meshed result (volume_to_mesh).
void add_decimation_options(CLI::App* cmd, PipelineOptions& p) {
    cmd->add_option("--target-faces", p.target_faces,
                    "decimate the result to at most N faces (quadric edge collapse, checked; see --decimator)")
        ->check(CLI::Range(std::size_t(4), std::size_t(1) << 40));
    cmd->add_option("--max-error", p.max_error,
                    "decimate the result while each collapse stays within E (world units) of the surface's tangent "
                    "planes: an adaptive mesh, coarse where flat (with --target-faces, whichever stops first)")
        ->check(CLI::PositiveNumber);
    add_decimator_option(cmd, p.decimator);
}

void add_voxelize_command(CLI::App& app) {
    auto a = std::make_shared<VoxelizeArgs>();
    auto* cmd = app.add_subcommand("voxelize", "scan-convert a mesh into a narrow-band signed distance volume");
    cmd->add_option("IN", a->input, "mesh file (obj, ply, off, stl, gltf, glb, drc)")->required();
    cmd->add_option("OUT", a->output, "volume file (.vdb or .nrrd)")->required();
    add_grid_options(cmd, a->pipeline);
    cmd->add_option("--band", a->pipeline.scan.half_width, "band half-width in voxels")
        ->check(CLI::Range(1.0, 64.0))->capture_default_str();
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_voxelize);
}

void add_extract_command(CLI::App& app) {
    auto a = std::make_shared<ExtractArgs>();
    auto* cmd = app.add_subcommand("extract", "extract the zero level set of a volume as a closed manifold mesh");
    cmd->add_option("IN", a->input, "volume file (.vdb, .nrrd, .nhdr, .nii, .nii.gz)")->required();
    cmd->add_option("OUT", a->output, "mesh file (ply, obj, off, stl, glb, drc)")->required();
    add_volume_input_options(cmd, a->volume, /*voxel_size=*/true);
    add_decimation_options(cmd, a->pipeline);
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_extract);
}

void add_smooth_command(CLI::App& app) {
    auto a = std::make_shared<SmoothArgs>();
    SmoothOptions& s = a->pipeline.smooth;
    auto* cmd = app.add_subcommand("smooth", "voxelize, filter the normal map and refit, extract (the whole pipeline)");
    cmd->add_option("IN", a->input,
                    "mesh file (obj, ply, off, stl, gltf, glb, drc) or volume file (vdb, nrrd, nhdr, nii, nii.gz)")
        ->required();
    cmd->add_option("OUT", a->output, "mesh file (ply, obj, off, stl, glb, drc) or volume file (vdb, nrrd)")->required();
    add_grid_options(cmd, a->pipeline);
    add_volume_input_options(cmd, a->volume, /*voxel_size=*/false);
    std::map<std::string, SmoothMode> modes;
    for (SmoothMode m : {SmoothMode::Isotropic, SmoothMode::Anisotropic, SmoothMode::HighBoost, SmoothMode::MeanCurvature,
                         SmoothMode::Bilateral, SmoothMode::Guided, SmoothMode::TotalVariation})
        modes[to_string(m)] = m;
    add_enum_option(cmd, "--mode", s.mode, modes, "bilateral | guided | tv | anisotropic | isotropic | highboost | mcf");
    cmd->add_option("--iterations", s.iterations,
                    "main iterations (normal loop + refit); default: " +
                        std::to_string(default_iterations(SmoothMode::Anisotropic)) + " for anisotropic, " +
                        std::to_string(default_iterations(SmoothMode::Isotropic)) + " for the other modes")
        ->check(CLI::Range(1, 10000));
    cmd->add_option("--normal-steps", s.normal_steps,
                    "normal-loop steps (bilateral, guided: filter passes; tv: solver iterations) per main iteration; "
                    "default: " +
                        std::to_string(default_normal_steps(SmoothMode::Anisotropic)) + ", " +
                        std::to_string(default_normal_steps(SmoothMode::Bilateral)) + " for bilateral and guided, " +
                        std::to_string(default_normal_steps(SmoothMode::TotalVariation)) + " for tv")
        ->check(CLI::Range(1, 10000));
    cmd->add_option("--length-scale", a->pipeline.length_scale,
                    "bilateral, guided, tv: the model's length unit in world units (default: the input's median edge length)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--sigma-spatial", s.sigma_spatial, "bilateral, guided: spatial sigma in length units")
        ->check(CLI::PositiveNumber)->capture_default_str();
    cmd->add_option("--sigma-range", s.sigma_range, "bilateral, guided: range sigma on the normals' chord")
        ->check(CLI::PositiveNumber)->capture_default_str();
    cmd->add_option("--tv-lambda", s.tv_lambda,
                    "tv: the fidelity's length in length units (larger: flatter, removes larger patches)")
        ->check(CLI::PositiveNumber)->capture_default_str();
    cmd->add_option("--mu", s.mu, "anisotropic conductance scale, 1/voxel")->check(CLI::PositiveNumber)->capture_default_str();
    cmd->add_option("--alpha", s.alpha, "high-boost amount")->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--presmooth", s.conductance_presmooth_steps,
                    "anisotropic: isotropic steps that regularise the conductance (0: the paper's raw g)")
        ->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--mu-robust", s.mu_robust,
                    "anisotropic: raise mu to C times the robust noise scale of the curvature (0: the fixed mu)")
        ->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--refit-steps", s.refit_max_steps,
                    "refit steps per main iteration at most (default: 40; bilateral, guided, tv: a refit time of 1.4 length units squared)")
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--refit-tolerance", s.refit_tolerance,
                    "the refit stops when D falls by less than this fraction of itself in a step")
        ->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--refit-super-steps", s.refit_super_steps,
                    "bilateral, guided, tv: cover the refit time in this many Runge-Kutta-Legendre super steps (0: explicit steps of --refit-dt)")
        ->check(CLI::Range(0, 100000))->capture_default_str();
    cmd->add_flag("--extend-by-gather", s.extend_by_gather,
                  "bilateral, guided, tv: carry the filtered normals off the surface by a filter pass at each closest point (slower; the default before 0.2)");
    cmd->add_flag("!--all-samples", s.thin_samples,
                  "bilateral, guided: filter every shell sample, also where the grid is finer than 5 voxels per length unit (slower; the default before 0.2)");
    cmd->add_option("--refit-dt", s.refit_dt, "refit time step, voxel² (at most 1/6)")
        ->check(CLI::PositiveNumber)->capture_default_str();
    cmd->add_flag("!--no-preserve-volume", s.preserve_volume,
                  "bilateral, guided, tv: do not shift the surface back to the volume it had before each refit");
    cmd->add_flag("--second-order", s.second_order_term, "add Appendix A's second term (Eq. 39) to the refit");
    const std::map<std::string, Connectivity> connectivity = {
        {"auto", Connectivity::Auto}, {"keep", Connectivity::Keep}, {"remesh", Connectivity::Remesh}};
    add_enum_option(cmd, "--connectivity", a->pipeline.connectivity, connectivity,
                    "keep: the input's own mesh, its vertices moved onto the result; remesh: a new mesh "
                    "extracted from it (open where the input is open, see --closed); auto (default): keep for an "
                    "open input, remesh for a closed one");
    cmd->add_flag("--fit-to-normal-map", a->pipeline.fit_to_normal_map,
                  "keep: turn the faces to the engine's last filtered normal map instead of the result's gradient");
    cmd->add_flag("--closed", a->pipeline.closed,
                  "re-mesh an open input as a closed, watertight surface (3D printing, tetrahedra) instead of "
                  "trimming it to the input's footprint");
    cmd->add_option("--relax-steps", a->pipeline.fit.relax_steps,
                    "keep: tangential relaxation iterations (untangle what noise moved along the surface)")
        ->check(CLI::Range(0, 100000))->capture_default_str();
    cmd->add_option("--fit-steps", a->pipeline.fit.vertex_steps,
                    "keep: vertex-update iterations turning the faces to the result's normals")
        ->check(CLI::Range(0, 100000))->capture_default_str();
    cmd->add_option("--boundary-rings", a->pipeline.fit.boundary_rings,
                    "keep: an open boundary stays, and the vertices within this many edge rings of it move partly")
        ->check(CLI::Range(0, 100000))->capture_default_str();
    cmd->add_flag("--normal-map", a->normal_map,
                  "with a .vdb output: also write the filtered normal map, a vector grid \"normals\"");
    add_decimation_options(cmd, a->pipeline);
    add_draco_options(cmd, a->draco);
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_smooth);
}

}  // namespace normalflow::cli
