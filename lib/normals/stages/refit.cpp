#include "normals/stages/refit.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "band/gather.h"
#include "band/iterate.h"
#include "normals/kernels/refit_energy_row.h"
#include "normals/kernels/refit_row.h"
#include "normals/kernels/row_mask.h"

namespace normalflow::engine {
namespace {

/// G(κ²), the penalty of the normal energy.
inline float penalty(RefitPenalty p, float k2, float inv2mu2) {
    if (p == RefitPenalty::PeronaMalik) return (1.0f - std::exp(-k2 * inv2mu2)) / inv2mu2;
    return k2;
}

/// e += D over the rows y0 … y1 of plane z of the block at `base` that have active samples, in
/// row order (P: the block's φ gathered with its halo; N: the normal map).
inline void add_plane_energy(const float* P, const std::uint8_t* mask, const Field3& N, std::size_t base, int z, int y0,
                             int y1, double& e) {
    for (int y = y0; y <= y1; ++y) {
        const std::size_t i = base + std::size_t(bidx(0, y, z));
        if (any_in_row(mask + i))
            e += refit_energy_row(P + lidx(0, y, z), mask + i, N[0].data() + i, N[1].data() + i, N[2].data() + i);
    }
}

/// H_N = ∇·N (central differences, Eq. 53) [− T ∇·(G N), Eq. 39, G the penalty p] over the active
/// blocks.
void target_curvature(StageContext& c, RefitPenalty p) {
    Band& band = c.band;
    WorkBuffers& w = band.work();
    const bool second = c.opt.second_order_term;
    const float inv2mu2 = 1.0f / (2.0f * c.opt.mu * c.opt.mu);
    if (second) {
        // G per sample from the central-difference shape matrix of N, into w.phi_next
        band.for_blocks(band.all_blocks(), 3, [&](std::size_t, std::int32_t b, Scratch& s) {
            const Neighbourhood& n = band.neighbourhood(std::size_t(b));
            float* N[3] = {s.at(0), s.at(1), s.at(2)};
            gather_n(n, w.normals, N[0], N[1], N[2]);
            const std::size_t base = std::size_t(b) * kBlockVoxels;
            for (int z = 0; z < kBlockDim; ++z)
                for (int y = 0; y < kBlockDim; ++y)
                    for (int x = 0; x < kBlockDim; ++x) {
                        const int q = lidx(x, y, z);
                        float dn2 = 0.0f, v2 = 0.0f;
                        for (int c = 0; c < 3; ++c) {
                            float vc = 0.0f;
                            for (int j = 0; j < 3; ++j) {
                                const float d = 0.5f * (N[c][q + kStride[j]] - N[c][q - kStride[j]]);
                                dn2 += d * d;
                                vc += d * N[j][q];
                            }
                            v2 += vc * vc;
                        }
                        w.phi_next[base + std::size_t(bidx(x, y, z))] = penalty(p, std::max(dn2 - v2, 0.0f), inv2mu2);
                    }
        });
    }
    const float T = float(c.opt.normal_steps) * std::min(c.opt.normal_dt, kMaxDt);
    band.for_blocks(band.active(), second ? 4 : 3, [&](std::size_t, std::int32_t b, Scratch& s) {
        const Neighbourhood& n = band.neighbourhood(std::size_t(b));
        float* N[3] = {s.at(0), s.at(1), s.at(2)};
        gather_n(n, w.normals, N[0], N[1], N[2]);
        float* Gv = nullptr;
        if (second) {
            Gv = s.at(3);
            gather(n, w.phi_next.data(), 0.0f, 0.0f, Gv);
        }
        const std::size_t base = std::size_t(b) * kBlockVoxels;
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x) {
                    const int q = lidx(x, y, z);
                    float h = 0.0f;
                    for (int a = 0; a < 3; ++a) h += 0.5f * (N[a][q + kStride[a]] - N[a][q - kStride[a]]);
                    if (second) {
                        float t = 0.0f;
                        for (int a = 0; a < 3; ++a)
                            t += 0.5f * (Gv[q + kStride[a]] * N[a][q + kStride[a]] -
                                         Gv[q - kStride[a]] * N[a][q - kStride[a]]);
                        h -= T * t;
                    }
                    w.hn[base + std::size_t(bidx(x, y, z))] = h;
                }
    });
}

/// defer_volume_shift (a brick's window): the part of D over the blocks window_lo ≤ (bi, bj, bk) < window_hi, from
/// the active blocks' energies, appended to the iteration's refit_window_energy.
void record_window_energy(StageContext& c, const std::vector<double>& energy) {
    if (!c.opt.defer_volume_shift) return;
    const std::vector<std::int32_t>& active = c.band.active();
    double sum = 0.0;
    for (std::size_t k = 0; k < active.size(); ++k) {
        const auto& bc = c.band.block_coord(std::size_t(active[k]));
        bool inside = true;
        for (int a = 0; a < 3; ++a) inside &= bc[a] >= c.opt.window_lo[a] && bc[a] < c.opt.window_hi[a];
        if (inside) sum += energy[k];
    }
    c.record().refit_window_energy.push_back(sum);
}

/// D of the current φ (no update).
double refit_energy(StageContext& c) {
    const Band& band = c.band;
    WorkBuffers& w = c.band.work();
    const Samples& phi = band.phi();
    const std::uint8_t* mask = band.mask();
    const std::vector<std::int32_t>& active = band.active();
    std::vector<double> energy(active.size(), 0.0);
    band.for_blocks(active, 1, [&](std::size_t k, std::int32_t b, Scratch& s) {
        float* P = s.at(0);
        gather_phi(band.neighbourhood(std::size_t(b)), phi, P);
        const std::size_t base = std::size_t(b) * kBlockVoxels;
        double e = 0.0;
        for (int z = 0; z < kBlockDim; ++z) add_plane_energy(P, mask, w.normals, base, z, 0, kBlockDim - 1, e);
        energy[k] = e;
    });
    record_window_energy(c, energy);
    double sum = 0.0;
    for (const double e : energy) sum += e;
    return sum;
}

}  // namespace

