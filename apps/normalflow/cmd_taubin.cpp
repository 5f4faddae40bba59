// normalflow taubin / laplacian / bilateral: the mesh-side smoothing baselines (io/openmesh/smoothing.h).
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "core/errors.h"
#include "io/io.h"
#ifdef NORMALFLOW_HAS_OPENMESH
#include "io/openmesh/smoothing.h"
#endif

namespace normalflow::cli {

namespace {

struct BaselineArgs {
    std::string input, output;
    double lambda = 0.5;            ///< taubin/laplacian step factor
    double mu = -0.53;              ///< taubin inflating factor
    int iterations = 10;            ///< taubin: λ|μ pairs; laplacian: steps; bilateral: normal passes
    std::string weights = "uniform";  ///< uniform | cotan
    int vertex_iterations = 10;     ///< bilateral vertex-update passes
    double sigma_spatial = 0.0;     ///< bilateral σ_s, world units (0: mean centroid distance)
    double sigma_range = 0.35;      ///< bilateral σ_r
    bool move_boundary = false;     ///< let open-boundary vertices move
    std::string command;            ///< taubin | laplacian | bilateral
    OutputFlags out;
};

#ifdef NORMALFLOW_HAS_OPENMESH
LaplacianWeights parse_weights(const std::string& s) {
    if (s == "uniform") return LaplacianWeights::Uniform;
    if (s == "cotan") return LaplacianWeights::Cotan;
    throw InvalidInput("--weights " + s + ": expected uniform or cotan");
}
#endif

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
    if (a.command == "taubin") {
        TaubinOptions o;
        o.lambda = a.lambda;
        o.mu = a.mu;
        o.iterations = a.iterations;
        o.weights = parse_weights(a.weights);
        o.fix_boundary = !a.move_boundary;
        r = taubin_smooth(mesh, o, &progress);
    } else if (a.command == "laplacian") {
        LaplacianOptions o;
        o.lambda = a.lambda;
        o.iterations = a.iterations;
        o.weights = parse_weights(a.weights);
        o.fix_boundary = !a.move_boundary;
        r = laplacian_smooth(mesh, o, &progress);
    } else {
        BilateralNormalOptions o;
        o.normal_iterations = a.iterations;
        o.vertex_iterations = a.vertex_iterations;
        o.sigma_spatial = a.sigma_spatial;
        o.sigma_range = a.sigma_range;
        o.fix_boundary = !a.move_boundary;
        r = bilateral_normal_filter(mesh, o, &progress);
    }
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

CLI::App* add_common(CLI::App& app, const char* name, const char* help, std::shared_ptr<BaselineArgs> args) {
    args->command = name;
    auto* cmd = app.add_subcommand(name, help);
    cmd->add_option("IN", args->input, "input mesh")->required();
    cmd->add_option("OUT", args->output, "output mesh (format from the extension)")->required();
    cmd->add_flag("--move-boundary", args->move_boundary, "let vertices on open boundaries move");
    add_output_flags(cmd, args->out);
    return cmd;
}

}  // namespace

void add_taubin_command(CLI::App& app) {
    auto args = std::make_shared<BaselineArgs>();
    auto* cmd = add_common(app, "taubin", "Taubin lambda|mu smoothing of the mesh (Taubin 1995), baseline", args);
    cmd->add_option("--lambda", args->lambda, "shrinking factor, (0, 1]")->capture_default_str();
    cmd->add_option("--mu", args->mu, "inflating factor, -1.5 <= mu <= -lambda")->capture_default_str();
    cmd->add_option("--iterations", args->iterations, "lambda|mu pairs")->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--weights", args->weights, "uniform or cotan")->check(CLI::IsMember({"uniform", "cotan"}))->capture_default_str();
    on_run(cmd, args, run_baseline);
}

void add_laplacian_command(CLI::App& app) {
    auto args = std::make_shared<BaselineArgs>();
    auto* cmd = add_common(app, "laplacian", "plain Laplacian smoothing of the mesh (shrinks), baseline", args);
    cmd->add_option("--lambda", args->lambda, "step factor, (0, 1]")->capture_default_str();
    cmd->add_option("--iterations", args->iterations, "steps")->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--weights", args->weights, "uniform or cotan")->check(CLI::IsMember({"uniform", "cotan"}))->capture_default_str();
    on_run(cmd, args, run_baseline);
}

void add_bilateral_command(CLI::App& app) {
    auto args = std::make_shared<BaselineArgs>();
    args->iterations = 20;
    auto* cmd = add_common(app, "bilateral", "bilateral normal filtering (Zheng et al. 2011), baseline", args);
    cmd->add_option("--iterations", args->iterations, "normal filtering passes")->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--vertex-iterations", args->vertex_iterations, "vertex update passes")->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--sigma-spatial", args->sigma_spatial, "spatial Gaussian width, world units (0: mean centroid distance)")
        ->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--sigma-range", args->sigma_range, "normal-difference Gaussian width, (0, 2]")->capture_default_str();
    on_run(cmd, args, run_baseline);
}

}  // namespace normalflow::cli
