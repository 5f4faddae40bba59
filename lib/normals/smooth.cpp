#include "normals/smooth.h"

// smooth_volume: the loop over the engine's stages. The narrow band, its block layout, the band
// move and the reinitialisation are lib/band (Band, after OpenVDB's LevelSetTracker); the normal
// filters (isotropic, anisotropic, high-boost, and bilateral, guided and total variation on the
// surface samples, behind NormalFilter, after OpenVDB's LevelSetFilter, each with its rules), the
// refit and mean curvature flow are lib/normals/stages; the row kernels they run are
// lib/normals/kernels.

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include "band/band.h"
#include "band/gather.h"
#include "band/layout.h"
#include "band/run_control.h"
#include "core/errors.h"
#include "normals/stages/mean_curvature.h"
#include "normals/stages/normal_filter.h"
#include "normals/stages/refit.h"
#include "normals/stages/stage.h"
#include "normals/stages/volume_constraint.h"

namespace normalflow {

namespace engine {
namespace {

/// A window's held border (SmoothOptions::fixed_lo, fixed_hi) gives way over fixed_zone voxels: there the filtered
/// normals are blended toward φ's own (all of φ's at the held layer, none at the zone's inner side), so that the
/// refit moves the surface less the nearer it is to the layer that does not move (see fixed_zone).
void relax_toward_border(Band& band, const SmoothOptions& opt) {
    const int zone = opt.fixed_zone;
    if (zone <= 0) return;
    bool any = false;
    for (int a = 0; a < 3; ++a) any |= opt.fixed_lo[a] > 0 || opt.fixed_hi[a] > 0;
    if (!any) return;
    Field3& N = band.work().normals;
    const Samples& phi = band.phi();
    const auto dims = band.grid().dims;
    // voxels from the held layer to the nearest of the samples lo <= (x, y, z) <= hi
    const auto held_distance = [&](const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
        float d = 1e9f;
        for (int a = 0; a < 3; ++a) {
            if (opt.fixed_lo[a] > 0) d = std::min(d, float(lo[a] - opt.fixed_lo[a]));
            if (opt.fixed_hi[a] > 0) d = std::min(d, float(dims[a] - opt.fixed_hi[a] - 1 - hi[a]));
        }
        return d;
    };
    band.for_blocks(band.all_blocks(), 1, [&](std::size_t, std::int32_t b, Scratch& s) {
        const auto& bc = band.block_coord(std::size_t(b));
        const std::array<int, 3> first{bc[0] * kBlockDim, bc[1] * kBlockDim, bc[2] * kBlockDim};
        const std::array<int, 3> last{first[0] + kBlockDim - 1, first[1] + kBlockDim - 1, first[2] + kBlockDim - 1};
        if (held_distance(first, last) >= float(zone)) return;
        float* P = s.at(0);
        gather_phi(band.neighbourhood(std::size_t(b)), phi, P);
        const std::size_t base = std::size_t(b) * kBlockVoxels;
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x) {
                    const std::array<int, 3> p{first[0] + x, first[1] + y, first[2] + z};
                    const float d = held_distance(p, p);
                    if (d >= float(zone)) continue;
                    const float t = std::clamp(1.0f - d / float(zone), 0.0f, 1.0f);
                    const int q = lidx(x, y, z);
                    float g[3];
                    for (int j = 0; j < 3; ++j) g[j] = 0.5f * (P[q + kStride[j]] - P[q - kStride[j]]);
                    const float gl = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
                    const std::size_t i = base + std::size_t(bidx(x, y, z));
                    if (!(gl > 0) || std::abs(N[0][i]) > 1.5f) continue;
                    float n[3], nl = 0;
                    for (int j = 0; j < 3; ++j) {
                        n[j] = (1 - t) * N[j][i] + t * g[j] / gl;
                        nl += n[j] * n[j];
                    }
                    nl = std::sqrt(nl);
                    if (nl > 0)
                        for (int j = 0; j < 3; ++j) N[j][i] = n[j] / nl;
                }
    });
}

}  // namespace
}  // namespace engine

