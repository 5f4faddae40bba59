// The options table (options.h): each option once, its default read from the structs through its field.
#include "pipeline/options.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/errors.h"
#include "core/version.h"
#include "pipeline/report_json.h"
#include "pipeline/system_memory.h"

namespace normalflow {

namespace {

constexpr unsigned S = unsigned(Command::Smooth), R = unsigned(Command::Remesh), V = unsigned(Command::Voxelize),
                   E = unsigned(Command::Extract), C = unsigned(Command::Compress);
constexpr double kUnbounded = 1e300;

template <class T>
constexpr OptionKind kind_of() {
    if constexpr (std::is_same_v<T, bool>)
        return OptionKind::Switch;
    else if constexpr (std::is_same_v<T, int>)
        return OptionKind::Int;
    else if constexpr (std::is_same_v<T, std::size_t>)
        return OptionKind::Count;
    else if constexpr (std::is_floating_point_v<T>)
        return OptionKind::Real;
    else if constexpr (std::is_same_v<T, std::optional<double>>)
        return OptionKind::OptionalReal;
    else {
        static_assert(std::is_enum_v<T> && sizeof(T) == sizeof(int), "an option's field: a number, bool or enum");
        return OptionKind::Choice;
    }
}

/// The names of an enum's values, as to_string spells them.
template <class En>
std::vector<OptionChoice> names(std::initializer_list<En> values) {
    std::vector<OptionChoice> out;
    for (En v : values) out.push_back({to_string(v), static_cast<int>(v)});
    return out;
}

/// One row: F is a captureless lambda RunOptions& → the field (its type gives the kind).
template <class F>
OptionSpec row(std::string name, std::string field, Group group, Tier tier, unsigned commands, F, std::string help) {
    using T = std::remove_reference_t<decltype(F{}(std::declval<RunOptions&>()))>;
    OptionSpec s;
    s.name = std::move(name);
    s.field = std::move(field);
    s.help = std::move(help);
    s.group = group;
    s.tier = tier;
    s.commands = commands;
    s.kind = kind_of<T>();
    s.single = std::is_same_v<T, float>;
    s.ref = [](RunOptions& o) -> void* { return &F{}(o); };
    return s;
}

OptionSpec range(OptionSpec s, double lo, double hi, bool lo_open = false, std::string zero = "") {
    s.lo = lo;
    s.hi = hi;
    s.lo_open = lo_open;
    s.zero = std::move(zero);
    return s;
}
OptionSpec positive(OptionSpec s, std::string zero = "") { return range(std::move(s), 0, kUnbounded, true, zero); }
OptionSpec non_negative(OptionSpec s) { return range(std::move(s), 0, kUnbounded); }
OptionSpec choices(OptionSpec s, std::vector<OptionChoice> c) {
    s.choices = std::move(c);
    return s;
}
OptionSpec bytes(OptionSpec s) {
    s.kind = OptionKind::Bytes;
    s = positive(std::move(s), "auto");
    s.hi = 0x1p62;  // 4 EiB: any memory, and a size_t
    return s;
}

std::string shortest(double x, bool single) {
    char b[64];
    const auto r = single ? std::to_chars(b, b + sizeof b, float(x)) : std::to_chars(b, b + sizeof b, x);
    return std::string(b, r.ptr);
}

std::vector<OptionSpec> make_table() {
    using G = Group;
    using T = Tier;
    const std::string auto_res = "voxels along the longest side (auto: " + shortest(kAutoVoxelsPerLength, false) +
                                 " per length unit, " + std::to_string(kAutoResolutionMin) + " to " +
                                 std::to_string(kAutoResolutionMax) +
                                 ", within the memory available; a mesh kept on its own faces, where the grid only "
                                 "guards, coarser down to voxels of twice its noise, at most by half)";
    const std::string iterations = "main iterations, each a filtering of the normal map and a refit (auto: up to " +
                                   std::to_string(default_iterations(SmoothMode::Bilateral)) +
                                   " for bilateral, guided and tv, fewer once the normal map is smooth; " +
                                   std::to_string(default_iterations(SmoothMode::Anisotropic)) + " for anisotropic, " +
                                   std::to_string(default_iterations(SmoothMode::Isotropic)) +
                                   " for isotropic, highboost and mcf)";
    const std::string normal_steps =
        "normal-loop steps per main iteration: filter passes (bilateral, guided), solver "
        "iterations (tv) (auto: " +
        std::to_string(default_normal_steps(SmoothMode::Bilateral)) + ", " +
        std::to_string(default_normal_steps(SmoothMode::TotalVariation)) + " for tv, " +
        std::to_string(default_normal_steps(SmoothMode::Anisotropic)) + " for the paper's modes)";
    const std::string refit_steps =
        "refit steps per main iteration at most (auto: " + std::to_string(default_refit_steps(SmoothOptions{})) +
        "; bilateral, guided, tv: a refit time of " + shortest(kNeighbourhoodRefitTime, true) +
        " length units squared)";
    const std::string connectivity =
        "keep: the input's own mesh, its faces smoothed (see --keep-filter); remesh: a new mesh extracted from it "
        "(open "
        "where the input is open, see --closed); auto: keep for an open input, and for a closed one whose kept "
        "result is manifold with no faces intersecting (as a re-meshed result); remesh otherwise and whenever "
        "--target-faces, --max-error or --closed is given";
    const std::string full_density = "keep every triangle of a re-meshed result (default: decimated within " +
                                     shortest(kCompactErrorVoxels, false) + " voxel of its surface and " +
                                     shortest(kCompactNormalDeviationDeg, false) +
                                     " degrees of its normals, a mesh whose size follows its shape)";
    const auto modes =
        names({SmoothMode::Bilateral, SmoothMode::Guided, SmoothMode::TotalVariation, SmoothMode::Anisotropic,
               SmoothMode::Isotropic, SmoothMode::HighBoost, SmoothMode::MeanCurvature});
    // clang-format off
    return {
        // Input
        range(row("resolution", "pipeline.scan.resolution", G::Input, T::Essential, S | R | V,
                  [](RunOptions& o) -> auto& { return o.pipeline.scan.resolution; }, auto_res), 8, 8192, false, "auto"),
        row("iso", "volume.iso", G::Input, T::Essential, S | E, [](RunOptions& o) -> auto& { return o.volume.iso; },
            "a volume file that is a scalar image (CT, MRI, probability): the surface where the value is V, inside "
            "where it is above"),
        row("label", "volume.label", G::Input, T::Advanced, S | E,
            [](RunOptions& o) -> auto& { return o.volume.label; },
            "a volume file that is a label map: the surface of the voxels labelled L"),
        row("negate", "volume.negate", G::Input, T::Advanced, S | E,
            [](RunOptions& o) -> auto& { return o.volume.negate; },
            "a volume file: flip the inside (with --iso: below V; a signed distance: positive inside)"),
        positive(row("voxel-size", "pipeline.scan.voxel_size", G::Input, T::Advanced, S | R | V | E,
                     [](RunOptions& o) -> auto& { return o.pipeline.scan.voxel_size; },
                     "voxel size in world units instead of --resolution; a volume file is resampled to it (none: "
                     "--resolution; a volume file's smallest spacing)"), "none"),
        non_negative(row("shell", "pipeline.scan.shell_thickness", G::Input, T::Advanced, S | R | V,
                         [](RunOptions& o) -> auto& { return o.pipeline.scan.shell_thickness; },
                         "process an open sheet as a shell of this thickness (world units; 0: none)")),
        row("repair", "pipeline.repair", G::Input, T::Advanced, S | R | V,
            [](RunOptions& o) -> auto& { return o.pipeline.repair; },
            "merge points, drop degenerate faces and orient the input first (needs CGAL)"),
        range(row("band", "pipeline.scan.half_width", G::Input, T::Advanced, V,
                  [](RunOptions& o) -> auto& { return o.pipeline.scan.half_width; }, "band half-width in voxels"),
              1, 64),
        choices(row("distance", "pipeline.distance", G::Input, T::Library, S | R | V,
                    [](RunOptions& o) -> auto& { return o.pipeline.distance; },
                    "closest-triangle search: the engine's BVH or CGAL's AABB tree (same distances)"),
                names({DistanceQuery::EngineBvh, DistanceQuery::CgalAabb})),
        // Smoothing
        choices(row("mode", "pipeline.smooth.mode", G::Smoothing, T::Essential, S,
                    [](RunOptions& o) -> auto& { return o.pipeline.smooth.mode; },
                    "the filter of the normal map: bilateral, guided, tv (total variation) in model units; the "
                    "paper's anisotropic, isotropic, highboost, mcf in voxels"), modes),
        range(row("iterations", "pipeline.smooth.iterations", G::Smoothing, T::Essential, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.smooth.iterations; }, iterations),
              1, 10000, false, "auto"),
        positive(row("length-scale", "pipeline.length_scale", G::Smoothing, T::Essential, S,
                     [](RunOptions& o) -> auto& { return o.pipeline.length_scale; },
                     "the model's length unit, world units: the scale of its noise and of the filters, and of the "
                     "automatic resolution (auto: the input's median edge length, at most 1/" +
                         shortest(kAutoResolutionMin / kAutoVoxelsPerLength, false) +
                         " of its longest side; a volume file's coarsest spacing)"), "auto"),
        range(row("normal-steps", "pipeline.smooth.normal_steps", G::Smoothing, T::Advanced, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.smooth.normal_steps; }, normal_steps),
              1, 10000, false, "auto"),
        positive(row("sigma-spatial", "pipeline.smooth.sigma_spatial", G::Smoothing, T::Advanced, S,
                     [](RunOptions& o) -> auto& { return o.pipeline.smooth.sigma_spatial; },
                     "bilateral, guided, tv: the spatial Gaussian's sigma in length units (auto: twice the "
                     "input's measured noise, at most 0.6, at least a voxel)"),
                 "auto"),
        positive(row("sigma-range", "pipeline.smooth.sigma_range", G::Smoothing, T::Advanced, S,
                     [](RunOptions& o) -> auto& { return o.pipeline.smooth.sigma_range; },
                     "bilateral, guided, tv: the range Gaussian's sigma on the normals' chord")),
        positive(row("tv-lambda", "pipeline.smooth.tv_lambda", G::Smoothing, T::Advanced, S,
                     [](RunOptions& o) -> auto& { return o.pipeline.smooth.tv_lambda; },
                     "tv: the fidelity's length in length units (larger: flatter, removes larger patches)")),
        row("preserve-volume", "pipeline.smooth.preserve_volume", G::Smoothing, T::Advanced, S,
            [](RunOptions& o) -> auto& { return o.pipeline.smooth.preserve_volume; },
            "bilateral, guided, tv: shift the surface back to the volume it had before each refit"),
        positive(row("mu", "pipeline.smooth.mu", G::Smoothing, T::Expert, S,
                     [](RunOptions& o) -> auto& { return o.pipeline.smooth.mu; },
                     "anisotropic: the conductance scale, 1/voxel")),
        non_negative(row("alpha", "pipeline.smooth.alpha", G::Smoothing, T::Expert, S,
                         [](RunOptions& o) -> auto& { return o.pipeline.smooth.alpha; }, "highboost: the gain")),
        range(row("presmooth", "pipeline.smooth.conductance_presmooth_steps", G::Smoothing, T::Expert, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.smooth.conductance_presmooth_steps; },
                  "anisotropic: isotropic steps that regularise the conductance (0: the paper's raw g)"),
              0, 100000),
        non_negative(row("mu-robust", "pipeline.smooth.mu_robust", G::Smoothing, T::Expert, S,
                         [](RunOptions& o) -> auto& { return o.pipeline.smooth.mu_robust; },
                         "anisotropic: raise mu to C times the robust noise scale of the curvature (0: the fixed "
                         "mu)")),
        range(row("refit-steps", "pipeline.smooth.refit_max_steps", G::Smoothing, T::Expert, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.smooth.refit_max_steps; }, refit_steps),
              1, 100000, false, "auto"),
        non_negative(row("refit-tolerance", "pipeline.smooth.refit_tolerance", G::Smoothing, T::Expert, S,
                         [](RunOptions& o) -> auto& { return o.pipeline.smooth.refit_tolerance; },
                         "the refit stops when D falls by less than this fraction of itself in a step")),
        positive(row("refit-dt", "pipeline.smooth.refit_dt", G::Smoothing, T::Expert, S,
                     [](RunOptions& o) -> auto& { return o.pipeline.smooth.refit_dt; },
                     "the refit's time step, voxels squared (above 1/6 it is clamped to 1/6)")),
        positive(row("normal-dt", "pipeline.smooth.normal_dt", G::Smoothing, T::Library, S,
                     [](RunOptions& o) -> auto& { return o.pipeline.smooth.normal_dt; },
                     "the normal loop's time step, voxels squared")),
        range(row("active-band", "pipeline.smooth.active_band", G::Smoothing, T::Library, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.smooth.active_band; },
                  "voxels: the samples the normal loop and the refit update"), 1.5, 5),
        range(row("refit-super-steps", "pipeline.smooth.refit_super_steps", G::Smoothing, T::Library, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.smooth.refit_super_steps; },
                  "bilateral, guided, tv: Runge-Kutta-Legendre super steps of the refit (0: explicit steps)"),
              0, 100000),
        row("extend-by-gather", "pipeline.smooth.extend_by_gather", G::Smoothing, T::Library, S,
            [](RunOptions& o) -> auto& { return o.pipeline.smooth.extend_by_gather; },
            "bilateral, guided, tv: a filter pass at each closest point (the default before 0.2)"),
        row("thin-samples", "pipeline.smooth.thin_samples", G::Smoothing, T::Library, S,
            [](RunOptions& o) -> auto& { return o.pipeline.smooth.thin_samples; },
            "bilateral, guided: filter every s-th shell sample, s = floor(length unit / 5 voxels)"),
        row("second-order", "pipeline.smooth.second_order_term", G::Smoothing, T::Library, S,
            [](RunOptions& o) -> auto& { return o.pipeline.smooth.second_order_term; },
            "the refit with Appendix A's second term (Eq. 39)"),
        // Output mesh
        choices(row("connectivity", "pipeline.connectivity", G::OutputMesh, T::Essential, S,
                    [](RunOptions& o) -> auto& { return o.pipeline.connectivity; }, connectivity),
                names({Connectivity::Auto, Connectivity::Keep, Connectivity::Remesh})),
        row("closed", "pipeline.closed", G::OutputMesh, T::Essential, S | R,
            [](RunOptions& o) -> auto& { return o.pipeline.closed; },
            "re-mesh an open input as a closed, watertight surface (3D printing, tetrahedra) instead of trimming "
            "it to the input's footprint"),
        range(row("target-faces", "pipeline.target_faces", G::OutputMesh, T::Essential, S | R | E,
                  [](RunOptions& o) -> auto& { return o.pipeline.target_faces; },
                  "decimate the result to at most N faces (quadric edge collapse, checked)"),
              4, double(std::size_t(1) << 40), false, "none"),
        positive(row("max-error", "pipeline.max_error", G::OutputMesh, T::Essential, S | R | E,
                     [](RunOptions& o) -> auto& { return o.pipeline.max_error; },
                     "decimate the result while each collapse stays within E (world units) of the surface's "
                     "tangent planes: coarse where flat (with --target-faces, whichever stops first)"), "none"),
        row("full-density", "pipeline.full_density", G::OutputMesh, T::Essential, S | R | E,
            [](RunOptions& o) -> auto& { return o.pipeline.full_density; }, full_density),
        row("sharpen", "pipeline.sharpen", G::OutputMesh, T::Advanced, R,
            [](RunOptions& o) -> auto& { return o.pipeline.sharpen; },
            "move the extraction's vertices onto the input's creases and corners (without: creases are one-voxel "
            "bevels)"),
        row("fit-to-normal-map", "pipeline.fit_to_normal_map", G::OutputMesh, T::Advanced, S,
            [](RunOptions& o) -> auto& { return o.pipeline.fit_to_normal_map; },
            "keep (volume, fit): turn the faces to the engine's last filtered normal map instead of the result's gradient"),
        row("normal-map", "normal_map", G::OutputMesh, T::Advanced, S,
            [](RunOptions& o) -> auto& { return o.normal_map; },
            "a .vdb output: also write the filtered normal map, a vector grid \"normals\""),
        range(row("relax-steps", "pipeline.fit.relax_steps", G::OutputMesh, T::Expert, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.fit.relax_steps; },
                  "keep (volume, fit): tangential relaxation iterations (untangle what noise moved along the surface)"), 0, 100000),
        range(row("fit-steps", "pipeline.fit.vertex_steps", G::OutputMesh, T::Expert, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.fit.vertex_steps; },
                  "keep (volume, fit): vertex-update iterations turning the faces to the result's normals"), 0, 100000),
        choices(row("keep-filter", "pipeline.keep_filter", G::OutputMesh, T::Advanced, S,
                    [](RunOptions& o) -> auto& { return o.pipeline.keep_filter; },
                    "keep: faces: the input's own faces filtered for the rounds of least estimated error (SURE); "
                    "volume: the vertices fitted to the smoothed volume, then its normals guide the face filter; "
                    "fit: the fit alone"),
                names({KeepFilter::Faces, KeepFilter::Volume, KeepFilter::Fit})),
        range(row("face-steps", "pipeline.faces.normal_steps", G::OutputMesh, T::Expert, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.faces.normal_steps; },
                  "keep: rounds of the face filter at most (auto: " + std::to_string(kMaxFaceRounds) +
                      " for faces, which stops at the least estimated error; 1 for volume)"), 0, 100000, false, "auto"),
        range(row("face-vertex-steps", "pipeline.faces.vertex_steps", G::OutputMesh, T::Library, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.faces.vertex_steps; },
                  "keep: vertex-update iterations in each round of the face filter"), 0, 100000),
        positive(row("face-sigma-r", "pipeline.faces.sigma_r", G::OutputMesh, T::Library, S,
                     [](RunOptions& o) -> auto& { return o.pipeline.faces.sigma_r; },
                     "keep: the face filter's range scale on the guidance normals (a chord length)")),
        positive(row("face-sigma-s", "pipeline.faces.sigma_s", G::OutputMesh, T::Library, S,
                     [](RunOptions& o) -> auto& { return o.pipeline.faces.sigma_s; },
                     "keep: the face filter's spatial scale, in mean distances between adjacent faces' centroids")),
        range(row("face-rings", "pipeline.faces.rings", G::OutputMesh, T::Library, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.faces.rings; },
                  "keep: the face filter's neighbourhood, in vertex rings"), 1, 100),
        row("face-patch", "pipeline.faces.patch_guidance", G::OutputMesh, T::Library, S,
            [](RunOptions& o) -> auto& { return o.pipeline.faces.patch_guidance; },
            "keep: the face filter's guidance is each face's most consistent patch"),
        choices(row("face-saliency", "pipeline.faces.saliency", G::OutputMesh, T::Library, S,
                    [](RunOptions& o) -> auto& { return o.pipeline.faces.saliency; },
                    "keep: a patch's consistency includes its relative saliency (Zhang et al.): on, off, or chosen, "
                    "both run and the one of lower estimated error kept"),
                names({PatchSaliency::Off, PatchSaliency::On, PatchSaliency::Chosen})),
        choices(row("face-range", "pipeline.faces.range", G::OutputMesh, T::Library, S,
                    [](RunOptions& o) -> auto& { return o.pipeline.faces.range; },
                    "keep: the face filter's weight on the guidance normals: guided, none (a linear mean), or "
                    "chosen, both run and the one of lower estimated error kept"),
                names({RangeWeight::Guided, RangeWeight::None, RangeWeight::Chosen})),
        range(row("face-own-patch", "pipeline.faces.own_patch_bias", G::OutputMesh, T::Library, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.faces.own_patch_bias; },
                  "keep: a neighbour's patch guides a face when its spread is below this fraction of the face's own"),
              0, 1, true),
        range(row("boundary-rings", "pipeline.fit.boundary_rings", G::OutputMesh, T::Expert, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.fit.boundary_rings; },
                  "keep (volume, fit): an open boundary stays, and the vertices within this many edge rings of it move partly"),
              0, 100000),
        range(row("projection-steps", "pipeline.fit.projection_steps", G::OutputMesh, T::Library, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.fit.projection_steps; },
                  "keep (volume, fit): Newton steps that put each vertex on the zero level set"), 0, 100000),
        choices(row("decimator", "pipeline.decimator", G::OutputMesh, T::Library, S | R | E,
                    [](RunOptions& o) -> auto& { return o.pipeline.decimator; },
                    "the decimator of --target-faces and --max-error (cgal: the one before 0.2; meshoptimizer: a "
                    "comparison)"),
                names({Decimator::Auto, Decimator::Quadric, Decimator::Meshoptimizer, Decimator::Cgal})),
        range(row("extract-iso", "pipeline.extract.iso", G::OutputMesh, T::Library, S | R | E,
                  [](RunOptions& o) -> auto& { return o.pipeline.extract.iso; }, "the level set extracted"),
              -kUnbounded, kUnbounded),
        // Web output
        range(row("position-bits", "draco.position_bits", G::WebOutput, T::Essential, S | R | C,
                  [](RunOptions& o) -> auto& { return o.draco.position_bits; },
                  "Draco: quantization bits per position axis"), 1, 30),
        range(row("normal-bits", "draco.normal_bits", G::WebOutput, T::Advanced, S | R | C,
                  [](RunOptions& o) -> auto& { return o.draco.normal_bits; },
                  "Draco: quantization bits per normal component"), 1, 30),
        range(row("texcoord-bits", "draco.texcoord_bits", G::WebOutput, T::Advanced, S | R | C,
                  [](RunOptions& o) -> auto& { return o.draco.texcoord_bits; },
                  "Draco: quantization bits per texture coordinate component"), 1, 30),
        range(row("level", "draco.compression_level", G::WebOutput, T::Advanced, S | R | C,
                  [](RunOptions& o) -> auto& { return o.draco.compression_level; },
                  "Draco: compression level, 0 (fast) to 10 (small)"), 0, 10),
        row("fallback", "draco.fallback", G::WebOutput, T::Advanced, S | R | C,
            [](RunOptions& o) -> auto& { return o.draco.fallback; },
            ".glb: also store uncompressed buffers for viewers without Draco (the file grows about 4 times)"),
        // Run
        bytes(row("max-memory", "pipeline.max_memory_bytes", G::Run, T::Advanced, S | R | V,
                  [](RunOptions& o) -> auto& { return o.pipeline.max_memory_bytes; },
                  "refuse a run estimated to need more than this (4G, 512M; auto: the memory available)")),
        range(row("brick-size", "pipeline.brick_voxels", G::Run, T::Expert, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.brick_voxels; },
                  "run the engine brick by brick, bricks of N voxels a side (auto: only where the whole volume "
                  "does not fit the memory, in the largest bricks that do)"), 8, 65536, false, "auto"),
        range(row("brick-halo", "pipeline.brick_halo_voxels", G::Run, T::Expert, S,
                  [](RunOptions& o) -> auto& { return o.pipeline.brick_halo_voxels; },
                  "the halo of a brick, voxels (auto: what one main iteration of the engine reaches)"), 1, 65536,
              false, "auto"),
        range(row("threads", "pipeline.scan.threads", G::Run, T::Advanced, S | R | V,
                  [](RunOptions& o) -> auto& { return o.pipeline.scan.threads; },
                  "worker threads (auto: all cores); results do not depend on it"), 1, 4096, false, "auto"),
    };
    // clang-format on
}

