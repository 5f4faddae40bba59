#pragma once
/// \file smooth.h
/// The level-set normal-map engine of normalflow: geometric surface processing of a signed
/// distance volume through its normal map (Tasdizen, Whitaker, Burchard & Osher, "Geometric
/// Surface Processing via Normal Maps", ACM TOG 22(4), 2003), plus mean curvature flow as the
/// second-order baseline.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/volume.h"

namespace normalflow {

/// Which surface process smooth_volume runs.
enum class SmoothMode {
    Isotropic,       ///< isotropic normal diffusion, G(κ²) = κ² (Tasdizen et al. 2003, Eq. 15)
    Anisotropic,     ///< Perona–Malik on the normals, g(κ²) = exp(−κ²/(2µ²)) (Eq. 20)
    HighBoost,       ///< high-boost filter, N' = normalize((1+α)Nⁿ − αNⁿ⁺¹) (Eq. 21–22)
    MeanCurvature,   ///< mean curvature flow φ_t = |∇φ| H, H = κ1 + κ2 (Eq. 9)
    Bilateral,       ///< bilateral filter of the normals on the surface, a disc in model units (after
                     ///< Zheng, Fu, Au & Tai 2011): N_i ← normalize(Σ_j W_s(|p_i − p_j|) W_r(|N_i − N_j|) N_j)
    Guided,          ///< the bilateral filter with its range weight on a guidance field, the mean
                     ///< normal of the most consistent patch near each sample (after Zhang, Deng,
                     ///< Zhang, Bouaziz & Liu 2015): creases stay sharp under heavy noise
    TotalVariation,  ///< total variation of the normal map on the surface with a fidelity term (the
                     ///< paper's section 6), minimised by a primal–dual solver: piecewise-constant
                     ///< normals, planar faces meeting at sharp creases (stages/total_variation.h)
};

/// Whether a mode is one of the filters on the surface samples (Bilateral, Guided, TotalVariation):
/// their parameters are in the model's units (SmoothOptions::length_scale), they share the
/// extension to the band, the refit's schedule, the volume constraint and the early stop.
constexpr bool is_neighbourhood_filter(SmoothMode m) {
    return m == SmoothMode::Bilateral || m == SmoothMode::Guided || m == SmoothMode::TotalVariation;
}

/// Name of a mode as the command line spells it: "isotropic", "anisotropic", "highboost", "mcf",
/// "bilateral", "guided", "tv".
const char* to_string(SmoothMode mode);

/// SmoothOptions::refit_super_steps' default.
inline constexpr int kDefaultRefitSuperSteps = 6;
/// Attempts of the refit in super steps: after one runs away the rest of the refit time starts again in super steps,
/// this many attempts in all, then in explicit steps.
inline constexpr int kRefitSuperStepAttempts = 2;

/// Options of smooth_volume. Lengths and times are in voxel units (h = 1) unless stated.
struct SmoothOptions {
    SmoothMode mode = SmoothMode::Anisotropic;
    int iterations = 0;          ///< main iterations (normal loop + refit), >= 0; 0: the mode's
                                 ///< default, default_iterations(mode): 16 for Anisotropic, 8 for the
                                 ///< others. Tuned on shared/data/pairs_gnf and pairs_gcn at resolution
                                 ///< 256 with 50 normal steps, mean normal error, anisotropic 8 → 16: CAD
                                 ///< models gain (fandisk_n0.7 16.43° → 13.50°, trimstar_n0.5 13.18° →
                                 ///< 11.24°, fandisk_n0.3 8.25° → 7.70°, sharpsphere_n0.3 9.30° → 8.18°:
                                 ///< the robust µ needs 4–12 iterations to come down to µ, and the
                                 ///< crease-preserving flow then flattens what noise is left); organic
                                 ///< ones lose (bunny_n0.2 7.91° → 9.04°, fertility_n3 5.09° → 5.75°: the
                                 ///< flow erodes their curved detail). Isotropic rounds creases with
                                 ///< more: 8 → 16 fandisk_n0.3 10.15° → 10.31°, block_n0.4 11.42° → 12.01°.
    int normal_steps = 0;        ///< steps of the normal loop per main iteration, >= 0; 0: the mode's
                                 ///< default, default_normal_steps(mode): 50 for the diffusions (paper:
                                 ///< 25; at resolution 256 the noise of real scans spans several voxels
                                 ///< and needs the longer loop).
                                 ///< MeanCurvature: explicit curvature steps per main iteration.
                                 ///< Bilateral, Guided: filter passes per main iteration.
                                 ///< TotalVariation: primal–dual iterations per main iteration.
    float length_scale = 0.0f;   ///< voxels, >= 0: the model's length unit ℓ, the scale of its noise and
                                 ///< of its smallest features: smooth_mesh sets it to the input's median
                                 ///< edge length. Bilateral, Guided and TotalVariation size their disc and
                                 ///< fidelity by it, so a finer
                                 ///< grid gives the same result. 0: kDefaultLengthScale.
    float sigma_spatial = 0.6f;  ///< Bilateral, Guided: the spatial Gaussian's σ in units of
                                 ///< length_scale (0.6: about the distance between the centroids of two
                                 ///< adjacent triangles, bilateral normal filtering's σ_c); the disc is 2σ
    float sigma_range = 0.35f;   ///< Bilateral, Guided: the range Gaussian's σ on the chord |N_i − N_j|
                                 ///< (0.35, as bilateral normal filtering: a 90° crease, chord 1.41, weighs
                                 ///< 3e-4; noise of 30°, chord 0.5, 0.36)
    float tv_lambda = 0.25f;     ///< TotalVariation, > 0: 1/α, the fidelity's length, in units of
                                 ///< length_scale: a patch of radius r whose normals differ by a chord δ
                                 ///< from its surroundings goes when tv_lambda·ℓ >= δr/2
    float mu = 0.1f;             ///< 1/voxel, > 0: anisotropic conductance scale (paper: 0.1)
    float alpha = 1.0f;          ///< >= 0: high-boost gain (Eq. 22)
    float normal_dt = 0.1f;      ///< voxel², time step of the normal loop, > 0; values above the
                                 ///< stability bound 1/6 of the 3-D staggered operator are clamped
                                 ///< to 1/6 (with a warning)
    float refit_dt = 0.1f;       ///< voxel², time step of the refit and of mean curvature flow, > 0;
                                 ///< clamped to 1/6 (explicit second-order flow) with a warning
    /// >= 0: refit steps per main iteration at most; 0: the mode's default, default_refit_steps: 40 for the
    /// diffusions; for the surface-sample filters (is_neighbourhood_filter) a refit time of
    /// kNeighbourhoodRefitTime·ℓ² (ℓ = length_scale in voxels), at least 40: a surface wave an edge long needs a
    /// time ∝ ℓ² to follow its filtered normals
    int refit_max_steps = 0;
    int refit_super_steps = kDefaultRefitSuperSteps;  ///< >= 0, Bilateral, Guided, TotalVariation: the
        ///< refit time refit_max_steps · refit_dt is covered in this many super steps of the
        ///< Runge–Kutta–Legendre method of second order (Meyer, Balsara & Aslam 2014), each twice as
        ///< long as the one before and of as many stages of the explicit rate (forward-Euler step
        ///< refit_dt) as its stability needs: about √(time) evaluations instead of time/refit_dt
        ///< (fandisk_n0.3 at 256: 160 instead of 702 over two iterations). D is evaluated, and the
        ///< patient stop decided, once per super step. A super step that runs away (a non-finite
        ///< stage, D doubled) or a first one that already raises D is undone, and the rest of the
        ///< refit time starts again in super steps from there (up to twice), then in explicit steps. 0: the explicit steps of refit_dt (the default before version 0.2).
    bool refit_whole_time = false;  ///< Bilateral, Guided, TotalVariation with refit_super_steps > 0: keep every super
        ///< step that stays finite, whatever D does (no patient stop, no undoing a super step that raised D or
        ///< doubled it, no restart in explicit steps for one). For work done brick by brick (smooth_in_bricks),
        ///< where D is a window's, not the whole surface's, and a window's border alone can raise it: the caller
        ///< sums the windows' D (SmoothIteration::refit_window_energy) and checks that the whole surface's refit
        ///< would have kept every super step too (super_steps_keep_every_step), as on fandisk_n0.3 at 256 and 512
        ///< and most of the study's pairs (docs/history/benchmarks-2026.md, "Bricks").
    /// For work done brick by brick (smooth_in_bricks): the whole surface's refit decisions (decide_super_steps on the
    /// windows' D summed), replayed in place of the window's own. Attempt a < refit_replay_count of the refit in super
    /// steps runs refit_replay[a] >= 0 super steps and starts the rest of the refit time again (a runaway undone), or
    /// runs -refit_replay[a] - 1 and stops there (a patient stop, or a last step that raised D); no check of its own.
    /// The attempt after them (if any) runs as refit_whole_time says, its D alone in refit_window_energy.
    int refit_replay_count = 0;
    std::array<int, kRefitSuperStepAttempts> refit_replay{};
    /// For work done brick by brick (smooth_in_bricks): the refit's explicit steps, where the whole surface's refit
    /// goes on in them (after kRefitSuperStepAttempts restarts, or a first super step that ran away; all replayed).
    /// refit_explicit_probe > 0: up to that many explicit steps, none undone and no stop of its own, D of each iterate
    /// (and of the last) alone in refit_window_energy, for the caller to decide the patient stop on the whole
    /// surface's D (decide_explicit_steps). refit_explicit_replay >= 0: exactly that many (the decision replayed).
    int refit_explicit_probe = 0;
    int refit_explicit_replay = -1;
    /// For work done brick by brick (smooth_in_bricks): with preserve_volume, measure the volume before and after
    /// each refit over the blocks window_lo <= (bi, bj, bk) < window_hi only (SmoothIteration::volume_before, ...)
    /// and leave the shift that restores it to the caller, who sums the bricks' measures; and count the filters'
    /// roughness over the same blocks in SmoothIteration::roughness_histogram, which the caller merges.
    bool defer_volume_shift = false;
    std::array<int, 3> window_lo{0, 0, 0};
    std::array<int, 3> window_hi{0, 0, 0};
    /// Voxels: where the volume's sample (0, 0, 0) lies in the grid it is a window of (smooth_in_bricks: the window's
    /// lower corner), a multiple of the filters' sample stride. The neighbourhood filters take their surface points
    /// in that grid's coordinates, so that a window's points, and the sums over them, are the whole grid's bit for
    /// bit: in its own coordinates a point's rounding differs, and a neighbour at the edge of the disc or a tie for
    /// the nearest sample can go the other way.
    std::array<int, 3> sample_origin{0, 0, 0};
    /// false: the volume is what smooth_volume returned (its band and φ a signed distance out to the half width, as
    /// a run leaves them), and the first iteration reads it as it is instead of reinitialising it first. A run in
    /// steps (smooth_in_bricks, one iteration at a time) then reads φ as the one run would have.
    bool reinitialise_input = true;
    /// Voxels at the grid's low (fixed_lo) and high (fixed_hi) side along each axis that no stage updates: a
    /// Dirichlet border for a window of a larger grid worked on alone (smooth_in_bricks), whose surface runs on past
    /// its sides. 0: none (the grid's border is zero-flux).
    std::array<int, 3> fixed_lo{0, 0, 0};
    std::array<int, 3> fixed_hi{0, 0, 0};
    /// >= 0, voxels: with a held border (fixed_lo, fixed_hi), a zone inside it that gives way gradually: before each
    /// refit the filtered normals there are blended toward φ's own normals, wholly at the held layer and not at all
    /// fixed_zone voxels from it, so the surface moves less the nearer it lies to the layer that does not move. Without
    /// it the surface beside the held layer moves as far as anywhere (several voxels in one refit where the noise is
    /// several voxels), |∇φ| grows in the few voxels between, and the refit's rate outruns its super steps: a window's
    /// refit ran away there (fandisk_n0.3 at 512, bricks of 256, halo 128). 0: none.
    int fixed_zone = 0;
    /// false: the last iteration leaves φ as its refit (and volume constraint) left it, the band where that
    /// iteration had it, not reinitialised: for a run in steps whose caller changes φ before the next step
    /// (smooth_in_bricks' volume constraint over the whole surface) and reinitialises it then
    /// (reinitialise_volume), as the one run would have.
    bool final_reinitialise = true;
    double refit_tolerance = 1e-4;         ///< >= 0: the refit stops when D decreases by less than this
                                           ///< fraction of itself in one step (0: until D stops decreasing).
                                           ///< The surface-sample filters: when D has not reached a new low by this
                                           ///< fraction for max(5, refit_max_steps/20) steps.
    int conductance_presmooth_steps = 25;  ///< >= 0, Anisotropic only: κ² for the conductance g is
        ///< taken from the normals pre-smoothed by this many isotropic steps of normal_dt (Catté,
        ///< Lions, Morel & Coll 1992: a regularised Perona–Malik; 25 steps of 0.1 ≈ Gaussian σ ≈ 2.2
        ///< voxel; on fandisk_n0.3 at 256: 12 steps 8.41°, 25 steps 8.25°, 50 steps 8.7°). The conductance is then computed once per main iteration and held during its
        ///< normal loop. 0: the paper's g from the current normals at every step (noise whose
        ///< curvature exceeds µ then stops the flow and survives).
    float mu_robust = 1.0f;  ///< >= 0, Anisotropic with pre-smoothing only: when > 0, the
        ///< conductance scale of each main iteration is max(mu, mu_robust · σ_κ), σ_κ a robust noise
        ///< scale of the curvature (after Black, Sapiro, Marimont & Heeger 1998): the lower quartile
        ///< of |κ| at the surface / 0.3186, measured on the pre-smoothed normals and at most the same
        ///< of the raw normals, never above the previous iteration's. Noise that the pre-smoothing
        ///< leaves is then inside the scale and diffuses, while creases, far above the quartile,
        ///< still stop the flow; as the noise goes the scale falls back to mu. On a clean surface the
        ///< raw normals are flat on its flat parts, so the scale is mu. 0: the fixed mu of the paper.
        ///< Resolution 256, anisotropic, mean normal error, fixed → 1.0: fandisk_n0.7 27.8° → 16.4°,
        ///< twelve_imp0.5 14.8° → 12.3°, fandisk_n0.3 8.25° → 8.25°, block_n0.4 9.71° → 9.66°
        ///< (1.5: 16.4°, –, –, 10.2°).
    bool extend_by_gather = false;  ///< Bilateral, Guided: carry the filtered normals to the rest of the
        ///< active band by evaluating one more filter pass at each sample's closest point (the
        ///< default before version 0.2; six times the cost) instead of taking that pass's result at
        ///< the surface sample nearest to the closest point
    bool thin_samples = true;  ///< Bilateral, Guided: filter every s-th shell sample along each axis,
        ///< s = ⌊length_scale / 5⌋ (1 at the automatic resolution), so that a finer grid costs no
        ///< more per main iteration's filter; false: every one (the default before version 0.2)
    bool preserve_volume =
        true;  ///< Bilateral, Guided, TotalVariation: after each refit, shift φ by a constant so that
               ///< the enclosed volume is what it was before it (the refit of a
               ///< filtered normal map shrinks convex parts a little, −0.1…−1.4% on
               ///< the study's CAD pairs without this)
    bool second_order_term = false;  ///< add Appendix A's second term (Eq. 39), ∇·(G N), scaled by
                                     ///< the normal-loop time normal_steps·normal_dt, to the refit
    float active_band = 4.0f;        ///< voxels, in [1.5, 5]: the normal loop and the refit update the
                                     ///< samples with |φ| <= this at the start of a main iteration
    int threads = 0;                 ///< worker threads, >= 0 (0: all, 1: serial); results do not depend on it
};

/// The main iterations smooth_volume runs for SmoothOptions::iterations = 0: 16 for Anisotropic,
/// 8 for Isotropic, HighBoost and MeanCurvature, kNeighbourhoodIterations for Bilateral, Guided
/// and TotalVariation.
int default_iterations(SmoothMode mode);
/// The normal steps (filter passes) per main iteration for SmoothOptions::normal_steps = 0: 50, or
/// kNeighbourhoodPasses for Bilateral and Guided, kTotalVariationSteps for TotalVariation.
int default_normal_steps(SmoothMode mode);

/// SmoothOptions::length_scale = 0 means this many voxels.
inline constexpr float kDefaultLengthScale = 4.0f;
/// Bilateral, Guided and TotalVariation with iterations = 0 run up to kNeighbourhoodIterations main iterations and
/// stop after one whose filter left a roughness (SmoothIteration::roughness) below
/// kNeighbourhoodRoughness: the normal map is then smooth at the disc's scale, and more filtering
/// would only erode curved detail (measured on the study's pairs after one iteration: 0.013–0.017 on
/// fertility, igea, pierrot and the clean fandisk, which lose 0.2–1.9° with a second; 0.046–0.64 on
/// the noisy CAD pairs, which gain 0.6–16°).
/// Bins of SmoothIteration::roughness_histogram over [0, 2).
inline constexpr int kRoughnessBins = 2048;
/// The 75th percentile of a roughness histogram (the centre of its bin: within 1/2048 of the samples' own), as
/// SmoothIteration::roughness takes it of the samples; 0 for an empty one.
float roughness_of_histogram(const std::vector<std::uint64_t>& histogram);
inline constexpr int kNeighbourhoodIterations = 2;
inline constexpr float kNeighbourhoodRoughness = 0.03f;
inline constexpr int kNeighbourhoodPasses = 10;
/// TotalVariation: primal–dual iterations per main iteration (its normal_steps' default).
inline constexpr int kTotalVariationSteps = 100;
inline constexpr float kNeighbourhoodRefitTime = 1.4f;

/// The surface-sample filters (Bilateral, Guided) take every s-th shell sample along each axis of the grid, s this
/// at most (SmoothOptions::thin_samples; 1 for the other modes): a window of a grid whose first sample lies on a
/// multiple of it along each axis thins its samples as the whole grid does.
int surface_sample_stride(const SmoothOptions& opt);
/// The refit steps per main iteration for SmoothOptions::refit_max_steps = 0 (see there).
int default_refit_steps(const SmoothOptions& opt);

/// Whether the refit in super steps (refit_super_steps > 0, the default filters' refit) keeps every super step
/// when D, where it checks it, takes the values d: one at the start of each super step, then the end's. False where
/// a check would act (a super step that runs away or doubles D, the patient stop, a last step that raised D), where
/// a value is not finite, or where d does not hold refit_super_steps + 1 values.
bool super_steps_keep_every_step(const std::vector<double>& d, const SmoothOptions& options);

/// What the refit in super steps decides on one attempt (refit_super_steps > 0; run_super_steps' checks on D given):
/// d holds D at the start of each super step, then at the end (refit_super_steps + 1 values); `total` is the refit
/// time the attempt covers (voxel²; the first attempt's: refit_time(options)).
struct SuperStepDecision {
    enum class Then {
        KeepAll,  ///< every super step kept: the refit ends
        Restart,  ///< `kept` kept, the next one undone (it ran away): the rest of the time starts again, in super
                  ///< steps (or in explicit steps where none was kept)
        Stop,     ///< `kept` kept, the next undone (the patient stop, or a last step that raised D): the refit ends
        Unknown,  ///< d holds a value that is not finite, or not refit_super_steps + 1 values
    };
    Then then = Then::Unknown;
    int kept = 0;
    double time_kept = 0.0;  ///< the refit time of the super steps kept (voxel²)
};
SuperStepDecision decide_super_steps(const std::vector<double>& d, const SmoothOptions& options, double total);
/// What the refit's explicit steps decide (refit_super_steps > 0, after the super steps' restarts; explicit_refit's
/// patient stop on D given): d holds D of each iterate of a probe of `run` steps that kept them all, then of the last
/// (run + 1 values); `rest` is the number of explicit steps the refit's time left.
struct ExplicitStepDecision {
    enum class Then {
        Keep,     ///< `steps` kept (the patient stop undoes the one after them; rest where no stop comes)
        Longer,   ///< no stop within the probe's `steps`, fewer than rest: a longer probe decides
        Unknown,  ///< d is empty or holds a value that is not finite
    };
    Then then = Then::Unknown;
    int steps = 0;
};
ExplicitStepDecision decide_explicit_steps(const std::vector<double>& d, const SmoothOptions& options, int rest);
/// The explicit refit's patience (steps without a new low of D before it stops), for the options' refit steps (the
/// mode's default where refit_max_steps is 0).
int refit_explicit_patience(const SmoothOptions& options);
/// The refit time of one main iteration (voxel²): its steps (refit_max_steps, or the mode's default) times refit_dt
/// (at most the stability bound).
double refit_time(const SmoothOptions& options);
/// The refit's time step (refit_dt, at most the explicit stability bound), voxel².
double refit_step_dt(const SmoothOptions& options);

/// What one main iteration of smooth_volume did (energies in voxel units).
struct SmoothIteration {
    std::vector<double> normal_energy;  ///< G before each normal-loop step and after the last
                                        ///< (normal_steps + 1 values; empty for MeanCurvature;
                                        ///< Bilateral, Guided: before and after the filter;
                                        ///< TotalVariation: its objective E before and after its solve)
    std::vector<double> refit_energy;   ///< D of each refit iterate evaluated: before each step, plus
                                        ///< the result when the refit ran refit_max_steps (empty for
                                        ///< MeanCurvature)
    double refit_energy_end = 0;        ///< D at the end of the refit: the smallest D seen (a last step
                                        ///< that raised D is undone)
    int refit_steps = 0;                ///< refit steps kept (under refit_super_steps: super steps, of
                                        ///< every restart, plus the explicit steps of a fallback)
    int refit_evaluations = 0;          ///< evaluations of the refit's rate over the band: its explicit
                                        ///< steps, or the stages of its super steps (the refit's cost)
    std::size_t filter_points = 0;      ///< Bilateral, Guided, TotalVariation: the surface samples
                                        ///< filtered (thin_samples), padding excluded
    float mu = 0;                       ///< Anisotropic: the conductance scale µ used (1/voxel); 0 for
                                        ///< the other modes
    float volume_shift = 0;             ///< voxels: the shift preserve_volume applied (positive: outwards)
    /// defer_volume_shift: the volume (voxels³) inside the surface over window_lo … window_hi before and after the
    /// refit, and its slope against a uniform shift of φ (voxels²): the shift that restores it is
    /// (volume_after − volume_before) / volume_slope outwards.
    double volume_before = 0, volume_after = 0, volume_slope = 0;
    /// defer_volume_shift, the surface-sample filters: how many surface samples of the window left each roughness,
    /// in kRoughnessBins bins over [0, 2) (the chord between two unit normals): the roughness of several windows
    /// together is the 75th percentile of their summed histograms (roughness_of_histogram).
    std::vector<std::uint32_t> roughness_histogram;
    /// defer_volume_shift, the refit in super steps: D over the window's blocks (window_lo … window_hi) wherever the
    /// refit evaluates D for its checks (the start of each super step, and the end), so that a caller can sum the
    /// windows' and check the whole surface's refit (super_steps_keep_every_step).
    std::vector<double> refit_window_energy;
    float roughness = 0;          ///< Bilateral, Guided, TotalVariation: what the filter left, the 75th percentile of
                                  ///< |N_i − M_i| over the surface samples, M_i the plain Gaussian mean
                                  ///< of the filtered normals over i's disc (0 for the other modes)
    std::size_t band_voxels = 0;  ///< samples processed (the active band)
    std::size_t allocated_voxels = 0;  ///< samples held in allocated blocks
    double seconds = 0;                ///< wall seconds of the whole main iteration

