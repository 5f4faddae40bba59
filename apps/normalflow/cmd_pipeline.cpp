// normalflow voxelize / extract / smooth: the pipeline read → repair → scan_convert → smooth → extract → write.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "core/errors.h"
#include "core/mesh_report.h"
#include "extract/extract_surface.h"
#include "io/io.h"
#include "normals/smooth.h"
#include "sdf/memory_estimate.h"
#include "sdf/scan_convert.h"
#ifdef NORMALFLOW_HAS_CGAL
#include "io/cgal/aabb_distance.h"
#include "io/cgal/cleanup.h"
#include "io/cgal/repair.h"
#endif

namespace normalflow::cli {

namespace {

/// How the mesh becomes a volume (shared by voxelize and smooth).
struct GridArgs {
    int resolution = 256;      ///< voxels along the longest side of the bounding box
    double voxel_size = 0;     ///< world units; overrides resolution when > 0
    float band = 3.0f;         ///< band half-width in voxels
    double shell = 0;          ///< world units: process an open sheet as a shell of this thickness
    bool repair = true;        ///< merge points, drop degenerate faces, orient, before scan conversion
    int threads = 0;           ///< 0 = all cores
    std::string max_memory;    ///< refuse runs estimated above this ("4G"); default: what the system has
    bool smoothing = false;    ///< the engine runs after scan conversion (for the memory estimate)
};

struct VoxelizeArgs {
    std::string input, output;
    GridArgs grid;
    OutputFlags out;
};

struct ExtractArgs {
    std::string input, output;
    OutputFlags out;
};

struct SmoothArgs {
    std::string input, output;
    GridArgs grid;
    std::string mode = "anisotropic";  ///< isotropic | anisotropic | highboost | mcf
    // Defaults are the library's (SmoothOptions), tuned on the real noisy pairs.
    int iterations = SmoothOptions{}.iterations;      ///< main iterations
    int normal_steps = SmoothOptions{}.normal_steps;  ///< normal-loop steps per main iteration
    float mu = SmoothOptions{}.mu;                    ///< 1/voxel, anisotropic conductance scale
    float alpha = SmoothOptions{}.alpha;              ///< high-boost amount
    int presmooth = -1;                ///< conductance pre-smoothing steps (-1: library default)
    float mu_robust = SmoothOptions{}.mu_robust;  ///< robust conductance scale factor (0: fixed mu)
    bool second_order = false;         ///< Appendix A's second term in the refit
    std::size_t target_faces = 0;      ///< > 0: decimate the extracted mesh (CGAL edge collapse)
    DracoOptions draco;                ///< quantization and level for .drc / .glb outputs
    OutputFlags out;
};

void add_grid_options(CLI::App* cmd, GridArgs& g) {
    cmd->add_option("--resolution", g.resolution, "voxels along the longest bounding-box side")
        ->check(CLI::Range(8, 8192));
    cmd->add_option("--voxel-size", g.voxel_size, "voxel size in world units (overrides --resolution)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--shell", g.shell, "process an open sheet as a shell of this thickness (world units)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_flag("!--no-repair", g.repair, "do not merge points, drop degenerate faces and orient first");
    cmd->add_option("--max-memory", g.max_memory,
                    "refuse a run estimated to need more than this (e.g. 4G; default: the memory available)");
    cmd->add_option("--threads", g.threads, "worker threads (0: all cores); results do not depend on it")
        ->check(CLI::NonNegativeNumber);
}

/// Refuses, before anything big is allocated, a run whose estimated peak exceeds --max-memory or
/// what the system has available.
void check_memory(const Mesh& mesh, const GridArgs& g, const std::string& input) {
    if (mesh.triangles.empty()) return;  // scan_convert gives the clear message
    const Box3d box = bounding_box(mesh);
    const Vec3d size = box.max - box.min;
    const double longest = std::max({size.x, size.y, size.z});
    const double h = g.voxel_size > 0 ? g.voxel_size : longest / g.resolution;
    if (!(h > 0) || !std::isfinite(h)) return;
    const MemoryEstimate e = estimate_memory(mesh, h, g.smoothing ? 8.0f : g.band);
    const double need = e.total(g.smoothing);
    const std::size_t available = available_memory_bytes();
    const std::size_t limit = g.max_memory.empty() ? available : parse_bytes(g.max_memory, "--max-memory");
    if (limit > 0 && need > double(limit))
        throw OutOfMemory(input + ": this run needs about " + format_bytes(need) + " at voxel size " +
                          std::to_string(h) + ", more than the " + format_bytes(double(limit)) +
                          (g.max_memory.empty() ? " available" : " allowed by --max-memory") +
                          "; lower --resolution or raise --max-memory");
    if (e.grid_samples / 512 > 2.0e9)
        throw OutOfMemory(input + ": the grid would have more than 2^31 blocks; lower --resolution");
}

/// Reads, repairs and scan-converts `input`; fills the "input" and "voxelize" parts of j.
Volume mesh_to_volume(const std::string& input, const GridArgs& g, TerminalProgress& progress, Json& j) {
    Stopwatch clock;
    progress.begin("read");
    ReadInfo info;
    Mesh mesh = read_mesh(input, &info);
    const double t_read = clock.lap();
    Json in = Json::object();
    in.set("file", input).set("format", info.format).set("vertices", mesh.positions.size()).set("triangles", mesh.triangles.size());
    std::vector<std::string> repair_warnings;
#ifdef NORMALFLOW_HAS_CGAL
    if (g.repair) {
        progress.begin("repair");
        const RepairReport rr = repair_mesh(mesh);
        in.set("points_merged", rr.points_merged).set("degenerate_removed", rr.degenerate_removed)
            .set("duplicates_removed", rr.duplicates_removed).set("faces_reversed", rr.faces_reversed);
        repair_warnings = rr.warnings;
    }
#endif
    const double t_repair = clock.lap();
    check_memory(mesh, g, input);
    progress.begin("voxelize");
    ScanConvertOptions opt;
    opt.resolution = g.resolution;
    opt.voxel_size = g.voxel_size;
    opt.half_width = g.band;
    opt.shell_thickness = g.shell;
    opt.threads = g.threads;
    ScanConvertReport sr;
#ifdef NORMALFLOW_HAS_CGAL
    const auto query = make_aabb_query(mesh);  // CGAL's AABB tree: exact closest points
#else
    const auto query = make_bvh_query(mesh);   // the engine's own BVH (same answers, no GPL code)
#endif
    Volume v = scan_convert(mesh, *query, opt, &sr, &progress);
    const double t_voxelize = clock.lap();
    j.set("input", in);
    Json vox = Json::object();
    vox.set("dims", Json::array(std::vector<int>(v.grid.dims.begin(), v.grid.dims.end())))
        .set("voxel_size", v.grid.voxel_size).set("band_half_width", v.half_width)
        .set("band_voxels", sr.band_voxels).set("blocks", v.block_count())
        .set("uncertain_sign", sr.uncertain_sign).set("memory_bytes", v.memory_bytes());
    j.set("voxelize", vox);
    Json sec = Json::object();
    sec.set("read", t_read).set("repair", t_repair).set("voxelize", t_voxelize);
    j.set("seconds", sec);
    Json warnings = Json::array(info.warnings);
    for (const auto& w : repair_warnings) warnings.push(w);
    for (const auto& w : sr.warnings) warnings.push(w);
    j.set("warnings", warnings);
    return v;
}

/// `source` names the input in messages; `smoothed` says whether the engine ran before.
Mesh volume_to_mesh(const Volume& v, TerminalProgress& progress, Json& j, const std::string& source, bool smoothed) {
    Stopwatch clock;
    progress.begin("extract");
    ExtractReport er;
    Mesh m = extract_surface(v, {}, &er);
    j["seconds"].set("extract", clock.seconds());
    if (m.empty()) {
        if (smoothed)
            throw InvalidInput(source + ": the surface vanished during smoothing (parts thinner than a few voxels "
                               "shrink away); raise --resolution or lower --iterations");
        throw InvalidInput(source + ": the volume holds no surface (every sample has the same sign)");
    }
    return m;
}

void write_result(const std::string& output, const Mesh& m, TerminalProgress& progress, Json& j,
                  const DracoOptions& draco = {}) {
    Stopwatch clock;
    progress.begin("write");
    WriteOptions wo;
    wo.glb = GlbEncoding::Draco;  // .glb: KHR_draco_mesh_compression
    wo.draco = draco;
    write_mesh(output, m, wo);
    const MeshReport r = mesh_report(m);
    Json out = Json::object();
    out.set("file", output).set("vertices", m.positions.size()).set("triangles", m.triangles.size())
        .set("components", r.components).set("closed", r.closed).set("manifold", r.manifold)
        .set("area", r.area).set("volume", r.volume);
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
    if (!is_volume_path(a.output))
        throw InvalidInput("voxelize: " + a.output + ": the output must be a .vdb or .nrrd file");
    Json j = Json::object();
    j.set("command", "voxelize");
    Volume v = mesh_to_volume(a.input, a.grid, progress, j);
    Stopwatch clock;
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
    Json j = Json::object();
    j.set("command", "extract").set("seconds", Json::object());
    progress.begin("read");
    Stopwatch clock;
    const Volume v = read_volume(a.input);
    j["seconds"].set("read", clock.seconds());
    const Mesh m = volume_to_mesh(v, progress, j, a.input, false);
    write_result(a.output, m, progress, j);
    finish(j, a.out, total, progress);
    progress.note("extract: " + a.output + " (" + std::to_string(m.triangles.size()) + " triangles)");
    return 0;
}

int run_smooth(const SmoothArgs& a) {
    Stopwatch total;
    TerminalProgress progress(a.out);
    SmoothOptions opt;
    if (a.mode == "isotropic") opt.mode = SmoothMode::Isotropic;
    else if (a.mode == "anisotropic") opt.mode = SmoothMode::Anisotropic;
    else if (a.mode == "highboost") opt.mode = SmoothMode::HighBoost;
    else if (a.mode == "mcf") opt.mode = SmoothMode::MeanCurvature;
    else throw InvalidInput("smooth: unknown --mode '" + a.mode + "' (isotropic, anisotropic, highboost, mcf)");
    opt.iterations = a.iterations;
    opt.normal_steps = a.normal_steps;
    opt.mu = a.mu;
    opt.alpha = a.alpha;
    opt.threads = a.grid.threads;
    if (a.presmooth >= 0) opt.conductance_presmooth_steps = a.presmooth;
    opt.mu_robust = a.mu_robust;
    opt.second_order_term = a.second_order;
    // Fail on a bad output path before the long computation.
    if (mesh_format_from_path(a.output) == MeshFormat::Unknown)
        throw InvalidInput("smooth: " + a.output + ": unknown output format (use .ply, .obj, .off, .stl, .glb, .drc)");

    Json j = Json::object();
    j.set("command", "smooth").set("mode", a.mode);
    GridArgs g = a.grid;
    g.smoothing = true;
    g.band = std::max(g.band, 3.0f);  // the engine rebuilds an 8-voxel band itself
    Volume v = mesh_to_volume(a.input, g, progress, j);
    Stopwatch clock;
    const SmoothReport sr = smooth_volume(v, opt, &progress);
    j["seconds"].set("smooth", clock.seconds());
    Json s = Json::object();
    s.set("iterations", sr.iterations).set("seconds_per_iteration", Json::array(sr.seconds_per_iteration))
        .set("band_voxels", Json::array(sr.band_voxels)).set("normal_energy", Json::array(sr.normal_energy))
        .set("refit_energy", Json::array(sr.refit_energy));
    if (!sr.mu.empty()) s.set("mu", Json::array(sr.mu));
    s.set("stopped_unchanged", sr.stopped_unchanged);
    if (sr.stopped_unchanged)
        progress.note("smooth: stopped after main iteration " + std::to_string(sr.iterations) + " of " +
                      std::to_string(opt.iterations > 0 ? opt.iterations : default_iterations(opt.mode)) +
                      ": its refit kept no step, so the surface no longer changes");
    j.set("smooth", s);
    for (const auto& w : sr.warnings) j["warnings"].push(w);
    Mesh m = volume_to_mesh(v, progress, j, a.input, true);
    if (a.target_faces > 0) {
#ifdef NORMALFLOW_HAS_CGAL
        progress.begin("decimate");
        cgal::CleanupOptions co;
        co.reduction = cgal::CleanupReduction::FaceCount;
        co.target_faces = a.target_faces;
        const cgal::CleanupReport cr = cgal::cleanup_mesh(m, co);
        j.set("decimate", Json::object()
                              .set("faces_before", cr.faces_before)
                              .set("faces_after", cr.faces_after)
                              .set("hausdorff", cr.hausdorff)
                              .set("seconds", cr.seconds));
        for (const auto& w : cr.warnings) j["warnings"].push(w);
#else
        throw InvalidInput("smooth: --target-faces needs a build with CGAL");
#endif
    }
    write_result(a.output, m, progress, j, a.draco);
    finish(j, a.out, total, progress);
    progress.note("smooth: " + a.output + " (" + std::to_string(m.triangles.size()) + " triangles, " +
                  std::to_string(int(total.seconds() * 10) / 10.0).substr(0, 5) + " s)");
    return 0;
}

}  // namespace

void add_voxelize_command(CLI::App& app) {
    auto a = std::make_shared<VoxelizeArgs>();
    auto* cmd = app.add_subcommand("voxelize", "scan-convert a mesh into a narrow-band signed distance volume");
    cmd->add_option("IN", a->input, "mesh file (obj, ply, off, stl, gltf, glb, drc)")->required();
    cmd->add_option("OUT", a->output, "volume file (.vdb or .nrrd)")->required();
    add_grid_options(cmd, a->grid);
    cmd->add_option("--band", a->grid.band, "band half-width in voxels")->check(CLI::Range(1.0, 64.0));
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_voxelize);
}

void add_extract_command(CLI::App& app) {
    auto a = std::make_shared<ExtractArgs>();
    auto* cmd = app.add_subcommand("extract", "extract the zero level set of a volume as a closed manifold mesh");
    cmd->add_option("IN", a->input, "volume file (.vdb or .nrrd)")->required();
    cmd->add_option("OUT", a->output, "mesh file (ply, obj, off, stl, glb, drc)")->required();
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_extract);
}