const char* to_string(SmoothMode mode) {
    switch (mode) {
        case SmoothMode::Isotropic: return "isotropic";
        case SmoothMode::Anisotropic: return "anisotropic";
        case SmoothMode::HighBoost: return "highboost";
        case SmoothMode::MeanCurvature: return "mcf";
        case SmoothMode::Bilateral: return "bilateral";
        case SmoothMode::Guided: return "guided";
        case SmoothMode::TotalVariation: return "tv";
    }
    return "unknown";
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// The distances a main iteration reads are exact below this (voxels); above, φ need only be at
/// least this. The normal loop and the refit read φ at the active samples (|φ| <= active_band)
/// and at their neighbours up to 2 voxels away (tangential gradients at the faces, curvature);
/// one voxel more for safety. The last reinitialisation, whose φ is returned, is exact to
/// kHalfWidth.
float working_limit(const SmoothOptions& opt) { return std::min(engine::kHalfWidth, opt.active_band + 3.0f); }

/// The main iterations on a band with a surface (opt's defaults resolved); iterations_given: the
/// caller set SmoothOptions::iterations (then no early stop when the normal map is smooth).
void run(engine::Band& band, const SmoothOptions& opt, SmoothReport& rep, Progress* progress, bool iterations_given,
         NormalMap* normal_map, const SmoothCheckpoint* checkpoint, Volume& v) {
    using namespace engine;
    RunControl ctl(progress, opt.iterations);
    StageContext c{band, opt, rep, ctl};
    const std::unique_ptr<NormalFilter> filter = make_normal_filter(opt.mode);  // none: mean curvature flow
    const bool auto_stop = !iterations_given && filter && filter->stops_when_smooth();
    const auto t_band = Clock::now();
    band.update_band();
    // out to the full half width, not just working_limit(): a run that stops in its first
    // iteration (below) then returns this φ as it is
    if (opt.reinitialise_input) band.reinitialise(kHalfWidth, ctl);
    rep.seconds_reinit += seconds_since(t_band);
    for (int it = 0; it < opt.iterations; ++it) {
        const auto t_it = Clock::now();
        ctl.iteration = it;
        band.build_active(opt.active_band);
        SmoothIteration& record = rep.iterations.emplace_back();
        record.band_voxels = band.active_voxels();
        record.allocated_voxels = band.nblocks() * kBlockVoxels;
        if (filter) {
            const auto t0 = Clock::now();
            filter->filter_normals(c);
            engine::relax_toward_border(band, opt);
            rep.seconds_normals += seconds_since(t0);
            const auto t1 = Clock::now();
            const bool keep = filter->preserves_volume(opt);
            const bool deferred = keep && opt.defer_volume_shift;
            double volume = 0.0;
            if (deferred)
                window_volume(band, opt.window_lo, opt.window_hi, record.volume_before, record.volume_slope);
            else if (keep)
                volume = active_volume(band);
            refit_to_normals(c, filter->refit_rules());
            if (deferred)
                window_volume(band, opt.window_lo, opt.window_hi, record.volume_after, record.volume_slope);
            else if (keep && record.refit_steps > 0)
                record.volume_shift = restore_volume(band, volume);
            if (normal_map)  // this iteration's N, the last one's in the end (the band moves next)
                for (std::size_t a = 0; a < 3; ++a)
                    band.write_field(band.work().normals[a], kNoNormal, (*normal_map)[a]);
            rep.seconds_refit += seconds_since(t1);
        } else {
            const auto t0 = Clock::now();
            mean_curvature_flow(c);
            rep.seconds_refit += seconds_since(t0);
        }
        // A refit that kept no step leaves φ bit for bit as this iteration found it (refit_to_normals
        // restores it), and the next iteration would start from that φ and the same µ (the
        // schedule takes the smaller of the last µ and one measured on the same normals): it
        // and every later one would repeat this one exactly. So stop, with the final
        // reinitialisation, which φ already had if the last one went out to kHalfWidth (a
        // stop in the first iteration): the surface did not move, so neither does the band.
        // (Reinitialising the unchanged φ and going on would only let the interface samples'
        // φ/|∇φ| drift a little each time.)
        const bool unchanged = filter && record.refit_steps == 0;
        // The filter left the normal map smooth at its disc's scale: this iteration is the last.
        const bool smooth_enough = auto_stop && record.roughness < kNeighbourhoodRoughness;
        const bool more = it + 1 < opt.iterations && !unchanged && !smooth_enough;
        const auto t2 = Clock::now();
        if (!(unchanged && band.reinit_limit() >= kHalfWidth) && (more || opt.final_reinitialise)) {
            band.update_band();
            band.reinitialise(more ? working_limit(opt) : kHalfWidth, ctl);
        }
        rep.seconds_reinit += seconds_since(t2);
        record.seconds = seconds_since(t_it);
        // The checkpoint reads φ as the next iteration would (exact within working_limit, the surface and the
        // samples next to it), and the band is left as it was: a run it lets go on is the one without it.
        if (more && checkpoint && *checkpoint) {
            band.write_back(v);
            if (!(*checkpoint)(v)) {
                const auto t3 = Clock::now();
                band.update_band();  // as a last iteration ends: φ out to the half width
                band.reinitialise(kHalfWidth, ctl);
                rep.seconds_reinit += seconds_since(t3);
                rep.stopped_at_checkpoint = true;
                ctl.finish();
                break;
            }
        }
        if (smooth_enough && !unchanged && it + 1 < opt.iterations) {
            rep.stopped_smooth = true;
            ctl.finish();
            break;
        }
        if (unchanged && it + 1 < opt.iterations) {
            rep.stopped_unchanged = true;
            ctl.finish();
            break;
        }
    }
}

void validate(const Volume& v, const SmoothOptions& opt) {
    validate_smooth_options(opt);
    v.check("smooth_volume");  // the volume's own invariants (lib/core/volume.h)
}

}  // namespace

