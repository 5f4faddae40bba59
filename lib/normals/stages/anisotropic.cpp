// The anisotropic normal filter: Perona–Malik on the normals, g(κ²) = exp(−κ²/(2µ²)) (Tasdizen et
// al. 2003, Eq. 20). By default regularised (SmoothOptions::conductance_presmooth_steps): the
// conductance is computed once per main iteration from normals pre-smoothed by isotropic steps
// (Catté, Lions, Morel & Coll 1992) and held during the normal loop, with the robust µ schedule
// (SmoothOptions::mu_robust); with 0 pre-smoothing steps, the paper's live g of the current normals.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "band/gather.h"
#include "band/iterate.h"
#include "normals/kernels/face_row.h"
#include "normals/kernels/face_terms.h"
#include "normals/stages/normal_filter.h"
#include "normals/stages/normal_loop.h"

namespace normalflow::engine {
namespace {

/// κ² at the faces q+½e_a of every allocated sample i for which keep(i, φ_i) holds, from the
/// normals in src: emit(block, a, i, κ²), in parallel over blocks.
template <class Keep, class Emit>
void face_curvatures(const Band& band, const Field3& src, Keep&& keep, Emit&& emit) {
    band.for_blocks(band.all_blocks(), 4, [&](std::size_t, std::int32_t b, Scratch& s) {
        const Neighbourhood& n = band.neighbourhood(std::size_t(b));
        float* P = s.at(0);
        float* N[3] = {s.at(1), s.at(2), s.at(3)};
        gather_phi(n, band.phi(), P);
        gather_n(n, src, N[0], N[1], N[2]);
        const float* Nc[3] = {N[0], N[1], N[2]};
        const std::size_t base = std::size_t(b) * kBlockVoxels;
        for (int a = 0; a < 3; ++a) {
            const int sa = kStride[a], sb = kStride[(a + 1) % 3], sc = kStride[(a + 2) % 3];
            for (int z = 0; z < kBlockDim; ++z)
                for (int y = 0; y < kBlockDim; ++y)
                    for (int x = 0; x < kBlockDim; ++x) {
                        const int q = lidx(x, y, z);
                        const std::size_t i = base + std::size_t(bidx(x, y, z));
                        if (!keep(i, P[q])) continue;
                        float m[3], k2;
                        face_terms(P, Nc, q, sa, sb, sc, m, k2);
                        emit(std::size_t(b), a, i, k2);
                    }
        }
    });
}

/// The robust noise scale of the curvature, σ_κ, from the normals in src (after Black, Sapiro,
/// Marimont & Heeger 1998): the lower quartile of |κ| over the faces of the active samples next
/// to the surface (|φ| <= 1), divided by 0.3186, the quartile of |x| for x ~ N(0, 1). The
/// quartile, not the median: creases and curved parts may cover up to 3/4 of the surface.
float curvature_noise_scale(const Band& band, const Field3& src) {
    const std::uint8_t* mask = band.mask();
    std::vector<std::vector<float>> near(band.nblocks());
    face_curvatures(
        band, src, [&](std::size_t i, float phi) { return mask[i] && std::abs(phi) <= 1.0f; },
        [&](std::size_t b, int, std::size_t, float k2) { near[b].push_back(k2); });
    std::vector<float> k2s;  // in block order: the quartile does not depend on the threads
    for (const auto& v : near) k2s.insert(k2s.end(), v.begin(), v.end());
    if (k2s.empty()) return 0.0f;
    auto q = k2s.begin() + std::ptrdiff_t(k2s.size() / 4);
    std::nth_element(k2s.begin(), q, k2s.end());
    return std::sqrt(std::max(*q, 0.0f)) / 0.3186f;
}

/// g = exp(−κ²/(2µ²)) at every face q+½e_a of the active blocks, q = −1…7 along a and 0…7
/// across (all the faces a normal step reads), from the normals in src (Catté et al.), with the
/// conductance scale mu, into pad_g (the padded layout of NormalLoop::padded_phi).
void conductance_from(StageContext& c, const NormalLoop& loop, const Field3& src, float mu, PaddedFaces (&pad_g)[3]) {
    const Band& bd = c.band;
    const std::vector<std::int32_t>& active = bd.active();
    const float inv2mu2 = 1.0f / (2.0f * mu * mu);
    const float band = c.opt.active_band;
    for (int a = 0; a < 3; ++a) pad_g[a].resize(active.size() * std::size_t(L3));
    bd.for_blocks(active, 7, [&](std::size_t k, std::int32_t b, Scratch& s) {
        const float* P = loop.padded_phi(k);
        float* N[3] = {s.at(0), s.at(1), s.at(2)};
        float* F = s.at(3);  // face fluxes: computed by face_row, unused here
        float* K = s.at(6);
        gather_n(bd.neighbourhood(std::size_t(b)), src, N[0], N[1], N[2]);
        for (int a = 0; a < 3; ++a) {
            float* G = pad_g[a].data() + k * L3;
            int lo[3] = {0, 0, 0};
            lo[a] = -1;
            const int nx = kBlockDim - lo[0];
            for (int z = lo[2]; z < kBlockDim; ++z)
                for (int y = lo[1]; y < kBlockDim; ++y) {
                    const int q0 = lidx(lo[0], y, z);
                    face_rows<FaceWeight::One>(a, P, N[0], nullptr, q0, nx, 1, band, inv2mu2, F, K);
                    for (int j = 0; j < nx; ++j) G[q0 + j] = std::exp(-K[q0 + j] * inv2mu2);
                }
        }
    });
}

/// The conductance scale of this main iteration (see SmoothOptions::mu_robust): µ, or
/// max(µ, mu_robust · σ_κ). σ_κ is measured on the pre-smoothed normals (the noise that the
/// conductance will see), but taken as at most the same scale of the raw normals: on a clean
/// surface the raw normals are exactly flat on its flat parts (σ = 0), while pre-smoothing bends
/// them near every crease, which on a small part can cover most of the surface. The scale is
/// never above the previous iteration's (the schedule only goes from coarse to fine).
float conductance_scale(StageContext& c, const Field3& raw, const Field3& presmoothed) {
    if (!(c.opt.mu_robust > 0.0f)) return c.opt.mu;
    const float sigma = std::min(curvature_noise_scale(c.band, presmoothed), curvature_noise_scale(c.band, raw));
    float mu = std::max(c.opt.mu, c.opt.mu_robust * sigma);
    if (const SmoothIteration* last = c.previous()) mu = std::min(mu, last->mu);
    return mu;
}

class AnisotropicFilter final : public NormalFilter {
public:
    /// 16 main iterations (the tuning is told at SmoothOptions::iterations).
    int default_iterations() const override { return 16; }
    /// The second-order term's G is the Perona–Malik penalty.
    RefitRules refit_rules() const override { return {RefitPenalty::PeronaMalik, RefitSchedule::FirstRise}; }

