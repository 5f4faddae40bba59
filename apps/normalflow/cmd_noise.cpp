// normalflow noise IN OUT --sigma S [--seed K] [--kind gaussian|impulsive] [--direction normal|random]
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "commands.h"
#include "io/io.h"
#include "metrics/noise.h"

namespace normalflow::cli {

namespace {

struct NoiseArgs {
    std::string input, output;
    NoiseOptions noise;  ///< the flags parse straight into it
    OutputFlags out;
};

const std::map<std::string, NoiseKind> kKinds = {{"gaussian", NoiseKind::Gaussian},
                                                 {"impulsive", NoiseKind::Impulsive}};
const std::map<std::string, NoiseDirection> kDirections = {{"normal", NoiseDirection::Normal},
                                                           {"random", NoiseDirection::Random}};

int run_noise(const NoiseArgs& a) {
    Stopwatch clock;
    Mesh mesh = read_mesh(a.input);
    const NoiseOptions& o = a.noise;
    const NoiseReport r = add_noise(mesh, o);
    write_mesh(a.output, mesh);
    if (a.out.json) {
        Json j = Json::object();
        j.set("command", "noise").set("input", a.input).set("output", a.output);
        j.set("sigma", o.sigma).set("seed", static_cast<unsigned long long>(o.seed));
        j.set("kind", name_of(kKinds, o.kind)).set("direction", name_of(kDirections, o.direction));
        j.set("mean_edge_length", r.mean_edge_length).set("sigma_world", r.sigma_world);
        j.set("vertices", r.vertices).set("displaced", r.displaced).set("rms_displacement", r.rms_displacement);
        j.set("seconds", clock.seconds());
        std::printf("%s\n", j.dump().c_str());
    } else if (!a.out.quiet) {
        std::printf("noise: %zu of %zu vertices displaced, sigma %.4g x mean edge %.6g = %.6g (rms %.6g) -> %s\n",
                    r.displaced, r.vertices, o.sigma, r.mean_edge_length, r.sigma_world, r.rms_displacement,
                    a.output.c_str());
    }
    return 0;
}

}  // namespace

void add_noise_command(CLI::App& app) {
    auto args = std::make_shared<NoiseArgs>();
    auto* cmd =
        app.add_subcommand("noise", "add synthetic noise (sigma in mean edge lengths), deterministic for a seed");
    cmd->add_option("IN", args->input, "input mesh")->required();
    cmd->add_option("OUT", args->output, "output mesh (format from the extension)")->required();
    cmd->add_option("--sigma", args->noise.sigma, "standard deviation, multiple of the mean edge length")
        ->required()
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--seed", args->noise.seed, "random seed")->capture_default_str();
    add_enum_option(cmd, "--kind", args->noise.kind, kKinds, "gaussian or impulsive");
    add_enum_option(cmd, "--direction", args->noise.direction, kDirections, "normal or random");
    cmd->add_option("--fraction", args->noise.impulsive_fraction, "fraction of vertices displaced by impulsive noise")
        ->check(CLI::Range(0.0, 1.0))
        ->capture_default_str();
    add_output_flags(cmd, args->out);
    on_run(cmd, args, run_noise);
}

}  // namespace normalflow::cli