template <class T>
T& field(const OptionSpec& s, RunOptions& o) {
    return *static_cast<T*>(s.ref(o));
}
template <class T>
const T& field(const OptionSpec& s, const RunOptions& o) {
    return *static_cast<const T*>(s.ref(const_cast<RunOptions&>(o)));
}

double number_of(const OptionSpec& s, const RunOptions& o) {
    switch (s.kind) {
        case OptionKind::Int: return field<int>(s, o);
        case OptionKind::Count:
        case OptionKind::Bytes: return double(field<std::size_t>(s, o));
        case OptionKind::Real: return s.single ? double(field<float>(s, o)) : field<double>(s, o);
        default: return 0;
    }
}

bool in_range(const OptionSpec& s, double x) {
    if (x == 0 && !s.zero.empty()) return true;
    if (s.single && !(std::abs(x) <= std::numeric_limits<float>::max())) return false;  // a float field holds it
    return (s.lo_open ? x > s.lo : x >= s.lo) && x <= s.hi && std::isfinite(x);
}

std::string choice_list(const OptionSpec& s) {
    std::string out;
    for (const OptionChoice& c : s.choices) out += (out.empty() ? "" : ", ") + c.name;
    return out;
}

std::string quoted(std::string_view text) {
    std::string q = "'";
    q.append(text);
    q += '\'';
    return q;
}

}  // namespace