    double normal_energy_start() const { return normal_energy.empty() ? 0.0 : normal_energy.front(); }
    double normal_energy_end() const { return normal_energy.empty() ? 0.0 : normal_energy.back(); }
    double refit_energy_start() const { return refit_energy.empty() ? 0.0 : refit_energy.front(); }
};

/// What smooth_volume did: one record per main iteration run, and the totals.
struct SmoothReport {
    std::vector<SmoothIteration> iterations;  ///< one per main iteration run, in order
    bool stopped_unchanged = false;           ///< true when smooth_volume stopped before the requested iterations
                                              ///< because a refit kept no step: φ was then exactly what that
                                              ///< iteration started from, and every later iteration would
                                              ///< have repeated it bit for bit (iterations.size() tells which)
    double seconds_normals = 0;               ///< total wall seconds in the normal loop (incl. normals, pre-smoothing)
    double seconds_refit = 0;                 ///< total wall seconds in the refit (incl. H_N) or the curvature flow
    double seconds_reinit = 0;                ///< total wall seconds moving the band and reinitialising φ
    std::vector<std::string> warnings;

    bool stopped_smooth = false;  ///< the surface-sample filters with iterations = 0: stopped before
                                  ///< kNeighbourhoodIterations because an iteration's filter left a
                                  ///< roughness below kNeighbourhoodRoughness
    bool stopped_at_checkpoint =
        false;  ///< the caller's SmoothCheckpoint stopped the run (iterations.size() tells when)
    int iterations_run() const { return int(iterations.size()); }
};

/// Called by smooth_volume after each main iteration that is not its last, with the volume as that iteration left it
/// (φ reinitialised as the next iteration reads it: exact within active_band + 3 voxels of the surface, beyond that
/// as the iteration found it): false stops the run there, φ then reinitialised out to the half width as on any return
/// (SmoothReport::stopped_at_checkpoint; the second reinitialisation moves the interface by a few hundredths of a
/// voxel against a run that ended there). For a caller that needs the rest of the run only if something about the
/// surface so far holds: the pipeline decides from the first iteration's surface whether to keep a closed input's
/// mesh, which reads nothing more of the volume. A run the checkpoint lets go on is bit for bit the one without it.
using SmoothCheckpoint = std::function<bool(const Volume&)>;

/// Smooths the surface {φ = 0} of a signed distance volume by the method of Tasdizen et al. 2003.
///
/// Method: each main iteration (1) computes the normal map N = ∇φ/|∇φ| (central differences,
/// Eq. 41–42); (2) runs normal_steps steps of the normal loop ∂N/∂t = (I − NNᵀ)∇·[g ∇N(I − P)]
/// with Appendix B's staggered fluxes on the 2×3 stencil (Eq. 43–52) and renormalisation;
/// (3) refits φ to the normals, ∂φ/∂t = |∇φ|(H_φ − H_N) (Eq. 17, 53–54, upwind |∇φ| of Osher &
/// Sethian 1988) until D = Σ(|∇φ| − ∇φ·N) stops decreasing; (4) moves the narrow band with the
/// surface (allocating and freeing 8³ blocks) and reinitialises φ to a signed distance (interface
/// samples by φ/|∇φ| bounded by the axis crossings, the rest by block-Jacobi passes of the Godunov
/// eikonal update, Jacobi passes inside each block until it settles; between main iterations exact
/// only as far as an iteration reads φ, active_band + 3 voxels, on return out to the half width).
/// MeanCurvature runs ∂φ/∂t = |∇φ| H_φ instead of (1)–(3). Bilateral and Guided replace (2): the
/// samples with |φ| <= 0.75 voxel, moved to their closest points x − φN, are filtered by
/// normal_steps passes of a bilateral (or guided) average over a disc of radius 2·sigma_spatial·
/// length_scale (TotalVariation: normal_steps primal–dual iterations of its objective), and every other active sample takes the filtered normals around its closest point;
/// their refit (3) runs for a time in model units (default_refit_steps) and, with preserve_volume,
/// is followed by a uniform shift of φ that restores the enclosed volume. A main iteration whose refit keeps no
/// step leaves φ unchanged, so every later one would repeat it: the run stops there
/// (SmoothReport::stopped_unchanged).
/// Anisotropic mode regularises the conductance (see SmoothOptions::conductance_presmooth_steps).
///
/// \param v        volume, modified in place: world-unit φ, negative inside. On return its band is
///                 8 voxels wide (half_width = 8, background = 8 h), its allocated blocks are the
///                 blocks that hold the surface and their 26 neighbours, tiles carry the right sign.
/// \param opt      options (voxel units, see SmoothOptions).
/// \param progress optional; ticked once per normal/refit step; may cancel.
/// \param normal_map optional: receives the normal map N the last main iteration filtered and refitted
///                 to, on the band of that iteration (its active samples; kNoNormal elsewhere): the
///                 targets fit_mesh_to_volume turns a kept mesh's faces to. Left empty for
///                 MeanCurvature (no normal map) and for a volume without a surface.
/// \param checkpoint optional: asked after each main iteration but the last whether to go on (SmoothCheckpoint);
///                 it runs on smooth_volume's threads (opt.threads).
///
/// Accepted input: any Volume whose allocated blocks hold the surface (a band of >= 1 voxel each
/// side) and whose unallocated blocks are tiled with the right sign. Open or many-component
/// surfaces are fine (they are level sets). The band should not touch the grid border (the
/// stencils clamp to the border, a zero-flux condition). A volume without a surface is returned
/// unchanged with a warning.
///
/// \throw InvalidInput   bad options or an inconsistent volume (messages name the field).
/// \throw NumericalError a NaN/Inf appeared in φ or N.
/// \throw Cancelled      progress->should_stop() returned true.
///
/// Cost: O(band voxels) memory (about 17 floats per allocated sample, plus φ and the conductance of
/// the active blocks padded to 10³ during the normal loop: 60–80 bytes per allocated sample at
/// resolution 256) and time per step (fandisk at 256, 25 steps + refit + band move: 1.4–2.0 s on
/// 2 cores, benchmarks/README.md);
/// threads via TBB over blocks, each step writes a second buffer and reductions are summed in a
/// fixed order, so the result is bit-identical for any thread count.
SmoothReport smooth_volume(Volume& v, const SmoothOptions& opt = {}, Progress* progress = nullptr,
                           NormalMap* normal_map = nullptr, const SmoothCheckpoint* checkpoint = nullptr);

/// Moves the narrow band of v to its surface and reinitialises φ to a signed distance out to the half width
/// (engine::kHalfWidth), as smooth_volume does at the start and the end of a run. A volume without a surface is
/// left as it is. threads: 0 all, else that many; the result does not depend on it.
void reinitialise_volume(Volume& v, int threads = 0);

/// Checks every field of opt as smooth_volume does before any work; a caller that does other work first (the
/// pipeline's scan conversion) checks them up front with it.
/// \throw InvalidInput "who: prefix<field> must be ..., got ..." for the first bad field.
void validate_smooth_options(const SmoothOptions& opt, const std::string& who = "smooth_volume",
                             const std::string& prefix = "");

}  // namespace normalflow
