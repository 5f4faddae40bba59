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

/// G(κ²), the penalty of the normal energy, and its derivative g.
inline float penalty(SmoothMode mode, float k2, float inv2mu2) {
    if (mode == SmoothMode::Anisotropic) return (1.0f - std::exp(-k2 * inv2mu2)) / inv2mu2;
    return k2;
}

/// H_N = ∇·N (central differences, Eq. 53) [− T ∇·(G N), Eq. 39] over the active blocks.
void target_curvature(StageContext& c) {
    Band& band = c.band;
    WorkBuffers& w = band.work();
    const bool second = c.opt.second_order_term;
    const float inv2mu2 = 1.0f / (2.0f * c.opt.mu * c.opt.mu);
    const SmoothMode emode = c.opt.mode == SmoothMode::Anisotropic ? SmoothMode::Anisotropic : SmoothMode::Isotropic;
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
                        w.phi_next[base + std::size_t(bidx(x, y, z))] =
                            penalty(emode, std::max(dn2 - v2, 0.0f), inv2mu2);
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
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y) {
                const std::size_t i0 = base + std::size_t(bidx(0, y, z));
                if (!any_in_row(mask + i0)) continue;
                e += refit_energy_row(P + lidx(0, y, z), mask + i0, w.normals[0].data() + i0, w.normals[1].data() + i0,
                                      w.normals[2].data() + i0);
            }
        energy[k] = e;
    });
    double sum = 0.0;
    for (const double e : energy) sum += e;
    return sum;
}

}  // namespace

/// One explicit step φ ← φ + dt |∇φ|_upwind (H_φ − hn) on the active samples (phi → w.phi_next,
/// then swapped). Returns D(φ before the step) when with_energy.
double refit_step(StageContext& c, bool with_energy) {
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
            nonfinite |= refit_row(P + lidx(0, y0, z), w.hn.data() + i0, mask + i0, dt, y1 - y0 + 1,
                                   w.phi_next.data() + i0);
            if (with_energy)
                for (int y = y0; y <= y1; ++y) {
                    const std::size_t i = base + std::size_t(bidx(0, y, z));
                    if (any_in_row(mask + i))
                        e += refit_energy_row(P + lidx(0, y, z), mask + i, w.normals[0].data() + i,
                                              w.normals[1].data() + i, w.normals[2].data() + i);
                }
        }
        if (nonfinite) bad = true;
        energy[k] = e;
    });
    if (bad) c.ctl.fail("phi in the refit");
    std::swap(phi, w.phi_next);
    double sum = 0.0;
    for (const double e : energy) sum += e;
    return sum;
}

/// Refit steps until D stops decreasing; φ ends as the iterate with the smallest D seen.
/// Buffers: phi (current), w.phi_next (written by the step), w.spare() (the previous iterate, kept
/// so that a step that raised D can be undone; the buffer the reinitialisation has already
/// written, so no fresh pages are touched). Samples outside the active blocks are equal in
/// all three (refit_step writes only the active blocks).
void refit_to_normals(StageContext& c) {
    WorkBuffers& w = c.band.work();
    Samples& phi = c.band.phi();
    target_curvature(c);  // may use w.phi_next as scratch
    copy_samples(phi, w.phi_next);
    Samples& prev_phi = w.spare();
    copy_samples(phi, prev_phi);
    std::vector<double> ds;  // D of each iterate evaluated
    int steps = 0;
    double prev = 0.0, d_end = 0.0;
    bool stopped = false;
    // The neighbourhood filters' normal maps are not exactly integrable: D wanders a little on its
    // way down, and a stop at its first rise could end the refit after a few steps on one grid
    // and not on the next (sharpsphere_n0.3 at resolution 239: 28 steps, 12.0°; at 230 and 256
    // the whole time, 6.4°). Their refit stops when D has not reached a new low for `patience`
    // steps, or when it rose to twice its low (a refit that runs away), undoing that last step.
    const bool patient = is_neighbourhood_filter(c.opt.mode);
    const int patience = std::max(5, c.opt.refit_max_steps / 20);
    double best = 0.0;
    int since_best = 0;
    for (int s = 0; s < c.opt.refit_max_steps; ++s) {
        std::swap(w.phi_next, prev_phi);  // prev_phi ← φ_{s−1}; w.phi_next is overwritten by the step
        const double d = refit_step(c, true);  // D(φ_s); now w.phi_next = φ_s, phi = φ_{s+1}
        ds.push_back(d);
        c.ctl.tick(0.5 + 0.5 * double(s + 1) / c.opt.refit_max_steps);
        if (patient) {
            if (s == 0 || d < best * (1.0 - c.opt.refit_tolerance)) {
                best = s == 0 ? d : std::min(best, d);
                since_best = 0;
            } else {
                ++since_best;
            }
            if (s > 0 && (since_best >= patience || d > 2.0 * best)) {
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
    SmoothIteration& r = c.record();
    r.refit_energy = std::move(ds);
    r.refit_energy_end = d_end;
    r.refit_steps = steps;
}

}  // namespace normalflow::engine