const char* to_string(Command c) {
    switch (c) {
        case Command::Smooth: return "smooth";
        case Command::Remesh: return "remesh";
        case Command::Voxelize: return "voxelize";
        case Command::Extract: return "extract";
        case Command::Compress: return "compress";
    }
    return "?";
}

const char* to_string(Group g) {
    switch (g) {
        case Group::Input: return "Input";
        case Group::Smoothing: return "Smoothing";
        case Group::OutputMesh: return "Output mesh";
        case Group::WebOutput: return "Web output (.glb, .drc)";
        case Group::Run: return "Run";
    }
    return "?";
}

RunOptions default_options(Command c) {
    RunOptions o;
    if (c == Command::Remesh) o.pipeline.sharpen = true;  // creases and corners kept unless --no-sharpen
    return o;
}

PipelineOptions pipeline_options(const RunOptions& options, Command c) {
    PipelineOptions p = options.pipeline;
    p.smoothing = c == Command::Smooth;
    if (c == Command::Remesh) p.connectivity = Connectivity::Remesh;
    p.smooth.threads = p.scan.threads;  // --threads: both stages
    return p;
}

VolumeInput volume_input(const RunOptions& o) {
    if (o.pipeline.scan.resolution != 0 || o.pipeline.scan.shell_thickness != 0)
        throw InvalidInput(
            "resolution and shell apply to a mesh input; a volume keeps its grid (voxel-size "
            "resamples it)");
    VolumeInput v = o.volume;
    v.voxel_size = o.pipeline.scan.voxel_size;
    return v;
}

