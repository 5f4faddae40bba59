// The flags that parse straight into PipelineOptions and VolumeInput (pipeline_options.h): every default
// shown in the help is the library's.
#include "pipeline_options.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>

#include "cli_support.h"
#include "core/errors.h"

namespace normalflow::cli {

namespace {

std::string number(double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", x);
    return b;
}

}  // namespace

void add_grid_options(CLI::App* cmd, PipelineOptions& p) {
    auto* res = cmd->add_option("--resolution", p.scan.resolution,
                                p.scan.resolution == 0
                                    ? "voxels along the longest bounding-box side (default: automatic, 5 per median "
                                      "edge length of the input, 128 to 512, within the memory available)"
                                    : "voxels along the longest bounding-box side")
                    ->check(CLI::Range(8, 8192));
    if (p.scan.resolution != 0) res->capture_default_str();
    cmd->add_option("--voxel-size", p.scan.voxel_size,
                    "voxel size in world units (overrides --resolution; a volume input is resampled to it)")
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

void add_smooth_options(CLI::App* cmd, PipelineOptions& p) {
    SmoothOptions& s = p.smooth;
    std::map<std::string, SmoothMode> modes;
    for (SmoothMode m :
         {SmoothMode::Isotropic, SmoothMode::Anisotropic, SmoothMode::HighBoost, SmoothMode::MeanCurvature,
          SmoothMode::Bilateral, SmoothMode::Guided, SmoothMode::TotalVariation})
        modes[to_string(m)] = m;
    add_enum_option(cmd, "--mode", s.mode, modes,
                    "bilateral | guided | tv | anisotropic | isotropic | highboost | mcf");
    cmd->add_option("--iterations", s.iterations,
                    "main iterations (normal loop + refit); default: up to " +
                        std::to_string(default_iterations(SmoothMode::Bilateral)) +
                        " for bilateral, guided and tv (fewer once the normal map is smooth), " +
                        std::to_string(default_iterations(SmoothMode::Anisotropic)) + " for anisotropic, " +
                        std::to_string(default_iterations(SmoothMode::Isotropic)) + " for isotropic, highboost and mcf")
        ->check(CLI::Range(1, 10000));
    cmd->add_option("--normal-steps", s.normal_steps,
                    "normal-loop steps (bilateral, guided: filter passes; tv: solver iterations) per main iteration; "
                    "default: " +
                        std::to_string(default_normal_steps(SmoothMode::Anisotropic)) + ", " +
                        std::to_string(default_normal_steps(SmoothMode::Bilateral)) + " for bilateral and guided, " +
                        std::to_string(default_normal_steps(SmoothMode::TotalVariation)) + " for tv")
        ->check(CLI::Range(1, 10000));
    cmd->add_option(
           "--length-scale", p.length_scale,
           "bilateral, guided, tv: the model's length unit in world units (default: the input's median edge length, "
           "at most 1/25.6 of its longest side)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--sigma-spatial", s.sigma_spatial, "bilateral, guided: spatial sigma in length units")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--sigma-range", s.sigma_range, "bilateral, guided: range sigma on the normals' chord")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--tv-lambda", s.tv_lambda,
                    "tv: the fidelity's length in length units (larger: flatter, removes larger patches)")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--mu", s.mu, "anisotropic conductance scale, 1/voxel")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_option("--alpha", s.alpha, "high-boost amount")->check(CLI::NonNegativeNumber)->capture_default_str();
    cmd->add_option("--presmooth", s.conductance_presmooth_steps,
                    "anisotropic: isotropic steps that regularise the conductance (0: the paper's raw g)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--mu-robust", s.mu_robust,
                    "anisotropic: raise mu to C times the robust noise scale of the curvature (0: the fixed mu)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--refit-steps", s.refit_max_steps,
                    "refit steps per main iteration at most (default: 40; bilateral, guided, tv: a refit time of 1.4 "
                    "length units squared)")
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--refit-tolerance", s.refit_tolerance,
                    "the refit stops when D falls by less than this fraction of itself in a step")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--refit-super-steps", s.refit_super_steps,
                    "bilateral, guided, tv: cover the refit time in this many Runge-Kutta-Legendre super steps (0: "
                    "explicit steps of --refit-dt)")
        ->check(CLI::Range(0, 100000))
        ->capture_default_str();
    cmd->add_flag("--extend-by-gather", s.extend_by_gather,
                  "bilateral, guided, tv: carry the filtered normals off the surface by a filter pass at each closest "
                  "point (slower; the default before 0.2)");
    cmd->add_flag("!--all-samples", s.thin_samples,
                  "bilateral, guided: filter every shell sample, also where the grid is finer than 5 voxels per length "
                  "unit (slower; the default before 0.2)");
    cmd->add_option("--refit-dt", s.refit_dt, "refit time step, voxel² (at most 1/6)")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_flag("!--no-preserve-volume", s.preserve_volume,
                  "bilateral, guided, tv: do not shift the surface back to the volume it had before each refit");
    cmd->add_flag("--second-order", s.second_order_term, "add Appendix A's second term (Eq. 39) to the refit");
    const std::map<std::string, Connectivity> connectivity = {
        {"auto", Connectivity::Auto}, {"keep", Connectivity::Keep}, {"remesh", Connectivity::Remesh}};
    add_enum_option(
        cmd, "--connectivity", p.connectivity, connectivity,
        "keep: the input's own mesh, its vertices moved onto the result; remesh: a new mesh "
        "extracted from it (open where the input is open, see --closed); auto (default): keep for an "
        "open input, and for a closed one whose fitted faces agree with the result (within " +
            number(kAutoKeepFitAngleDeg) +
            " degrees on average), remesh otherwise and whenever --target-faces, --max-error or --closed is given");
    cmd->add_flag("--fit-to-normal-map", p.fit_to_normal_map,
                  "keep: turn the faces to the engine's last filtered normal map instead of the result's gradient");
    cmd->add_flag("--closed", p.closed,
                  "re-mesh an open input as a closed, watertight surface (3D printing, tetrahedra) instead of "
                  "trimming it to the input's footprint");
    cmd->add_option("--relax-steps", p.fit.relax_steps,
                    "keep: tangential relaxation iterations (untangle what noise moved along the surface)")
        ->check(CLI::Range(0, 100000))
        ->capture_default_str();
    cmd->add_option("--fit-steps", p.fit.vertex_steps,
                    "keep: vertex-update iterations turning the faces to the result's normals")
        ->check(CLI::Range(0, 100000))
        ->capture_default_str();
    cmd->add_option("--boundary-rings", p.fit.boundary_rings,
                    "keep: an open boundary stays, and the vertices within this many edge rings of it move partly")
        ->check(CLI::Range(0, 100000))
        ->capture_default_str();
}