void add_smooth_command(CLI::App& app) {
    auto a = std::make_shared<SmoothArgs>();
    auto* cmd = app.add_subcommand("smooth", "voxelize, filter the normal map and refit, extract (the whole pipeline)");
    cmd->add_option("IN", a->input, "mesh file (obj, ply, off, stl, gltf, glb, drc)")->required();
    cmd->add_option("OUT", a->output, "mesh file (ply, obj, off, stl, glb, drc)")->required();
    add_grid_options(cmd, a->grid);
    cmd->add_option("--mode", a->mode, "isotropic | anisotropic | highboost | mcf")
        ->check(CLI::IsMember({"isotropic", "anisotropic", "highboost", "mcf"}));
    cmd->add_option("--iterations", a->iterations,
                    "main iterations (normal loop + refit); default: " +
                        std::to_string(default_iterations(SmoothMode::Anisotropic)) + " for anisotropic, " +
                        std::to_string(default_iterations(SmoothMode::Isotropic)) + " for the other modes")
        ->check(CLI::Range(1, 10000));
    cmd->add_option("--normal-steps", a->normal_steps, "normal-loop steps per main iteration")->check(CLI::Range(1, 10000));
    cmd->add_option("--mu", a->mu, "anisotropic conductance scale, 1/voxel")->check(CLI::PositiveNumber);
    cmd->add_option("--alpha", a->alpha, "high-boost amount")->check(CLI::NonNegativeNumber);
    cmd->add_option("--presmooth", a->presmooth,
                    "anisotropic: isotropic steps that regularise the conductance (0: the paper's raw g)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--mu-robust", a->mu_robust,
                    "anisotropic: raise mu to C times the robust noise scale of the curvature (0: the fixed mu)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_flag("--second-order", a->second_order, "add Appendix A's second term (Eq. 39) to the refit");
    cmd->add_option("--target-faces", a->target_faces, "decimate the result to at most N faces (CGAL edge collapse)")
        ->check(CLI::Range(std::size_t(4), std::size_t(1) << 40));
    add_draco_options(cmd, a->draco);
    add_output_flags(cmd, a->out);
    on_run(cmd, a, run_smooth);
}

}  // namespace normalflow::cli
