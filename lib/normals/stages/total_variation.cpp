// Total variation of the normal map on the surface samples (total_variation.h): the primal–dual
// solver, and the filter of SmoothMode::TotalVariation that runs it (surface_filter.h).
#include "normals/stages/total_variation.h"

#include <cmath>
#include <cstddef>
#include <memory>
#include <vector>

#include "band/iterate.h"
#include "normals/smooth.h"
#include "normals/stages/normal_filter.h"
#include "normals/stages/surface_filter.h"

namespace normalflow::engine {

namespace {

/// |K|² of the forward differences on a 3-D grid is at most 4 per axis; the tangential projection
/// does not increase it. Chambolle & Pock need τσ|K|² <= 1.
constexpr float kNormK2 = 12.0f;

/// Z = Y (I − n nᵀ) for the 3×3 Y of sample i (row c, column a at y[3c + a]).
inline void project_columns(const Samples (&y)[9], const Samples (&n)[3], std::size_t i, float (&z)[9]) {
    const float n0 = n[0][i], n1 = n[1][i], n2 = n[2][i];
    for (int c = 0; c < 3; ++c) {
        const float yc0 = y[3 * c][i], yc1 = y[3 * c + 1][i], yc2 = y[3 * c + 2][i];
        const float d = (yc0 * n0 + yc1 * n1) + yc2 * n2;
        z[3 * c] = yc0 - d * n0;
        z[3 * c + 1] = yc1 - d * n1;
        z[3 * c + 2] = yc2 - d * n2;
    }
}

/// G_i(v) = [D_x v, D_y v, D_z v]_i (I − n_i n_iᵀ), the forward differences to the neighbours in fwd.
inline void tangential_gradient(const Samples (&v)[3], const Samples (&n)[3], const std::vector<std::int32_t> (&fwd)[3],
                                std::size_t i, float (&g)[9]) {
    for (int a = 0; a < 3; ++a) {
        const std::int32_t j = fwd[a][i];
        for (int c = 0; c < 3; ++c) g[3 * c + a] = j >= 0 ? v[c][std::size_t(j)] - v[c][i] : 0.0f;
    }
    const float n0 = n[0][i], n1 = n[1][i], n2 = n[2][i];
    for (int c = 0; c < 3; ++c) {
        const float d = (g[3 * c] * n0 + g[3 * c + 1] * n1) + g[3 * c + 2] * n2;
        g[3 * c] -= d * n0;
        g[3 * c + 1] -= d * n1;
        g[3 * c + 2] -= d * n2;
    }
}

}  // namespace

void TotalVariation::build(const Band& band, const SurfaceSamples& S) {
    S_ = &S;
    const std::size_t n = S.size();
    // band sample → surface sample, for the blocks' own samples and their neighbours'
    std::vector<std::int32_t> at(band.nblocks() * kBlockVoxels, -1);
    for (std::size_t i = 0; i < n; ++i)
        if (S.index[i] != SurfaceSamples::kPadding) at[S.index[i]] = std::int32_t(i);
    for (int a = 0; a < 3; ++a) {
        fwd_[a].assign(n, -1);
        bwd_[a].assign(n, -1);
    }
    band.for_blocks(band.active(), 0, [&](std::size_t, std::int32_t b, Scratch&) {
        const auto& bc = band.block_coord(std::size_t(b));
        for (std::size_t i = S.begin(b); i < S.end(b); ++i) {
            if (S.index[i] == SurfaceSamples::kPadding) continue;
            const int local = int(S.index[i] % kBlockVoxels);
            const int xyz[3] = {local % kBlockDim, (local / kBlockDim) % kBlockDim, local / (kBlockDim * kBlockDim)};
            for (int a = 0; a < 3; ++a)
                for (int s = -1; s <= 1; s += 2) {
                    int q[3] = {xyz[0], xyz[1], xyz[2]};
                    int blk[3] = {bc[0], bc[1], bc[2]};
                    q[a] += s;
                    if (q[a] < 0 || q[a] >= kBlockDim) {
                        blk[a] += s;
                        q[a] = (q[a] + kBlockDim) % kBlockDim;
                    }
                    const std::int32_t slot = band.block_at(blk[0], blk[1], blk[2]);
                    if (slot < 0) continue;
                    const std::int32_t j = at[std::size_t(slot) * kBlockVoxels + std::size_t(bidx(q[0], q[1], q[2]))];
                    (s > 0 ? fwd_ : bwd_)[a][i] = j;
                }
        }
    });
}

void TotalVariation::start(const Samples (&N)[3]) {
    const std::size_t n = S_->size();
    for (int c = 0; c < 3; ++c) {
        copy_samples(N[c], f_[c]);
        copy_samples(N[c], bar_[c]);
    }
    for (auto& y : y_) y.assign(n, 0.0f);
    tau_ = sigma_ = 1.0f / std::sqrt(kNormK2);
}

void TotalVariation::iterate(const Band& band, Samples (&N)[3], float alpha) {
    const SurfaceSamples& S = *S_;
    const std::vector<std::int32_t>& act = band.active();
    const float sigma = sigma_, tau = tau_;
    // dual: Y ← the projection onto |Y|_F <= 1 of Y + σ G(N̄)
    band.for_blocks(act, 0, [&](std::size_t, std::int32_t b, Scratch&) {
        for (std::size_t i = S.begin(b); i < S.end(b); ++i) {
            if (S.index[i] == SurfaceSamples::kPadding) continue;
            float g[9];
            tangential_gradient(bar_, S.n, fwd_, i, g);
            float y[9], len2 = 0.0f;
            for (int k = 0; k < 9; ++k) {
                y[k] = y_[k][i] + sigma * g[k];
                len2 += y[k] * y[k];
            }
            const float s = len2 > 1.0f ? 1.0f / std::sqrt(len2) : 1.0f;
            for (int k = 0; k < 9; ++k) y_[k][i] = y[k] * s;
        }
    });
    // primal: N ← normalize((N − τKᵀY + τα F)/(1 + τα)), Kᵀ Y = −div(Y P); then N̄ extrapolated
    const float theta = 1.0f / std::sqrt(1.0f + 2.0f * alpha * tau);
    band.for_blocks(act, 0, [&](std::size_t, std::int32_t b, Scratch&) {
        for (std::size_t i = S.begin(b); i < S.end(b); ++i) {
            if (S.index[i] == SurfaceSamples::kPadding) continue;
            float kt[3] = {0.0f, 0.0f, 0.0f};
            float z[9];
            project_columns(y_, S.n, i, z);
            for (int a = 0; a < 3; ++a)
                if (fwd_[a][i] >= 0)
                    for (int c = 0; c < 3; ++c) kt[c] -= z[3 * c + a];
            for (int a = 0; a < 3; ++a) {
                const std::int32_t j = bwd_[a][i];
                if (j < 0) continue;
                project_columns(y_, S.n, std::size_t(j), z);
                for (int c = 0; c < 3; ++c) kt[c] += z[3 * c + a];
            }
            float v[3];
            for (int c = 0; c < 3; ++c) v[c] = (N[c][i] - tau * kt[c] + tau * alpha * f_[c][i]) / (1.0f + tau * alpha);
            const float len = std::sqrt((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2]);
            if (!(len > 1e-12f)) continue;  // keep N (and N̄) where the step vanishes
            for (int c = 0; c < 3; ++c) {
                const float nc = v[c] / len;
                bar_[c][i] = nc + theta * (nc - N[c][i]);
                N[c][i] = nc;
            }
        }
    });
    tau_ = theta * tau;
    sigma_ = sigma / theta;
}

double TotalVariation::energy(const Band& band, const Samples (&N)[3], float alpha) const {
    const SurfaceSamples& S = *S_;
    const std::vector<std::int32_t>& act = band.active();
    std::vector<double> per(act.size(), 0.0);
    band.for_blocks(act, 0, [&](std::size_t li, std::int32_t b, Scratch&) {
        double e = 0.0;
        for (std::size_t i = S.begin(b); i < S.end(b); ++i) {
            if (S.index[i] == SurfaceSamples::kPadding) continue;
            float g[9];
            tangential_gradient(N, S.n, fwd_, i, g);
            double g2 = 0.0;
            for (float x : g) g2 += double(x) * x;
            double d2 = 0.0;
            for (int c = 0; c < 3; ++c) d2 += double(N[c][i] - f_[c][i]) * (N[c][i] - f_[c][i]);
            e += std::sqrt(g2) + 0.5 * double(alpha) * d2;
        }
        per[li] = e;
    });
    double total = 0.0;
    for (double e : per) total += e;
    return total;
}

namespace {

/// The filter: normal_steps primal–dual iterations on all the surface samples (no pass loop), the
/// fidelity's length tv_lambda·ℓ; the extension then takes one bilateral pass of the result.
class TotalVariationFilter final : public SurfaceSampleFilter {
public:
    int default_normal_steps() const override { return kTotalVariationSteps; }

private:
    void filter_samples(StageContext& c, const Disc& d) override {
        const float alpha = 1.0f / (c.opt.tv_lambda * d.ell);
        solver_.build(c.band, S_);
        solver_.solve(c.band, cur_, alpha, c.opt.normal_steps, [&] { c.ctl.poll(); });
        energy_[0] = solver_.initial_energy();
        energy_[1] = solver_.energy(c.band, cur_, alpha);
        c.ctl.tick(0.5);
    }

    /// Every sample: the objective's graph joins grid neighbours.
    int stride(const SmoothOptions&, float) const override { return 1; }

    /// The objective E before and after the solve (the G that filter_normals measured before it
    /// is not reported).
    std::vector<double> normal_energy(StageContext&, double) override { return {energy_[0], energy_[1]}; }

    TotalVariation solver_;
    double energy_[2] = {0.0, 0.0};
};

}  // namespace

std::unique_ptr<NormalFilter> make_total_variation_filter() { return std::make_unique<TotalVariationFilter>(); }

}  // namespace normalflow::engine