void validate_smooth_options(const SmoothOptions& opt, const std::string& who, const std::string& prefix) {
    auto bad = [&](const std::string& m) { throw InvalidInput(who + ": " + prefix + m); };
    if (opt.iterations < 0)
        bad("iterations must be >= 0 (0: the mode's default), got " + std::to_string(opt.iterations));
    if (opt.normal_steps < 0)
        bad("normal_steps must be >= 0 (0: the mode's default), got " + std::to_string(opt.normal_steps));
    if (!(opt.length_scale >= 0.0f) || !std::isfinite(opt.length_scale))
        bad("length_scale must be >= 0, got " + std::to_string(opt.length_scale));
    if (!(opt.sigma_spatial > 0.0f) || !std::isfinite(opt.sigma_spatial))
        bad("sigma_spatial must be > 0, got " + std::to_string(opt.sigma_spatial));
    if (!(opt.sigma_range > 0.0f) || !std::isfinite(opt.sigma_range))
        bad("sigma_range must be > 0, got " + std::to_string(opt.sigma_range));
    if (!(opt.tv_lambda > 0.0f) || !std::isfinite(opt.tv_lambda))
        bad("tv_lambda must be > 0, got " + std::to_string(opt.tv_lambda));
    if (!(opt.mu > 0.0f) || !std::isfinite(opt.mu)) bad("mu must be > 0, got " + std::to_string(opt.mu));
    if (!(opt.alpha >= 0.0f) || !std::isfinite(opt.alpha)) bad("alpha must be >= 0, got " + std::to_string(opt.alpha));
    if (!(opt.normal_dt > 0.0f) || !std::isfinite(opt.normal_dt))
        bad("normal_dt must be > 0, got " + std::to_string(opt.normal_dt));
    if (!(opt.refit_dt > 0.0f) || !std::isfinite(opt.refit_dt))
        bad("refit_dt must be > 0, got " + std::to_string(opt.refit_dt));
    if (opt.refit_max_steps < 0)
        bad("refit_max_steps must be >= 0 (0: the mode's default), got " + std::to_string(opt.refit_max_steps));
    if (opt.refit_super_steps < 0)
        bad("refit_super_steps must be >= 0 (0: explicit steps), got " + std::to_string(opt.refit_super_steps));
    if (!(opt.refit_tolerance >= 0.0)) bad("refit_tolerance must be >= 0");
    if (opt.conductance_presmooth_steps < 0) bad("conductance_presmooth_steps must be >= 0");
    if (!(opt.mu_robust >= 0.0f) || !std::isfinite(opt.mu_robust))
        bad("mu_robust must be >= 0, got " + std::to_string(opt.mu_robust));
    if (!(opt.active_band >= 1.5f && opt.active_band <= 5.0f))
        bad("active_band must be in [1.5, 5] voxels, got " + std::to_string(opt.active_band));
    if (opt.threads < 0) bad("threads must be >= 0, got " + std::to_string(opt.threads));
    if (opt.fixed_zone < 0) bad("fixed_zone must be >= 0, got " + std::to_string(opt.fixed_zone));
    if (opt.refit_replay_count < 0 || opt.refit_replay_count > kRefitSuperStepAttempts)
        bad("refit_replay_count must be in [0, " + std::to_string(kRefitSuperStepAttempts) + "], got " +
            std::to_string(opt.refit_replay_count));
    if (opt.refit_explicit_probe < 0)
        bad("refit_explicit_probe must be >= 0, got " + std::to_string(opt.refit_explicit_probe));
    if (opt.refit_explicit_replay < -1)
        bad("refit_explicit_replay must be >= -1, got " + std::to_string(opt.refit_explicit_replay));
}