/// One explicit step φ ← φ + dt |∇φ|_upwind (H_φ − hn) on the active samples (phi → w.phi_next,
/// then swapped). Returns D(φ before the step) when with_energy.
namespace {
double refit_step_recorded(StageContext& c, bool with_energy, bool record_window, bool* nonfinite_out = nullptr);
}  // namespace

double refit_step(StageContext& c, bool with_energy) { return refit_step_recorded(c, with_energy, false); }

namespace {

/// refit_step; record_window: the window's part of D appended to refit_window_energy (record_window_energy);
/// nonfinite_out: set where the step left φ not finite, instead of failing the run.
double refit_step_recorded(StageContext& c, bool with_energy, bool record_window, bool* nonfinite_out) {
    Band& band = c.band;
    WorkBuffers& w = band.work();
    Samples& phi = band.phi();
    const std::uint8_t* mask = band.mask();
    const std::vector<std::int32_t>& active = band.active();
    std::vector<double> energy(active.size(), 0.0);
    std::atomic<bool> bad{false};
    const float dt = std::min(c.opt.refit_dt, kMaxDt);
    band.for_blocks(active, 1, [&](std::size_t k, std::int32_t b, Scratch& s) {
        const Neighbourhood& n = band.neighbourhood(std::size_t(b));
        float* P = s.at(0);
        gather_phi(n, phi, P);
        const std::size_t base = std::size_t(b) * kBlockVoxels;
        double e = 0.0;
        int nonfinite = 0;
        // The span of rows with active samples of each z plane in one call; a row in between
        // without any gets φ, which w.phi_next already holds there (see refit_to_normals).
        const std::uint8_t* M = mask + base;
        for (int z = 0; z < kBlockDim; ++z) {
            const auto [y0, y1] = row_span(0, [&](int y) { return any_in_row(M + bidx(0, y, z)); });
            if (y1 < y0) continue;
            const std::size_t i0 = base + std::size_t(bidx(0, y0, z));
            nonfinite |=
                refit_row(P + lidx(0, y0, z), w.hn.data() + i0, mask + i0, dt, y1 - y0 + 1, w.phi_next.data() + i0);
            if (with_energy) add_plane_energy(P, mask, w.normals, base, z, y0, y1, e);
        }
        if (nonfinite) bad = true;
        energy[k] = e;
    });
    if (bad && !nonfinite_out) c.ctl.fail("phi in the refit");
    if (nonfinite_out) *nonfinite_out = bad;
    if (record_window) record_window_energy(c, energy);
    std::swap(phi, w.phi_next);
    double sum = 0.0;
    for (const double e : energy) sum += e;
    return sum;
}

/// Each super step lasts this many times the one before: short ones first, where φ still moves
/// fast (the first refit takes the noise out of it), long ones as it settles. On fandisk_n0.3 at
/// resolution 256, 6 super steps, mean normal angle against the explicit refit's 4.86°: uniform
/// 5.41°, 1.5 4.84°, 2 4.83°, 3 (4 steps) 4.92°.
constexpr double kSuperStepGrowth = 2.0;
/// Restarts in super steps after one ran away, before the rest of the refit goes to explicit steps.
constexpr int kSuperStepRetries = kRefitSuperStepAttempts;

/// The coefficients of an s-stage Runge–Kutta–Legendre super step of second order (Meyer,
/// Balsara & Aslam 2014, Eq. 16–17): Y_1 = Y_0 + μ̃_1 τ L(Y_0); Y_j = μ_j Y_{j−1} + ν_j Y_{j−2} +
/// (1 − μ_j − ν_j) Y_0 + μ̃_j τ L(Y_{j−1}) + γ̃_j τ L(Y_0). Stable for τ up to (s² + s − 2)/4
/// forward-Euler steps.
struct Rkl2 {
    int s = 0;
    std::vector<double> mu, nu, mut, gat;  // index j = 1 … s (mu[1], nu[1], gat[1] unused)
    explicit Rkl2(int stages) : s(stages), mu(std::size_t(stages) + 1), nu(mu), mut(mu), gat(mu) {
        auto b = [](int j) { return j <= 2 ? 1.0 / 3.0 : double(j * j + j - 2) / double(2 * j * (j + 1)); };
        const double w1 = 4.0 / double(s * s + s - 2);
        mut[1] = b(1) * w1;
        for (int j = 2; j <= s; ++j) {
            const auto J = std::size_t(j);
            mu[J] = double(2 * j - 1) / j * b(j) / b(j - 1);
            nu[J] = -double(j - 1) / j * b(j) / b(j - 2);
            mut[J] = mu[J] * w1;
            gat[J] = -(1.0 - b(j - 1)) * mut[J];
        }
    }
};

/// The fewest stages whose super step of length tau is stable with forward-Euler step dt.
int rkl2_stages(double tau, double dt) {
    int s = 2;
    while (double(s * s + s - 2) / 4.0 * dt < tau) ++s;
    return s;
}

/// One stage of the super step on the active samples: out = a·y1 + b·y2 + (1 − a − b)·y0 + ct·L(y1)
/// + cg·m0 where the mask is set (y0 elsewhere is what every buffer holds there). The first stage
/// (y2 = nullptr) also stores L(y0) into m0 and returns D(y0).
double rkl2_stage(StageContext& c, const Samples& y1, const Samples* y2, const Samples& y0, Samples& m0, double a,
                  double b, double ct, double cg, Samples& out, bool& nonfinite_out) {
    Band& band = c.band;
    WorkBuffers& w = band.work();
    const std::uint8_t* mask = band.mask();
    const std::vector<std::int32_t>& active = band.active();
    const bool first = y2 == nullptr;
    std::vector<double> energy(active.size(), 0.0);
    std::atomic<bool> bad{false};
    const float fa = float(a), fb = float(b), f0 = float(1.0 - a - b), fct = float(ct), fcg = float(cg);
    band.for_blocks(active, 2, [&](std::size_t k, std::int32_t blk, Scratch& s) {
        float* P = s.at(0);
        float* R = s.at(1);
        gather_phi(band.neighbourhood(std::size_t(blk)), y1, P);
        const std::size_t base = std::size_t(blk) * kBlockVoxels;
        const std::uint8_t* M = mask + base;
        double e = 0.0;
        int nonfinite = 0;
        for (int z = 0; z < kBlockDim; ++z) {
            const auto [r0, r1] = row_span(0, [&](int y) { return any_in_row(M + bidx(0, y, z)); });
            if (r1 < r0) continue;
            const std::size_t i0 = base + std::size_t(bidx(0, r0, z));
            const int n = (r1 - r0 + 1) * kBlockDim;
            nonfinite |= refit_rate_row(P + lidx(0, r0, z), w.hn.data() + i0, mask + i0, r1 - r0 + 1, R);
            const std::uint8_t* m = mask + i0;
            float* o = out.data() + i0;
            const float* Y0 = y0.data() + i0;
            float* M0 = m0.data() + i0;
            if (first) {
                for (int q = 0; q < n; ++q) {
                    if (m[q]) M0[q] = R[q];
                    o[q] = m[q] ? Y0[q] + fct * R[q] : Y0[q];
                }
                add_plane_energy(P, mask, w.normals, base, z, r0, r1, e);
            } else {
                const float* Y1 = y1.data() + i0;
                const float* Y2 = y2->data() + i0;
                for (int q = 0; q < n; ++q)
                    o[q] = m[q] ? ((fa * Y1[q] + fb * Y2[q]) + f0 * Y0[q]) + (fct * R[q] + fcg * M0[q]) : Y0[q];
            }
        }
        if (nonfinite) bad = true;
        energy[k] = e;
    });
    if (bad) nonfinite_out = true;
    if (first) record_window_energy(c, energy);
    double sum = 0.0;
    for (const double e : energy) sum += e;
    return sum;
}

struct ExplicitResult {
    int steps = 0;
    double d_end = 0.0;
};
/// How explicit_refit runs: by its schedule's stop, or (smooth_in_bricks' replay of the whole surface) every step
/// kept with no stop, D of each iterate in the window's record (a probe) or not (the decision replayed).
enum class ExplicitChecks { Stop, Probe, Replay };
ExplicitResult explicit_refit(StageContext& c, int max_steps, RefitSchedule schedule, int patience,
                              std::vector<double>& ds, ExplicitChecks checks = ExplicitChecks::Stop);
/// The explicit refit's patience: steps without a new low of D before it stops (surface-sample filters).
int explicit_patience(const SmoothOptions& o) { return std::max(5, o.refit_max_steps / 20); }

/// The explicit refit's patient stop, D of one iterate after another (explicit_refit, decide_explicit_steps): the
/// refit stops at iterate s > 0 when D has not reached a new low (by more than `tolerance` of it) for `patience`
/// steps, or rose to twice its low; it then keeps the iterate before.
struct PatientStop {
    double tolerance = 0.0;
    int patience = 0;
    double best = 0.0;
    int since_best = 0;
    bool stops_at(int s, double d) {
        if (s == 0 || d < best * (1.0 - tolerance)) {
            best = s == 0 ? d : std::min(best, d);
            since_best = 0;
        } else {
            ++since_best;
        }
        return s > 0 && (since_best >= patience || d > 2.0 * best);
    }
};

struct SuperResult {
    int kept = 0;            // super steps kept
    double d_end = 0.0;      // D of φ at the end (when not runaway)
    bool runaway = false;    // a super step ran away and was undone (see refit_super_stepping)
    double time_kept = 0.0;  // the refit time φ was carried through
};

/// A refit time `total` in refit_super_steps super steps of the Runge–Kutta–Legendre method
/// (second order) from φ: the explicit refit's flow with far fewer evaluations of its rate (stages
/// ∝ √time instead of ∝ time). D (appended to ds) is evaluated at the start of each super step;
/// the patient stop of the explicit refit, counted in time.
/// replay >= 0: exactly that many super steps, no check (SmoothOptions::refit_replay).
SuperResult run_super_steps(StageContext& c, double total, std::vector<double>& ds, int replay = -1) {
    WorkBuffers& w = c.band.work();
    Samples& phi = c.band.phi();
    const double dt = std::min(c.opt.refit_dt, kMaxDt);
    const int n = c.opt.refit_super_steps;
    const double growth = kSuperStepGrowth;
    // super step k lasts tau0·growth^k; together they last `total`
    const double tau0 = growth == 1.0 ? total / n : total * (growth - 1.0) / (std::pow(growth, n) - 1.0);
    Samples& m0 = w.normals_next[0];
    fit_samples(m0, phi.size());
    Samples* ring[3] = {&w.phi_next, &w.normals_next[1], &w.normals_next[2]};
    for (Samples* r : ring) copy_samples(phi, *r);
    Samples& prev_phi = w.spare();
    copy_samples(phi, prev_phi);
    // the explicit refit's patience, as a time: a super step that ends that long after the lowest
    // D without a new low stops the refit
    const double patience_time = double(explicit_patience(c.opt)) * dt;
    double best = 0.0, prev = 0.0, d_end = 0.0, since_best = 0.0, tau_prev = 0.0;
    double time_kept = 0.0;  // the refit time φ has been carried through
    int kept = 0;
    bool stopped = false, runaway = false;
    const bool checks = !c.opt.refit_whole_time && replay < 0;
    const auto undo_last = [&] {  // back to the start of the last super step kept
        std::swap(phi, prev_phi);
        --kept;
        time_kept -= tau_prev;
    };
    for (int step = 0; step < n; ++step) {
        if (step == replay) break;
        c.ctl.poll();
        const double tau = tau0 * std::pow(growth, step);
        const Rkl2 k(rkl2_stages(tau, dt));
        bool nonfinite = false;
        // stage 1 from y0 = φ: into ring[0], L(φ) into m0, D(φ)
        const double d = rkl2_stage(c, phi, nullptr, phi, m0, 0.0, 0.0, k.mut[1] * tau, 0.0, *ring[0], nonfinite);
        ++c.record().refit_evaluations;
        ds.push_back(d);
        if (step > 0 && d > 2.0 * best && checks) {  // the last super step ran away: undo it
            undo_last();
            runaway = true;
            break;
        }
        if (step == 0 || d < best * (1.0 - c.opt.refit_tolerance)) {
            best = step == 0 ? d : std::min(best, d);
            since_best = 0.0;
        } else {
            since_best += tau_prev;
        }
        if (step > 0 && since_best >= patience_time && checks) {
            undo_last();
            d_end = prev;
            stopped = true;
            // The first super step already raised D: it was too long to follow the flow, so the
            // refit time goes to explicit steps instead of to nothing.
            runaway = kept == 0;
            break;
        }
        tau_prev = tau;
        // stages 2 … s: ring[0] = Y_{j−1}, ring[1] = Y_{j−2} (Y_0 = φ at j = 2), ring[2] = Y_j
        for (int j = 2; j <= k.s && !nonfinite; ++j) {
            const auto J = std::size_t(j);
            const Samples& y2 = j == 2 ? phi : *ring[1];
            rkl2_stage(c, *ring[0], &y2, phi, m0, k.mu[J], k.nu[J], k.mut[J] * tau, k.gat[J] * tau, *ring[2],
                       nonfinite);
            ++c.record().refit_evaluations;
            std::swap(ring[1], ring[0]);  // ring[1] = Y_{j−1}
            std::swap(ring[0], ring[2]);  // ring[0] = Y_j
        }
        if (nonfinite) {  // φ is still this super step's start
            runaway = true;
            break;
        }
        std::swap(prev_phi, phi);  // prev_phi = this super step's start
        std::swap(phi, *ring[0]);  // φ = Y_s; ring[0] holds an old iterate (equal off the mask)
        ++kept;
        time_kept += tau;
        prev = d;
        c.ctl.tick(0.5 + 0.5 * double(step + 1) / n);
    }
    if (replay >= 0) return {kept, prev, false, time_kept};
    if (!stopped && !runaway) {
        d_end = refit_energy(c);
        ds.push_back(d_end);
        if (kept > 0 && d_end > 2.0 * best && checks) {  // the last super step ran away: undo it
            undo_last();
            runaway = true;
        } else if (kept > 0 && !(d_end <= prev) && checks) {  // it raised D: undo it, as the
                                                              // explicit refit does
            undo_last();
            d_end = prev;
        }
    }
    return {kept, d_end, runaway, time_kept};
}

/// The refit in super steps (run_super_steps). A long super step can run away where the band's
/// operator is stiffer than the explicit step allows (a non-finite stage, D doubled, or a first
/// super step that already raises D): it is undone, and the rest of the refit time starts again in
/// super steps, short ones first, from the last one that held; after kSuperStepRetries such
/// restarts, in explicit steps.
void refit_super_stepping(StageContext& c) {
    const double dt = std::min(c.opt.refit_dt, kMaxDt);
    double left = double(c.opt.refit_max_steps) * dt;
    std::vector<double> ds;
    int kept = 0;
    double d_end = 0.0;
    for (int attempt = 0;; ++attempt) {
        if (attempt == kSuperStepRetries) {
            const int rest = std::max(int(std::lround(left / dt)), 1);
            const int patience = explicit_patience(c.opt);
            ExplicitResult e;
            if (c.opt.refit_explicit_replay >= 0) {  // the whole surface's stop (smooth_in_bricks)
                e = explicit_refit(c, std::min(c.opt.refit_explicit_replay, rest), RefitSchedule::Patient, patience, ds,
                                   ExplicitChecks::Replay);
            } else if (c.opt.refit_explicit_probe > 0) {  // D of the steps, for the caller to decide the stop
                c.record().refit_window_energy.clear();
                e = explicit_refit(c, std::min(c.opt.refit_explicit_probe, rest), RefitSchedule::Patient, patience, ds,
                                   ExplicitChecks::Probe);
            } else {
                e = explicit_refit(c, rest, RefitSchedule::Patient, patience, ds);
            }
            kept += e.steps;
            d_end = e.d_end;
            break;
        }
        // the whole surface's decisions (smooth_in_bricks), then the attempt after them as the options say, its D
        // alone in the window's record
        const bool replayed = attempt < c.opt.refit_replay_count;
        const int replay = replayed ? c.opt.refit_replay[std::size_t(attempt)] : -1;
        if (!replayed && attempt > 0 && attempt == c.opt.refit_replay_count) c.record().refit_window_energy.clear();
        SuperResult r = run_super_steps(c, left, ds, replayed ? (replay >= 0 ? replay : -replay - 1) : -1);
        r.runaway |= replayed && replay >= 0;
        kept += r.kept;
        d_end = r.d_end;
        if (!r.runaway) break;
        // the first super step itself ran away: the same schedule again would too
        if (!(r.time_kept > 0.0)) attempt = kSuperStepRetries - 1;
        left -= r.time_kept;
        if (!(left > 0.5 * dt)) {  // nothing left to refit: φ as the last super step left it
            d_end = refit_energy(c);
            ds.push_back(d_end);
            break;
        }
    }
    SmoothIteration& r = c.record();
    r.refit_energy = std::move(ds);
    r.refit_energy_end = d_end;
    r.refit_steps = kept;
}

}  // namespace

