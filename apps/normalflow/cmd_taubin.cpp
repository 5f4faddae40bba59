// normalflow taubin / laplacian / bilateral: the mesh-side smoothing baselines (io/openmesh/smoothing.h).
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "commands.h"
#include "core/errors.h"
#include "io/io.h"
#include "io/openmesh/smoothing.h"  // plain option and report structs; the code needs OpenMesh

namespace normalflow::cli {

namespace {

/// Flags parse straight into the library's option structs (io/openmesh/smoothing.h), whose defaults
/// the help shows.
struct BaselineArgs {
    std::string input, output;
    TaubinOptions taubin;
    LaplacianOptions laplacian;
    BilateralNormalOptions bilateral;
    std::string command;  ///< taubin | laplacian | bilateral
    OutputFlags out;
};

const std::map<std::string, LaplacianWeights> kWeights = {{"uniform", LaplacianWeights::Uniform},
                                                          {"cotan", LaplacianWeights::Cotan}};

int run_baseline(const BaselineArgs& a) {
#ifndef NORMALFLOW_HAS_OPENMESH
    (void)a;
    throw InvalidInput(a.command + ": this build has no OpenMesh (NORMALFLOW_WITH_OPENMESH=OFF)");
#else
    Stopwatch clock;
    TerminalProgress progress(a.out);
    Mesh mesh = read_mesh(a.input);
    const double t_read = clock.lap();
    SmoothingReport r;
    if (a.command == "taubin")
        r = taubin_smooth(mesh, a.taubin, &progress);
    else if (a.command == "laplacian")
        r = laplacian_smooth(mesh, a.laplacian, &progress);
    else
        r = bilateral_normal_filter(mesh, a.bilateral, &progress);
    const double t_smooth = clock.lap();
    write_mesh(a.output, mesh);
    const double t_write = clock.lap();
    if (a.out.json) {
        Json j = Json::object();
        j.set("command", a.command).set("input", a.input).set("output", a.output);
        j.set("vertices", r.vertices).set("triangles", mesh.triangles.size()).set("faces_skipped", r.faces_skipped);
        j.set("boundary_vertices", r.boundary_vertices).set("iterations", r.iterations);
        j.set("max_displacement", r.max_displacement);
        Json s = Json::object();
        s.set("read", t_read).set("smooth", t_smooth).set("write", t_write);
        j.set("seconds", s).set("peak_memory_bytes", peak_memory_bytes());
        j.set("warnings", Json::array(r.warnings));
        std::printf("%s\n", j.dump().c_str());
        return 0;
    }
    for (const auto& w : r.warnings) progress.note("warning: " + w);
    if (!a.out.quiet)
        std::printf("%s: %zu vertices, %d iterations, max displacement %.6g, %.3f s -> %s\n", a.command.c_str(),
                    r.vertices, r.iterations, r.max_displacement, t_smooth, a.output.c_str());
    return 0;
#endif
}

CLI::App* add_common(CLI::App& app, const char* name, const char* help, std::shared_ptr<BaselineArgs> args,
                     bool& fix_boundary) {
    args->command = name;
    auto* cmd = app.add_subcommand(name, help);
    cmd->add_option("IN", args->input, "input mesh")->required();
    cmd->add_option("OUT", args->output, "output mesh (format from the extension)")->required();
    cmd->add_flag("!--move-boundary", fix_boundary, "let vertices on open boundaries move");
    add_output_flags(cmd, args->out);
    return cmd;
}

}  // namespace

void add_taubin_command(CLI::App& app) {
    auto args = std::make_shared<BaselineArgs>();
    TaubinOptions& o = args->taubin;
    auto* cmd = add_common(app, "taubin", "Taubin lambda|mu smoothing of the mesh (Taubin 1995), baseline", args,
                           o.fix_boundary);
    cmd->add_option("--lambda", o.lambda, "shrinking factor, (0, 1]")->capture_default_str();
    cmd->add_option("--mu", o.mu, "inflating factor, -1.5 <= mu <= -lambda")->capture_default_str();
    cmd->add_option("--iterations", o.iterations, "lambda|mu pairs")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    add_enum_option(cmd, "--weights", o.weights, kWeights, "uniform or cotan");
    on_run(cmd, args, run_baseline);
}

void add_laplacian_command(CLI::App& app) {
    auto args = std::make_shared<BaselineArgs>();
    LaplacianOptions& o = args->laplacian;
    auto* cmd =
        add_common(app, "laplacian", "plain Laplacian smoothing of the mesh (shrinks), baseline", args, o.fix_boundary);
    cmd->add_option("--lambda", o.lambda, "step factor, (0, 1]")->capture_default_str();
    cmd->add_option("--iterations", o.iterations, "steps")->check(CLI::NonNegativeNumber)->capture_default_str();
    add_enum_option(cmd, "--weights", o.weights, kWeights, "uniform or cotan");
    on_run(cmd, args, run_baseline);
}

void add_bilateral_command(CLI::App& app) {
    auto args = std::make_shared<BaselineArgs>();
    BilateralNormalOptions& o = args->bilateral;
    auto* cmd =
        add_common(app, "bilateral", "bilateral normal filtering (Zheng et al. 2011), baseline", args, o.fix_boundary);
    cmd->add_option("--iterations", o.normal_iterations, "normal filtering passes")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--vertex-iterations", o.vertex_iterations, "vertex update passes")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--sigma-spatial", o.sigma_spatial,
                    "spatial Gaussian width, world units (0: mean centroid distance)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--sigma-range", o.sigma_range, "normal-difference Gaussian width, (0, 2]")->capture_default_str();
    on_run(cmd, args, run_baseline);
}

}  // namespace normalflow::cli