void refuse_volume_options(const RunOptions& o) {
    if (o.volume.iso || o.volume.label || o.volume.negate)
        throw InvalidInput("iso, label and negate apply to a volume input");
}

void set_volume_length_scale(PipelineOptions& p, const VolumeReadInfo& info) {
    if (p.length_scale == 0 && p.smooth.length_scale == 0)
        p.length_scale = kVolumeLengthScaleVoxels * std::max({info.spacing[0], info.spacing[1], info.spacing[2]});
}

std::string OptionSpec::key() const {
    std::string k = name;
    std::replace(k.begin(), k.end(), '-', '_');
    return k;
}

std::span<const OptionSpec> option_table() {
    static const std::vector<OptionSpec> table = make_table();
    return table;
}

const OptionSpec* find_option(std::string_view name, Command c) {
    std::string n(name);
    std::replace(n.begin(), n.end(), '_', '-');
    for (const OptionSpec& s : option_table())
        if (s.name == n && s.takes(c)) return &s;
    return nullptr;
}

std::vector<const OptionSpec*> user_options(Command c) {
    std::vector<const OptionSpec*> out;
    for (const OptionSpec& s : option_table())
        if (s.takes(c) && s.tier != Tier::Library) out.push_back(&s);
    return out;
}

std::string option_range(const OptionSpec& s) {
    switch (s.kind) {
        case OptionKind::Switch: return "true or false";
        case OptionKind::OptionalReal: return "a number";
        case OptionKind::Choice: return "one of " + choice_list(s);
        default: break;
    }
    std::string r = s.kind == OptionKind::Real ? "a number " : "an integer ";
    if (s.hi >= kUnbounded)
        r.append(s.lo_open ? "> " : ">= ").append(shortest(s.lo, false));
    else
        r.append("in ")
            .append(s.lo_open ? "(" : "[")
            .append(shortest(s.lo, false))
            .append(", ")
            .append(shortest(s.hi, false))
            .append("]");
    if (s.kind == OptionKind::Bytes) r = "a size such as 4G, 512M or 100000";
    if (!s.zero.empty()) r += ", or " + s.zero;
    return r;
}