/// Refit steps until D stops decreasing; φ ends as the iterate with the smallest D seen.
/// Buffers: phi (current), w.phi_next (written by the step), w.spare() (the previous iterate, kept
/// so that a step that raised D can be undone; the buffer the reinitialisation has already
/// written, so no fresh pages are touched). Samples outside the active blocks are equal in
/// all three (refit_step writes only the active blocks).
void refit_to_normals(StageContext& c, const RefitRules& rules) {
    target_curvature(c, rules.penalty);  // may use w.phi_next as scratch
    if (c.opt.refit_super_steps > 0 && rules.schedule == RefitSchedule::Patient) {
        refit_super_stepping(c);
        return;
    }
    std::vector<double> ds;  // D of each iterate evaluated
    const ExplicitResult e = explicit_refit(c, c.opt.refit_max_steps, rules.schedule, explicit_patience(c.opt), ds);
    SmoothIteration& r = c.record();
    r.refit_energy = std::move(ds);
    r.refit_energy_end = e.d_end;
    r.refit_steps = e.steps;
}

namespace {

/// Up to max_steps explicit refit steps from φ, D of each iterate appended to ds; φ ends as the
/// iterate the stop rule keeps (see refit_to_normals).
ExplicitResult explicit_refit(StageContext& c, int max_steps, RefitSchedule schedule, int patience,
                              std::vector<double>& ds, ExplicitChecks checks) {
    WorkBuffers& w = c.band.work();
    Samples& phi = c.band.phi();
    copy_samples(phi, w.phi_next);
    Samples& prev_phi = w.spare();
    copy_samples(phi, prev_phi);
    int steps = 0;
    double prev = 0.0, d_end = 0.0;
    bool stopped = false;
    // The neighbourhood filters' normal maps are not exactly integrable: D wanders a little on its
    // way down, and a stop at its first rise could end the refit after a few steps on one grid
    // and not on the next (sharpsphere_n0.3 at resolution 239: 28 steps, 12.0°; at 230 and 256
    // the whole time, 6.4°). Their refit stops when D has not reached a new low for `patience`
    // steps, or when it rose to twice its low (a refit that runs away), undoing that last step.
    const bool patient = schedule == RefitSchedule::Patient;
    PatientStop stop{.tolerance = c.opt.refit_tolerance, .patience = patience};
    for (int s = 0; s < max_steps; ++s) {
        std::swap(w.phi_next, prev_phi);  // prev_phi ← φ_{s−1}; w.phi_next is overwritten by the step
        // D(φ_s); now w.phi_next = φ_s, phi = φ_{s+1}
        const bool probe = checks == ExplicitChecks::Probe;
        bool nonfinite = false;
        const double d = refit_step_recorded(c, true, probe, probe ? &nonfinite : nullptr);
        ++c.record().refit_evaluations;
        ds.push_back(d);
        c.ctl.tick(0.5 + 0.5 * double(s + 1) / max_steps);
        if (nonfinite) {  // a probe ends where φ ran away (its D so far says where the whole surface's stops)
            std::swap(phi, prev_phi);
            d_end = prev;
            stopped = true;
            break;
        }
        if (checks != ExplicitChecks::Stop) {
            ++steps;
            prev = d;
            continue;
        }
        if (patient) {
            if (stop.stops_at(s, d)) {
                std::swap(phi, prev_phi);  // back to φ_{s−1}
                d_end = prev;
                --steps;
                stopped = true;
                break;
            }
            ++steps;
            prev = d;
            continue;
        }
        if (s > 0 && !(d < prev * (1.0 - c.opt.refit_tolerance))) {
            if (d > prev) {
                std::swap(phi, prev_phi);  // φ_s raised D: back to φ_{s−1}
                d_end = prev;
                --steps;
            } else {
                std::swap(phi, w.phi_next);  // φ_s still (barely) lowered D: keep it
                d_end = d;
            }
            stopped = true;
            break;
        }
        ++steps;
        prev = d;
    }
    if (!stopped) {
        d_end = refit_energy(c);
        ds.push_back(d_end);
    }
    return {steps, d_end};
}

}  // namespace

}  // namespace normalflow::engine

