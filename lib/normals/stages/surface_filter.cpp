// The base of the filters on the surface samples (surface_filter.h): the samples, the
// neighbourhood sums over them, the roughness the filter left and the extension of its normals to
// the rest of the active band.
#include "normals/stages/surface_filter.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "band/iterate.h"
#include "normals/kernels/pair_sum.h"

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

/// ℓ, voxels: SmoothOptions::length_scale, or kDefaultLengthScale for 0.
float length_scale(const SmoothOptions& opt) {
    return opt.length_scale > 0.0f ? opt.length_scale : kDefaultLengthScale;
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

/// acc = Σ over the samples within √r2 of q among the candidates of the query's run of the pair
/// weights (kernels/pair_sum), range values r, values v.
void gather_candidates(const SurfaceSamples& S, Candidates& c, const Field3& r, const Field3& v, const float q[3],
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

}  // namespace

void SurfaceSampleFilter::filter_normals(StageContext& c) {
    Band& band = c.band;
    WorkBuffers& w = band.work();
    loop_.prepare(c);
    const double g_before = loop_.step(c, w.normals, w.normals_next, FaceWeight::One, false);

    Disc d{};
    d.ell = length_scale(c.opt);
    d.sigma_s = c.opt.sigma_spatial * d.ell;
    d.radius = 2.0f * d.sigma_s;
    d.r2 = d.radius * d.radius;
    d.ks = 1.0f / (2.0f * d.sigma_s * d.sigma_s);
    d.kr = 1.0f / (2.0f * c.opt.sigma_range * c.opt.sigma_range);
    S_.build(band, w.normals, kShell, d.radius, c.opt.active_band, stride(c.opt, d.ell), c.opt.sample_origin);
    c.record().filter_points = std::size_t(
        std::count_if(S_.index.begin(), S_.index.end(), [](std::size_t i) { return i != SurfaceSamples::kPadding; }));
    const std::size_t n = S_.size();
    for (int k = 0; k < 3; ++k) {
        copy_samples(S_.n[k], cur_[k]);
        fit_samples(next_[k], n);
    }
    fit_samples(consistency_, n);

    filter_samples(c, d);
    c.record().roughness = roughness(band, d.ks, d.r2);
    if (c.opt.defer_volume_shift) {  // the window's histogram, for a caller that merges several windows' roughness
        std::vector<std::uint32_t>& hist = c.record().roughness_histogram;
        hist.assign(kRoughnessBins, 0);
        for (std::size_t i = 0; i < S_.size(); ++i) {
            if (!(consistency_[i] >= 0.0f)) continue;
            const auto& bc = band.block_coord(S_.index[i] / kBlockVoxels);
            bool inside = true;
            for (int a = 0; a < 3; ++a) inside &= bc[a] >= c.opt.window_lo[a] && bc[a] < c.opt.window_hi[a];
            if (!inside) continue;
            const int bin = std::clamp(int(consistency_[i] * (kRoughnessBins / 2.0f)), 0, kRoughnessBins - 1);
            ++hist[std::size_t(bin)];
        }
    }
    extend(c, d);
    c.record().normal_energy = normal_energy(c, g_before);
}

int SurfaceSampleFilter::default_refit_steps(const SmoothOptions& opt) const {
    const float ell = length_scale(opt);
    const double steps = std::ceil(double(kNeighbourhoodRefitTime) * ell * ell / std::min(opt.refit_dt, kMaxDt));
    return int(std::clamp(steps, 40.0, 100000.0));
}

int SurfaceSampleFilter::stride(const SmoothOptions& opt, float ell) const {
    return !opt.thin_samples ? 1 : std::max(1, int(std::floor(ell / kStrideLength)));
}

}  // namespace normalflow::engine

namespace normalflow {
float roughness_of_histogram(const std::vector<std::uint64_t>& histogram) {
    std::uint64_t n = 0;
    for (const std::uint64_t c : histogram) n += c;
    if (n == 0) return 0.0f;
    const std::uint64_t q = n * 3 / 4;  // the sample nth_element puts there, counted from 0
    std::uint64_t seen = 0;
    for (std::size_t b = 0; b < histogram.size(); ++b) {
        seen += histogram[b];
        if (seen > q) return (float(b) + 0.5f) * (2.0f / float(histogram.size()));
    }
    return 2.0f;
}

int surface_sample_stride(const SmoothOptions& opt) {
    if (!is_neighbourhood_filter(opt.mode) || !opt.thin_samples) return 1;
    return std::max(1, int(std::floor(engine::length_scale(opt) / engine::kStrideLength)));
}
}  // namespace normalflow