void set_option(const OptionSpec& s, RunOptions& o, std::string_view text) {
    const auto bad = [&]() -> std::string { return quoted(text) + " is not " + option_range(s); };
    if (s.kind == OptionKind::Switch) {
        static const char* const yes[] = {"true", "1", "yes", "on"};
        static const char* const no[] = {"false", "0", "no", "off"};
        for (const char* y : yes)
            if (text == y) return void(field<bool>(s, o) = true);
        for (const char* n : no)
            if (text == n) return void(field<bool>(s, o) = false);
        throw InvalidInput(quoted(text) + " is not true or false");
    }
    if (s.kind == OptionKind::Choice) {
        for (const OptionChoice& c : s.choices)
            if (text == c.name) {
                std::memcpy(s.ref(o), &c.value, sizeof(int));  // the enum's value (sizeof checked in kind_of)
                return;
            }
        throw InvalidInput(quoted(text) + " is not one of " + choice_list(s));
    }
    if (s.kind == OptionKind::OptionalReal && text.empty()) return void(field<std::optional<double>>(s, o).reset());
    double x = 0;
    if (!s.zero.empty() && (text == s.zero || text == "0")) {
        x = 0;
    } else if (s.kind == OptionKind::Bytes) {
        try {
            x = double(parse_bytes(std::string(text)));
        } catch (const InvalidInput&) {
            throw InvalidInput(bad());
        }
    } else {
        const std::string t(text);
        char* end = nullptr;
        x = std::strtod(t.c_str(), &end);
        if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(x)) throw InvalidInput(bad());
        if (s.kind != OptionKind::Real && s.kind != OptionKind::OptionalReal && x != std::floor(x))
            throw InvalidInput(bad());
    }
    if (s.kind == OptionKind::OptionalReal) return void(field<std::optional<double>>(s, o) = x);
    if (!in_range(s, x)) throw InvalidInput(bad());
    switch (s.kind) {
        case OptionKind::Int: field<int>(s, o) = int(x); break;
        case OptionKind::Count:
        case OptionKind::Bytes: field<std::size_t>(s, o) = std::size_t(x); break;
        default:
            if (s.single)
                field<float>(s, o) = float(x);
            else
                field<double>(s, o) = x;
    }
}