// The defaults are the filter's rules (lib/normals/stages); mean curvature flow, which has no
// filter, takes the diffusions'.
int default_iterations(SmoothMode mode) {
    const auto filter = engine::make_normal_filter(mode);
    return filter ? filter->default_iterations() : engine::kDiffusionIterations;
}

int default_refit_steps(const SmoothOptions& opt) {
    const auto filter = engine::make_normal_filter(opt.mode);
    return filter ? filter->default_refit_steps(opt) : engine::kDiffusionRefitSteps;
}

int default_normal_steps(SmoothMode mode) {
    const auto filter = engine::make_normal_filter(mode);
    return filter ? filter->default_normal_steps() : engine::kDiffusionSteps;
}

void reinitialise_volume(Volume& v, int threads) {
    v.check("reinitialise_volume");
    auto work = [&] {
        engine::Band band(v);
        if (!band.has_surface()) return;
        engine::RunControl ctl(nullptr, 1);
        band.update_band();
        band.reinitialise(engine::kHalfWidth, ctl);
        band.write_back(v);
    };
    if (threads > 0) {
        tbb::task_arena arena(threads);
        arena.execute(work);
    } else {
        work();
    }
}

SmoothReport smooth_volume(Volume& v, const SmoothOptions& options, Progress* progress, NormalMap* normal_map,
                           const SmoothCheckpoint* checkpoint) {
    validate(v, options);
    SmoothReport rep;
    if (options.normal_dt > engine::kMaxDt)
        rep.warnings.push_back("normal_dt " + std::to_string(options.normal_dt) +
                               " clamped to the stability bound 1/6");
    if (options.refit_dt > engine::kMaxDt)
        rep.warnings.push_back("refit_dt " + std::to_string(options.refit_dt) + " clamped to the stability bound 1/6");
    detail::begin(progress, "smooth");
    auto work = [&] {
        SmoothOptions opt = options;
        if (opt.iterations == 0) opt.iterations = default_iterations(opt.mode);
        if (opt.normal_steps == 0) opt.normal_steps = default_normal_steps(opt.mode);
        if (opt.refit_max_steps == 0) opt.refit_max_steps = default_refit_steps(opt);
        engine::Band band(v);
        if (!band.has_surface()) {
            rep.warnings.push_back("the volume holds no surface (no sign change); returned unchanged");
            return;
        }
        band.set_fixed_border(opt.fixed_lo, opt.fixed_hi);
        run(band, opt, rep, progress, options.iterations != 0, normal_map, checkpoint, v);
        band.write_back(v);
    };
    if (options.threads > 0) {
        tbb::task_arena arena(options.threads);
        arena.execute(work);
    } else {
        work();
    }
    return rep;
}

}  // namespace normalflow
