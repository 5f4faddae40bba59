// The filters of the normal map on the surface samples: bilateral (the band's counterpart of
// bilateral normal filtering, Zheng, Fu, Au & Tai 2011), guided (the range weight taken on a
// guidance field of patch normals, after Zhang, Deng, Zhang, Bouaziz & Liu 2015) and total
// variation (total_variation.h). Bilateral and guided average the normals of the samples next to
// the surface (SurfaceSamples: |φ| <= kShell, moved to their closest points) over a disc whose size
// is given in the model's units (SmoothOptions::length_scale); total variation minimises its
// energy over the same samples. All three then carry the result to the rest of the active band by
// closest point.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "band/iterate.h"
#include "normals/kernels/pair_sum.h"
#include "normals/stages/normal_filter.h"
#include "normals/stages/normal_loop.h"
#include "normals/stages/surface_samples.h"
#include "normals/stages/total_variation.h"

namespace normalflow::engine {
namespace {

/// Samples with |φ| <= kShell are the point set the filters average (about 1.5 per voxel² of
/// surface, each within 0.75 voxel of its closest point).
constexpr float kShell = 0.75f;
/// The filters take every s-th shell sample along each axis, s = ⌊ℓ / kStrideLength⌋ (ℓ the length
/// scale in voxels): at the automatic resolution (ℓ about 5 voxels) all of them.
constexpr float kStrideLength = 5.0f;
/// The extension takes the filtered normals around a closest point only where the nearest surface
/// sample's normal is within 45° of the sample's own.
constexpr float kSameSide = 0.70710678f;

float lane_total(const float* acc) {
    return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

/// acc = Σ over the samples within √r2 of q (their blocks near block b) of the pair weights
/// (kernels/pair_sum), range values r, values v.
void gather(const SurfaceSamples& S, std::int32_t b, const Samples (&r)[3], const Samples (&v)[3], const float q[3],
            const float rq[3], float ks, float kr, float r2, float (&acc)[32]) {
    std::fill(acc, acc + 32, 0.0f);
    thread_local std::vector<PairSpan> spans;
    spans.clear();
    for (std::int32_t b2 : S.near(b)) {
        if (S.box_distance2(b2, q) > r2) continue;
        for (std::int32_t k = b2 * SurfaceSamples::kRuns; k < (b2 + 1) * SurfaceSamples::kRuns; ++k)
            if (S.run_distance2(k, q) <= r2) spans.push_back(S.span(k));
    }
    pair_sum(S.arrays(r, v), spans.data(), int(spans.size()), q, rq, ks, kr, r2, acc);
}

/// The candidate runs of the queries of one run (SurfaceSamples::candidates): their spans and
/// boxes (struct of arrays, so that the test of each query against them vectorises).
struct Candidates {
    std::vector<std::int32_t> runs;
    std::vector<PairSpan> spans, selected;
    std::vector<float> lo[3], hi[3];
    void set(const SurfaceSamples& S) {
        spans.clear();
        for (int a = 0; a < 3; ++a) {
            lo[a].clear();
            hi[a].clear();
        }
        for (const std::int32_t r : runs) {
            spans.push_back(S.span(r));
            for (std::size_t a = 0; a < 3; ++a) {
                lo[a].push_back(S.run_lo(r)[a]);
                hi[a].push_back(S.run_hi(r)[a]);
            }
        }
        selected.resize(spans.size());
    }
};

/// The same over the candidates of the query's run.
void gather(const SurfaceSamples& S, Candidates& c, const Samples (&r)[3], const Samples (&v)[3], const float q[3],
            const float rq[3], float ks, float kr, float r2, float (&acc)[32]) {
    std::fill(acc, acc + 32, 0.0f);
    const std::size_t m = c.spans.size();
    int k = 0;
    for (std::size_t j = 0; j < m; ++j) {
        const float dx = std::max({c.lo[0][j] - q[0], q[0] - c.hi[0][j], 0.0f});
        const float dy = std::max({c.lo[1][j] - q[1], q[1] - c.hi[1][j], 0.0f});
        const float dz = std::max({c.lo[2][j] - q[2], q[2] - c.hi[2][j], 0.0f});
        c.selected[std::size_t(k)] = c.spans[j];
        k += (dx * dx + dy * dy) + dz * dz <= r2 ? 1 : 0;
    }
    pair_sum(S.arrays(r, v), c.selected.data(), k, q, rq, ks, kr, r2, acc);
}

/// f(i, candidates of i's run) for every surface sample i (padding skipped) of the active blocks.
template <class F>
void for_samples(const Band& band, const SurfaceSamples& S, float reach, F&& f) {
    band.for_blocks(band.active(), 0, [&](std::size_t, std::int32_t b, Scratch&) {
        thread_local Candidates cand;
        for (int k = 0; k < SurfaceSamples::kRuns; ++k) {
            if (S.run_empty(b, k)) continue;
            S.candidates(b, k, reach, cand.runs);
            cand.set(S);
            for (std::size_t i = S.run_begin(b, k); i < S.run_end(b, k); ++i)
                if (S.index[i] != SurfaceSamples::kPadding) f(i, cand);
        }
    });
}

/// (x, y, z) = the lane totals of acc normalised; false when they vanish.
bool normalised(const float (&acc)[32], float out[3]) {
    const float x = lane_total(acc), y = lane_total(acc + 8), z = lane_total(acc + 16);
    const float len = std::sqrt((x * x + y * y) + z * z);
    if (!(len > 1e-12f)) return false;
    out[0] = x / len;
    out[1] = y / len;
    out[2] = z / len;
    return true;
}

enum class Kind { Bilateral, Guided, TotalVariation };

class NeighbourhoodFilter final : public NormalFilter {
public:
    explicit NeighbourhoodFilter(Kind kind) : guided_(kind == Kind::Guided), tv_(kind == Kind::TotalVariation) {}

    void filter_normals(StageContext& c) override {
        Band& band = c.band;
        WorkBuffers& w = band.work();
        loop_.prepare(c);
        std::vector<double> energy;
        energy.push_back(loop_.step(c, w.normals, w.normals_next, FaceWeight::One, false));

        const float ell = c.opt.length_scale > 0.0f ? c.opt.length_scale : kDefaultLengthScale;
        const float sigma_s = c.opt.sigma_spatial * ell;
        const float radius = 2.0f * sigma_s;
        const float r2 = radius * radius;
        const float ks = 1.0f / (2.0f * sigma_s * sigma_s);
        const float kr = 1.0f / (2.0f * c.opt.sigma_range * c.opt.sigma_range);
        // The points: every s-th shell sample along each axis, s = ⌊ℓ / kStrideLength⌋: about as
        // many per ℓ² at any resolution, so that a finer grid costs no more here (total variation
        // keeps them all: its graph joins grid neighbours).
        const int stride = tv_ || !c.opt.thin_samples ? 1 : std::max(1, int(std::floor(ell / kStrideLength)));
        S_.build(band, w.normals, kShell, radius, c.opt.active_band, stride);
        c.record().filter_points = std::size_t(std::count_if(
            S_.index.begin(), S_.index.end(), [](std::size_t i) { return i != SurfaceSamples::kPadding; }));
        const std::size_t n = S_.size();
        for (int k = 0; k < 3; ++k) {
            copy_samples(S_.n[k], cur_[k]);
            fit_samples(next_[k], n);
            if (guided_) {
                fit_samples(guide_[k], n);
                fit_samples(mean_[k], n);
            }
        }
        fit_samples(consistency_, n);  // the guidance's patch consistency; roughness's scratch

        if (tv_) {  // normal_energy: the total-variation objective before and after its solve
            const float alpha = 1.0f / (c.opt.tv_lambda * ell);
            tv_solver_.build(band, S_);
            tv_solver_.solve(band, cur_, alpha, c.opt.normal_steps, [&] { c.ctl.poll(); });
            energy.clear();
            energy.push_back(tv_solver_.initial_energy());
            energy.push_back(tv_solver_.energy(band, cur_, alpha));
            c.ctl.tick(0.5);
        }
        for (int pass = 0; pass < (tv_ ? 0 : c.opt.normal_steps); ++pass) {
            c.ctl.poll();
            if (guided_) guidance(band, radius);
            const Samples(&range)[3] = guided_ ? guide_ : cur_;
            filter_pass(band, range, ks, kr, r2, next_);
            for (int k = 0; k < 3; ++k) std::swap(cur_[k], next_[k]);
            c.ctl.tick(0.5 * double(pass + 1) / c.opt.normal_steps);
        }
        c.record().roughness = roughness(band, ks, r2);
        extend(c, ks, kr, r2);
        if (!tv_) energy.push_back(loop_.step(c, w.normals, w.normals_next, FaceWeight::One, false));
        c.record().normal_energy = std::move(energy);
    }

private:
    /// One pass of the filter over the surface samples: out_i = normalised Σ_j w_ij cur_j, the
    /// range weight on `range` (cur_ or the guidance), cur_i where the weights vanish.
    void filter_pass(const Band& band, const Samples (&range)[3], float ks, float kr, float r2, Samples (&out)[3]) {
        for_samples(band, S_, std::sqrt(r2), [&](std::size_t i, Candidates& cand) {
            float acc[32];
            const float q[3] = {S_.p[0][i], S_.p[1][i], S_.p[2][i]};
            const float rq[3] = {range[0][i], range[1][i], range[2][i]};
            gather(S_, cand, range, cur_, q, rq, ks, kr, r2, acc);
            float o[3];
            if (!normalised(acc, o))
                for (int k = 0; k < 3; ++k) o[k] = cur_[k][i];
            for (int k = 0; k < 3; ++k) out[k][i] = o[k];
        });
    }

    /// The surface sample nearest to q among the blocks near b within √best (the smallest index
    /// among equally near ones, so the answer does not depend on the order the blocks are
    /// visited in); kPadding when none is. The block holding q is searched first, so that the
    /// others are mostly culled by their boxes.
    std::size_t nearest_sample(const Band& band, std::int32_t b, const float q[3], float best) const {
        std::size_t at = SurfaceSamples::kPadding;
        auto scan = [&](std::int32_t b2) {
            for (std::size_t j = S_.begin(b2); j < S_.end(b2); ++j) {
                const float dx = S_.p[0][j] - q[0], dy = S_.p[1][j] - q[1], dz = S_.p[2][j] - q[2];
                const float d2 = (dx * dx + dy * dy) + dz * dz;
                if (d2 < best || (d2 == best && j < at)) {
                    best = d2;
                    at = j;
                }
            }
        };
        const auto cell = [](float v) { return int(std::floor(std::round(v) / float(kBlockDim))); };
        const std::int32_t home = band.block_at(cell(q[0]), cell(q[1]), cell(q[2]));
        const std::vector<std::int32_t>& near = S_.near(b);
        const bool home_near = home >= 0 && std::binary_search(near.begin(), near.end(), home);
        if (home_near) scan(home);
        for (std::int32_t b2 : near)
            if ((b2 != home || !home_near) && S_.box_distance2(b2, q) <= best) scan(b2);
        return at;
    }

    /// What the filter left: the 75th percentile over the surface samples of |N_i − M_i|, M_i the
    /// plain (spatial-only) Gaussian mean of the filtered normals over i's disc. Near 0 where the
    /// normal map is smooth at the disc's scale; creases (up to a quarter of the samples) do not
    /// count; noise that is left does.
    float roughness(const Band& band, float ks, float r2) {
        const std::size_t n = S_.size();
        std::fill(consistency_.begin(), consistency_.end(), -1.0f);
        for_samples(band, S_, std::sqrt(r2), [&](std::size_t i, Candidates& cand) {
            float acc[32];
            const float q[3] = {S_.p[0][i], S_.p[1][i], S_.p[2][i]};
            const float rq[3] = {0, 0, 0};
            gather(S_, cand, cur_, cur_, q, rq, ks, 0.0f, r2, acc);
            float o[3];
            if (!normalised(acc, o)) return;
            const float dx = cur_[0][i] - o[0], dy = cur_[1][i] - o[1], dz = cur_[2][i] - o[2];
            consistency_[i] = std::sqrt((dx * dx + dy * dy) + dz * dz);
        });
        std::vector<float> v;
        v.reserve(n);
        for (std::size_t i = 0; i < n; ++i)
            if (consistency_[i] >= 0.0f) v.push_back(consistency_[i]);
        if (v.empty()) return 0.0f;
        const auto q = v.begin() + std::ptrdiff_t(v.size() * 3 / 4);
        std::nth_element(v.begin(), q, v.end());
        return *q;
    }

    /// The guidance of each surface sample: the mean normal of the most consistent patch (the
    /// samples within `patch` of a centre) among the patches centred within `patch` of it;
    /// consistency = |Σ N| / count, 1 for a patch of equal normals. A patch on one side of a
    /// crease is more consistent than one across it, so the guidance keeps the crease sharp
    /// while the noise, averaged over the patch, leaves it.
    void guidance(const Band& band, float radius) {
        const float patch = 0.5f * radius;
        const float p2 = patch * patch;
        const std::vector<std::int32_t>& act = band.active();
        band.for_blocks(act, 0, [&](std::size_t, std::int32_t b, Scratch&) {
            float acc[32];
            for (std::size_t i = S_.begin(b); i < S_.end(b); ++i) {
                if (S_.index[i] == SurfaceSamples::kPadding) {
                    consistency_[i] = -1.0f;
                    continue;
                }
                const float q[3] = {S_.p[0][i], S_.p[1][i], S_.p[2][i]};
                const float rq[3] = {0, 0, 0};
                gather(S_, b, cur_, cur_, q, rq, 0.0f, 0.0f, p2, acc);
                const float x = lane_total(acc), y = lane_total(acc + 8), z = lane_total(acc + 16);
                const float cnt = lane_total(acc + 24);
                const float len = std::sqrt((x * x + y * y) + z * z);
                consistency_[i] = cnt > 0.0f ? len / cnt : 0.0f;
                const float inv = len > 1e-12f ? 1.0f / len : 0.0f;
                mean_[0][i] = x * inv;
                mean_[1][i] = y * inv;
                mean_[2][i] = z * inv;
            }
        });
        band.for_blocks(act, 0, [&](std::size_t, std::int32_t b, Scratch&) {
            for (std::size_t i = S_.begin(b); i < S_.end(b); ++i) {
                if (S_.index[i] == SurfaceSamples::kPadding) continue;
                const float q[3] = {S_.p[0][i], S_.p[1][i], S_.p[2][i]};
                float best = -1.0f;
                std::size_t at = i;
                for (std::int32_t b2 : S_.near(b)) {
                    if (S_.box_distance2(b2, q) > p2) continue;
                    for (std::size_t j = S_.begin(b2); j < S_.end(b2); ++j) {
                        const float dx = S_.p[0][j] - q[0], dy = S_.p[1][j] - q[1], dz = S_.p[2][j] - q[2];
                        if ((dx * dx + dy * dy) + dz * dz <= p2 && consistency_[j] > best) {
                            best = consistency_[j];
                            at = j;
                        }
                    }
                }
                for (int k = 0; k < 3; ++k) guide_[k][i] = mean_[k][at];
            }
        });
    }

    /// The filtered normals into work().normals: each surface sample its own; every other active
    /// sample x (its closest point q = x − φ(x)N(x)) those of the surface sample nearest to q, when
    /// one lies within the disc and faces the same way as x's own normal (otherwise x keeps N: the
    /// other wall of a groove or a thin part, the far side of a crease's wedge). Which ones: by
    /// default, one more pass of the filter at that nearest sample; with extend_by_gather, that
    /// pass evaluated at q itself, the range weight against the nearest sample's normal (the same
    /// within the fraction of a voxel between q and its nearest sample, at several times the cost).
    void extend(StageContext& c, float ks, float kr, float r2) {
        Band& band = c.band;
        WorkBuffers& w = band.work();
        const Samples& phi = band.phi();
        const std::uint8_t* mask = band.mask();
        const Samples(&range)[3] = guided_ ? guide_ : cur_;
        const bool at_q = c.opt.extend_by_gather;
        if (!at_q) filter_pass(band, range, ks, kr, r2, next_);
        band.for_blocks(band.active(), 0, [&](std::size_t, std::int32_t b, Scratch&) {
            const auto& bc = band.block_coord(std::size_t(b));
            const std::size_t base = std::size_t(b) * kBlockVoxels;
            float acc[32];
            for (int z = 0; z < kBlockDim; ++z)
                for (int y = 0; y < kBlockDim; ++y)
                    for (int x = 0; x < kBlockDim; ++x) {
                        const std::size_t i = base + std::size_t(bidx(x, y, z));
                        if (!mask[i] || S_.taken(band, std::size_t(b), x, y, z, phi[i])) continue;
                        const float q[3] = {float(bc[0] * kBlockDim + x) - phi[i] * w.normals[0][i],
                                            float(bc[1] * kBlockDim + y) - phi[i] * w.normals[1][i],
                                            float(bc[2] * kBlockDim + z) - phi[i] * w.normals[2][i]};
                        const std::size_t at = nearest_sample(band, b, q, r2);
                        if (at == SurfaceSamples::kPadding) continue;  // nothing within reach: keep N
                        const float rq[3] = {range[0][at], range[1][at], range[2][at]};
                        if ((rq[0] * w.normals[0][i] + rq[1] * w.normals[1][i]) + rq[2] * w.normals[2][i] < kSameSide)
                            continue;
                        float o[3];
                        if (at_q) {
                            gather(S_, b, range, cur_, q, rq, ks, kr, r2, acc);
                            if (!normalised(acc, o)) continue;
                        } else {
                            for (int k = 0; k < 3; ++k) o[k] = next_[k][at];
                        }
                        for (int k = 0; k < 3; ++k) w.normals[k][i] = o[k];
                    }
            // the surface samples of this block: their own filtered normals
            for (std::size_t j = S_.begin(b); j < S_.end(b); ++j) {
                const std::size_t i = S_.index[j];
                if (i == SurfaceSamples::kPadding) continue;
                for (int k = 0; k < 3; ++k) w.normals[k][i] = cur_[k][j];
            }
        });
    }

    bool guided_, tv_;
    TotalVariation tv_solver_;
    NormalLoop loop_;
    SurfaceSamples S_;
    Samples cur_[3], next_[3], guide_[3], mean_[3];
    Samples consistency_;
};

}  // namespace

std::unique_ptr<NormalFilter> make_bilateral_filter() { return std::make_unique<NeighbourhoodFilter>(Kind::Bilateral); }
std::unique_ptr<NormalFilter> make_guided_filter() { return std::make_unique<NeighbourhoodFilter>(Kind::Guided); }
std::unique_ptr<NormalFilter> make_total_variation_filter() {
    return std::make_unique<NeighbourhoodFilter>(Kind::TotalVariation);
}

}  // namespace normalflow::engine