std::string option_text(const OptionSpec& s, const RunOptions& o) {
    switch (s.kind) {
        case OptionKind::Switch: return field<bool>(s, o) ? "true" : "false";
        case OptionKind::OptionalReal: {
            const auto& v = field<std::optional<double>>(s, o);
            return v ? shortest(*v, false) : "";
        }
        case OptionKind::Choice: {
            int v = 0;
            std::memcpy(&v, s.ref(const_cast<RunOptions&>(o)), sizeof(int));
            for (const OptionChoice& c : s.choices)
                if (c.value == v) return c.name;
            return "?";
        }
        default: break;
    }
    const double x = number_of(s, o);
    if (x == 0 && !s.zero.empty()) return s.zero;
    if (s.kind == OptionKind::Bytes) return std::to_string(field<std::size_t>(s, o));
    return shortest(x, s.single);
}

Json option_json(const OptionSpec& s, const RunOptions& o) {
    switch (s.kind) {
        case OptionKind::Switch: return Json(field<bool>(s, o));
        case OptionKind::Int: return Json(field<int>(s, o));
        case OptionKind::Count:
        case OptionKind::Bytes: return Json(static_cast<unsigned long long>(field<std::size_t>(s, o)));
        case OptionKind::Real: return Json(std::stod(shortest(number_of(s, o), s.single)));  // 0.6f as 0.6
        case OptionKind::OptionalReal: {
            const auto& v = field<std::optional<double>>(s, o);
            return v ? Json(*v) : Json();
        }
        case OptionKind::Choice: return Json(option_text(s, o));
    }
    return Json();
}