namespace normalflow::engine {

std::vector<double> SurfaceSampleFilter::normal_energy(StageContext& c, double g_before) {
    WorkBuffers& w = c.band.work();
    return {g_before, loop_.step(c, w.normals, w.normals_next, FaceWeight::One, false)};
}

void SurfaceSampleFilter::run_passes(StageContext& c, const Disc& d) {
    for (int pass = 0; pass < c.opt.normal_steps; ++pass) {
        c.ctl.poll();
        before_pass(c.band, d);
        filter_pass(c.band, range(), d, next_);
        for (int k = 0; k < 3; ++k) std::swap(cur_[k], next_[k]);
        c.ctl.tick(0.5 * double(pass + 1) / c.opt.normal_steps);
    }
}

void SurfaceSampleFilter::filter_pass(const Band& band, const Field3& range, const Disc& d, Field3& out) {
    for_samples(band, S_, std::sqrt(d.r2), [&](std::size_t i, Candidates& cand) {
        float acc[32];
        const float q[3] = {S_.p[0][i], S_.p[1][i], S_.p[2][i]};
        const float rq[3] = {range[0][i], range[1][i], range[2][i]};
        gather_candidates(S_, cand, range, cur_, q, rq, d.ks, d.kr, d.r2, acc);
        float o[3];
        if (!normalised(acc, o))
            for (int k = 0; k < 3; ++k) o[k] = cur_[k][i];
        for (int k = 0; k < 3; ++k) out[k][i] = o[k];
    });
}

void SurfaceSampleFilter::gather_near(std::int32_t b, const Field3& r, const Field3& v, const float q[3],
                                      const float rq[3], float ks, float kr, float r2, float (&acc)[32]) const {
    std::fill(acc, acc + 32, 0.0f);
    thread_local std::vector<PairSpan> spans;
    spans.clear();
    for (std::int32_t b2 : S_.near(b)) {
        if (S_.box_distance2(b2, q) > r2) continue;
        for (std::int32_t k = b2 * SurfaceSamples::kRuns; k < (b2 + 1) * SurfaceSamples::kRuns; ++k)
            if (S_.run_distance2(k, q) <= r2) spans.push_back(S_.span(k));
    }
    pair_sum(S_.arrays(r, v), spans.data(), int(spans.size()), q, rq, ks, kr, r2, acc);
}

/// The surface sample nearest to q among the blocks near b within √best (among equally near ones the
/// first by its block's coordinates, so that the answer depends neither on the order the blocks are
/// visited in nor on the slots they hold);
/// kPadding when none is. The block holding q is searched first, so that the others are mostly
/// culled by their boxes.
std::size_t SurfaceSampleFilter::nearest_sample(const Band& band, std::int32_t b, const float q[3], float best) const {
    std::size_t at = SurfaceSamples::kPadding;
    // blocks in the order of their coordinates (near's order): the same in a window as in the whole grid
    const auto by_coords = [&](std::int32_t a, std::int32_t c) {
        const auto &p = band.block_coord(std::size_t(a)), &r = band.block_coord(std::size_t(c));
        return std::tie(p[2], p[1], p[0]) < std::tie(r[2], r[1], r[0]);
    };
    // among equally near samples the first by its block's coordinates, then by its order in the block
    const auto before = [&](std::size_t j, std::size_t k) {
        const std::int32_t bj = std::int32_t(S_.index[j] / kBlockVoxels), bk = std::int32_t(S_.index[k] / kBlockVoxels);
        return bj == bk ? j < k : by_coords(bj, bk);
    };
    auto scan = [&](std::int32_t b2) {
        for (std::size_t j = S_.begin(b2); j < S_.end(b2); ++j) {
            const float dx = S_.p[0][j] - q[0], dy = S_.p[1][j] - q[1], dz = S_.p[2][j] - q[2];
            const float d2 = (dx * dx + dy * dy) + dz * dz;
            if (d2 < best || (d2 == best && S_.index[j] != SurfaceSamples::kPadding &&
                              (at == SurfaceSamples::kPadding || before(j, at)))) {
                best = d2;
                at = j;
            }
        }
    };
    // (the points are in the frame of S_.origin(), a multiple of the block's side)
    const std::array<int, 3>& o = S_.origin();
    const auto cell = [](float v, int o) { return int(std::floor(std::round(v) / float(kBlockDim))) - o / kBlockDim; };
    const std::int32_t home = band.block_at(cell(q[0], o[0]), cell(q[1], o[1]), cell(q[2], o[2]));
    const std::vector<std::int32_t>& near = S_.near(b);
    const bool home_near = home >= 0 && std::binary_search(near.begin(), near.end(), home, by_coords);
    if (home_near) scan(home);
    for (std::int32_t b2 : near)
        if ((b2 != home || !home_near) && S_.box_distance2(b2, q) <= best) scan(b2);
    return at;
}

/// What the filter left: the 75th percentile over the surface samples of |N_i − M_i|, M_i the
/// plain (spatial-only) Gaussian mean of the filtered normals over i's disc. Near 0 where the
/// normal map is smooth at the disc's scale; creases (up to a quarter of the samples) do not
/// count; noise that is left does.
float SurfaceSampleFilter::roughness(const Band& band, float ks, float r2) {
    const std::size_t n = S_.size();
    std::fill(consistency_.begin(), consistency_.end(), -1.0f);
    for_samples(band, S_, std::sqrt(r2), [&](std::size_t i, Candidates& cand) {
        float acc[32];
        const float q[3] = {S_.p[0][i], S_.p[1][i], S_.p[2][i]};
        const float rq[3] = {0, 0, 0};
        gather_candidates(S_, cand, cur_, cur_, q, rq, ks, 0.0f, r2, acc);
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

/// The filtered normals into work().normals: each surface sample its own; every other active
/// sample x (its closest point q = x − φ(x)N(x)) those of the surface sample nearest to q, when
/// one lies within the disc and faces the same way as x's own normal (otherwise x keeps N: the
/// other wall of a groove or a thin part, the far side of a crease's wedge). Which ones: by
/// default, one more pass of the filter at that nearest sample; with extend_by_gather, that
/// pass evaluated at q itself, the range weight against the nearest sample's normal (the same
/// within the fraction of a voxel between q and its nearest sample, at several times the cost).
void SurfaceSampleFilter::extend(StageContext& c, const Disc& d) {
    Band& band = c.band;
    WorkBuffers& w = band.work();
    const Samples& phi = band.phi();
    const std::uint8_t* mask = band.mask();
    const Field3& range = this->range();
    const bool at_q = c.opt.extend_by_gather;
    if (!at_q) filter_pass(band, range, d, next_);
    band.for_blocks(band.active(), 0, [&](std::size_t, std::int32_t b, Scratch&) {
        const auto& bc = band.block_coord(std::size_t(b));
        const std::array<int, 3>& o0 = c.opt.sample_origin;
        const std::size_t base = std::size_t(b) * kBlockVoxels;
        float acc[32];
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x) {
                    const std::size_t i = base + std::size_t(bidx(x, y, z));
                    if (!mask[i] || S_.taken(band, std::size_t(b), x, y, z, phi[i])) continue;
                    const float q[3] = {float(o0[0] + bc[0] * kBlockDim + x) - phi[i] * w.normals[0][i],
                                        float(o0[1] + bc[1] * kBlockDim + y) - phi[i] * w.normals[1][i],
                                        float(o0[2] + bc[2] * kBlockDim + z) - phi[i] * w.normals[2][i]};
                    const std::size_t at = nearest_sample(band, b, q, d.r2);
                    if (at == SurfaceSamples::kPadding) continue;  // nothing within reach: keep N
                    const float rq[3] = {range[0][at], range[1][at], range[2][at]};
                    if ((rq[0] * w.normals[0][i] + rq[1] * w.normals[1][i]) + rq[2] * w.normals[2][i] < kSameSide)
                        continue;
                    float o[3];
                    if (at_q) {
                        gather_near(b, range, cur_, q, rq, d.ks, d.kr, d.r2, acc);
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

}  // namespace normalflow::engine