    void filter_normals(StageContext& c) override {
        WorkBuffers& w = c.band.work();
        loop_.prepare(c);
        FaceWeight cond = FaceWeight::Live;
        if (c.opt.conductance_presmooth_steps > 0) {
            // the pre-smoothed normals in normals_aux, normals_next the ping-pong
            cond = FaceWeight::Frozen;
            copy_fields(w.normals, w.normals_aux);
            copy_fields(w.normals, w.normals_next);
            for (int s = 0; s < c.opt.conductance_presmooth_steps; ++s) {
                c.ctl.poll();
                loop_.step(c, w.normals_aux, w.normals_next, FaceWeight::One, true);
                std::swap(w.normals_aux, w.normals_next);
            }
            const float mu = conductance_scale(c, w.normals, w.normals_aux);
            conductance_from(c, loop_, w.normals_aux, mu, pad_g_);
            c.record().mu = mu;
        } else {
            c.record().mu = c.opt.mu;
        }
        loop_.run(c, cond, pad_g_);
    }

private:
    NormalLoop loop_;
    PaddedFaces pad_g_[3];  // per active block: frozen conductance of the faces, padded_phi's layout
};

}  // namespace

std::unique_ptr<NormalFilter> make_anisotropic_filter() { return std::make_unique<AnisotropicFilter>(); }

}  // namespace normalflow::engine