void check_options(const RunOptions& o, const char* who) {
    for (const OptionSpec& s : option_table()) {
        const bool numeric = s.kind == OptionKind::Int || s.kind == OptionKind::Count || s.kind == OptionKind::Real ||
                             s.kind == OptionKind::Bytes;
        if (numeric && !in_range(s, number_of(s, o)))
            throw InvalidInput(std::string(who) + ": " + s.key() + " (" + s.field +
                               ") = " + shortest(number_of(s, o), s.single) + ": expected " + option_range(s));
        if (s.kind == OptionKind::OptionalReal) {
            const auto& v = field<std::optional<double>>(s, o);
            if (v && !std::isfinite(*v))
                throw InvalidInput(std::string(who) + ": " + s.key() + " (" + s.field + "): not finite");
        }
    }
}

Json parameters_json(const RunOptions& o, Command c) {
    Json j = Json::object();
    Json library = Json::object();
    for (const OptionSpec& s : option_table())
        if (s.takes(c)) (s.tier == Tier::Library ? library : j).set(s.key(), option_json(s, o));
    j.set("library", library);
    return j;
}

Json resolved_json(const PipelineOptions& o, const PipelineReport& r, double voxel_size, bool scan_converted) {
    const ScanConvertOptions& scan = r.scan_options;  // as run: the automatic resolution and the band rule applied
    Json j = Json::object();
    j.set("resolution", scan_converted && scan.voxel_size == 0 ? scan.resolution : 0).set("voxel_size", voxel_size);
    if (scan_converted) j.set("band", scan.half_width);
    if (o.smoothing) {
        SmoothOptions s = o.smooth;  // with the length unit as run, in voxels, for the mode's refit steps
        if (s.length_scale == 0 && r.length_scale > 0 && voxel_size > 0)
            s.length_scale = float(r.length_scale / voxel_size);
        j.set("length_scale", r.length_scale)
            .set("noise", r.noise)
            .set("sigma_spatial", r.sigma_spatial)
            .set("iterations", s.iterations > 0 ? s.iterations : default_iterations(s.mode))
            .set("iterations_run", r.smooth.iterations_run())
            .set("normal_steps", s.normal_steps > 0 ? s.normal_steps : default_normal_steps(s.mode))
            .set("refit_steps", s.refit_max_steps > 0 ? s.refit_max_steps : default_refit_steps(s));
    }
    return j;
}

void set_parameters(Json& j, const RunOptions& run, Command c, const PipelineOptions& opt, const PipelineReport& r,
                    double voxel_size, bool scan_converted) {
    j.set("parameters", parameters_json(run, c)).set("resolved", resolved_json(opt, r, voxel_size, scan_converted));
}

Json run_report_json(Command c, const RunOptions& run, const PipelineReport& r, bool scan_converted) {
    const PipelineOptions opt = pipeline_options(run, c);
    Json j = to_json(r);
    j.set("command", to_string(c));
    if (opt.smoothing) j.set("mode", to_string(opt.smooth.mode));
    set_parameters(j, run, c, opt, r, r.scan.grid.voxel_size, scan_converted);
    j.set("version", version());
    return j;
}

}  // namespace normalflow