void add_remesh_options(CLI::App* cmd, PipelineOptions& p) {
    p.sharpen = true;
    cmd->add_flag("!--no-sharpen", p.sharpen,
                  "keep the extraction's vertices on the grid edges (creases become one-voxel bevels) instead of "
                  "moving them onto the input's creases and corners");
    cmd->add_flag("--closed", p.closed,
                  "re-mesh an open input as a closed, watertight surface (3D printing, tetrahedra) instead of "
                  "trimming it to the input's footprint");
}

void add_decimation_options(CLI::App* cmd, PipelineOptions& p) {
    cmd->add_option("--target-faces", p.target_faces,
                    "decimate the result to at most N faces (quadric edge collapse, checked; see --decimator)")
        ->check(CLI::Range(std::size_t(4), std::size_t(1) << 40));
    cmd->add_option("--max-error", p.max_error,
                    "decimate the result while each collapse stays within E (world units) of the surface's tangent "
                    "planes: an adaptive mesh, coarse where flat (with --target-faces, whichever stops first)")
        ->check(CLI::PositiveNumber);
    char compact[160];
    std::snprintf(compact, sizeof compact, "decimated within %g voxel of its surface and %g degrees of its normals",
                  kCompactErrorVoxels, kCompactNormalDeviationDeg);
    cmd->add_flag("--full-density", p.full_density,
                  std::string("keep every triangle of a re-meshed result (default: ") + compact +
                      ", a mesh whose size follows its shape)");
    add_decimator_option(cmd, p.decimator);
}

void set_volume_length_scale(PipelineOptions& p, const VolumeReadInfo& info) {
    if (p.length_scale == 0 && p.smooth.length_scale == 0)
        p.length_scale = kVolumeLengthScaleVoxels * std::max({info.spacing[0], info.spacing[1], info.spacing[2]});
}

}  // namespace normalflow::cli