namespace normalflow {

double refit_step_dt(const SmoothOptions& options) {
    return std::min(double(options.refit_dt), double(engine::kMaxDt));
}

double refit_time(const SmoothOptions& options) {
    const int steps = options.refit_max_steps > 0 ? options.refit_max_steps : default_refit_steps(options);
    return double(steps) * refit_step_dt(options);
}

SuperStepDecision decide_super_steps(const std::vector<double>& d, const SmoothOptions& options, double total) {
    // run_super_steps's checks, on D given: the same constants, the same order
    using Then = SuperStepDecision::Then;
    const int n = options.refit_super_steps;
    if (n <= 0 || d.empty() || d.size() > std::size_t(n) + 1) return {};
    const double dt = refit_step_dt(options);
    const double growth = engine::kSuperStepGrowth;
    const double tau0 = growth == 1.0 ? total / n : total * (growth - 1.0) / (std::pow(growth, n) - 1.0);
    SmoothOptions resolved = options;
    resolved.refit_max_steps = options.refit_max_steps > 0 ? options.refit_max_steps : default_refit_steps(options);
    const double patience_time = double(engine::explicit_patience(resolved)) * dt;
    double best = 0.0, prev = 0.0, since_best = 0.0, tau_prev = 0.0;
    SuperStepDecision r;
    // the time of the steps kept, summed as a replay of them sums it (run_super_steps)
    const auto undo_last = [&](Then then) {
        --r.kept;
        r.time_kept = 0.0;
        for (int k = 0; k < r.kept; ++k) r.time_kept += tau0 * std::pow(growth, k);
        r.then = then;
        return r;
    };
    // fewer values than super steps (a window whose super steps stopped where its φ was no longer finite): the
    // decision where one falls within them
    for (int step = 0; step < n; ++step) {
        if (std::size_t(step) == d.size()) return {};
        const double x = d[std::size_t(step)];
        if (!std::isfinite(x)) return {};
        if (step > 0 && x > 2.0 * best) return undo_last(Then::Restart);
        if (step == 0 || x < best * (1.0 - options.refit_tolerance)) {
            best = step == 0 ? x : std::min(best, x);
            since_best = 0.0;
        } else {
            since_best += tau_prev;
        }
        // the patient stop; where it undoes the first super step, the rest of the time goes to explicit steps
        if (step > 0 && since_best >= patience_time) return undo_last(r.kept == 1 ? Then::Restart : Then::Stop);
        tau_prev = tau0 * std::pow(growth, step);
        ++r.kept;
        r.time_kept += tau_prev;
        prev = x;
    }
    if (d.size() != std::size_t(n) + 1) return {};
    const double end = d.back();
    if (!std::isfinite(end)) return {};
    if (end > 2.0 * best) return undo_last(Then::Restart);
    if (!(end <= prev)) return undo_last(Then::Stop);
    r.then = Then::KeepAll;
    return r;
}

int refit_explicit_patience(const SmoothOptions& options) {
    SmoothOptions resolved = options;
    resolved.refit_max_steps = options.refit_max_steps > 0 ? options.refit_max_steps : default_refit_steps(options);
    return engine::explicit_patience(resolved);
}

ExplicitStepDecision decide_explicit_steps(const std::vector<double>& d, const SmoothOptions& options, int rest) {
    // explicit_refit's patient stop (PatientStop), on D given. d[s] is D(φ_s), the iterate
    // after s steps; a stop at s keeps s − 1 steps. d's last value, D after every step of the probe, is the next
    // step's D in a refit that goes on.
    using Then = ExplicitStepDecision::Then;
    if (d.empty()) return {};
    const int run = int(d.size()) - 1;
    engine::PatientStop stop{.tolerance = options.refit_tolerance, .patience = refit_explicit_patience(options)};
    for (int s = 0; s <= run && s < rest; ++s) {
        const double x = d[std::size_t(s)];
        if (!std::isfinite(x)) return {};
        if (stop.stops_at(s, x)) return {Then::Keep, s - 1};
    }
    if (run >= rest) return {Then::Keep, rest};
    return {Then::Longer, run};
}

bool super_steps_keep_every_step(const std::vector<double>& d, const SmoothOptions& options) {
    return decide_super_steps(d, options, refit_time(options)).then == SuperStepDecision::Then::KeepAll;
}

}  // namespace normalflow
