// The scan conversion and the engine brick by brick (bricks.h).
#include "normals/bricks.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <string>

#include "band/layout.h"
#include "core/errors.h"

namespace normalflow {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

int round_up(int v, int to) { return (v + to - 1) / to * to; }

// Appends the warnings of `from` that `to` does not hold yet (each brick repeats the same ones).
void add_new(std::vector<std::string>& to, const std::vector<std::string>& from) {
    for (const std::string& w : from)
        if (std::find(to.begin(), to.end(), w) == to.end()) to.push_back(w);
}

/// Voxels along a window's sides inside the grid that the engine does not update (SmoothOptions::fixed_lo): its
/// stencils reach 2 voxels, so the samples they read there are the window's own, held as they came.
constexpr int kFixedBorder = 4;

// One main iteration over the bricks: each brick's window, scan-converted (the first iteration) or copied from the
// last iteration's result `from`, runs one iteration of the engine; its interior goes into `to`.
struct Pass {
    SmoothIteration record;  // the iteration over the whole: sums over the bricks, the roughness of their histograms
    std::vector<std::uint64_t> roughness;        // the bricks' interiors' roughness histograms summed
    double volume_change = 0, volume_slope = 0;  // Σ over the bricks' interiors (defer_volume_shift)
    std::vector<std::string> warnings;
    bool any = false;    // some brick's engine ran
    bool moved = false;  // some brick's refit kept a step
};

// The blocks of `from` in window w, as a volume of their own (the window's grid, the same band and tiles).
Volume window_of(const Volume& from, const BlockWindow& w) {
    Volume v(window_grid(from.grid, w), from.half_width);
    v.background = from.background;
    for (int k = w.lo[2]; k < w.hi[2]; ++k)
        for (int j = w.lo[1]; j < w.hi[1]; ++j)
            for (int i = w.lo[0]; i < w.hi[0]; ++i) {
                const std::int32_t s = from.block_table[from.table_index(i, j, k)];
                if (s < 0) {
                    v.block_table[v.table_index(i - w.lo[0], j - w.lo[1], k - w.lo[2])] = s;
                    continue;
                }
                const std::int32_t d = v.allocate_block(i - w.lo[0], j - w.lo[1], k - w.lo[2]);
                std::copy_n(from.block_values(s), kBlockVoxels, v.block_values(d));
            }
    return v;
}

// reinitialise_only: each window of `from` only reinitialised (reinitialise_volume), as a run ends.
Pass run_pass(const Mesh& m, const ClosestTriangleQuery& q, const WindingNumber* wn, const Grid& grid,
              const ScanConvertOptions& scan, const SmoothOptions& opt, int brick_blocks, int halo_blocks,
              const Volume* from, Volume& to, BrickReport& rep, Progress* progress, double done_before, double share,
              bool reinitialise_only = false) {
    Pass result;
    const auto& gbd = to.block_dims;
    const int total = rep.total();
    int done = 0;
    const auto t_pass = Clock::now();
    for (int bk = 0; bk < gbd[2]; bk += brick_blocks)
        for (int bj = 0; bj < gbd[1]; bj += brick_blocks)
            for (int bi = 0; bi < gbd[0]; bi += brick_blocks) {
                const std::array<int, 3> lo{bi, bj, bk};
                std::array<int, 3> hi{};
                BlockWindow w;
                for (int a = 0; a < 3; ++a) {
                    hi[a] = std::min(lo[a] + brick_blocks, gbd[a]);
                    w.lo[a] = std::max(0, lo[a] - halo_blocks);
                    w.hi[a] = std::min(gbd[a], hi[a] + halo_blocks);
                }
                auto t0 = Clock::now();
                Volume sub = from ? window_of(*from, w) : scan_convert_window(m, q, wn, grid, w, scan);
                rep.seconds_scan += seconds_since(t0);
                const auto slot = [&](const Volume& v, int i, int j, int k) {
                    return v.block_table[v.table_index(i - w.lo[0], j - w.lo[1], k - w.lo[2])];
                };
                // Only a window whose interior holds (or lies within the band of) a surface runs the engine.
                bool interior_band = false;
                for (int k = lo[2]; k < hi[2] && !interior_band; ++k)
                    for (int j = lo[1]; j < hi[1] && !interior_band; ++j)
                        for (int i = lo[0]; i < hi[0] && !interior_band; ++i) interior_band = slot(sub, i, j, k) >= 0;
                if (interior_band && reinitialise_only) {
                    t0 = Clock::now();
                    reinitialise_volume(sub, opt.threads);
                    rep.seconds_smooth += seconds_since(t0);
                } else if (interior_band) {
                    SmoothOptions brick = opt;
                    for (int a = 0; a < 3; ++a) {
                        brick.window_lo[a] = lo[a] - w.lo[a];
                        brick.window_hi[a] = hi[a] - w.lo[a];
                        // the window's sides within the grid hold still: the surface runs on past them
                        brick.fixed_lo[a] = w.lo[a] > 0 ? kFixedBorder : 0;
                        brick.fixed_hi[a] = w.hi[a] < gbd[a] ? kFixedBorder : 0;
                    }
                    t0 = Clock::now();
                    SmoothReport r = smooth_volume(sub, brick);
                    rep.seconds_smooth += seconds_since(t0);
                    if (!r.iterations.empty()) {
                        ++rep.bricks_run;
                        rep.largest_window_blocks = std::max(rep.largest_window_blocks, sub.block_count());
                        const SmoothIteration& it = r.iterations.front();
                        SmoothIteration& sum = result.record;
                        if (result.roughness.size() < it.roughness_histogram.size())
                            result.roughness.resize(it.roughness_histogram.size(), 0);
                        for (std::size_t h = 0; h < it.roughness_histogram.size(); ++h)
                            result.roughness[h] += it.roughness_histogram[h];
                        sum.filter_points += it.filter_points;
                        sum.band_voxels += it.band_voxels;
                        sum.allocated_voxels += it.allocated_voxels;
                        sum.refit_steps = std::max(sum.refit_steps, it.refit_steps);
                        sum.refit_evaluations = std::max(sum.refit_evaluations, it.refit_evaluations);
                        sum.mu = std::max(sum.mu, it.mu);
                        result.volume_change += it.volume_after - it.volume_before;
                        result.volume_slope += it.volume_slope;
                        result.moved |= it.refit_steps > 0 || !is_neighbourhood_filter(opt.mode);
                        result.any = true;
                    }
                    // (a window whose surface lies beyond it, only its band's edge in the interior, has nothing to say)
                    if (!r.iterations.empty()) add_new(result.warnings, r.warnings);
                }
                // The interior into the result: its blocks as the brick's engine left them, its tiles' signs.
                for (int k = lo[2]; k < hi[2]; ++k)
                    for (int j = lo[1]; j < hi[1]; ++j)
                        for (int i = lo[0]; i < hi[0]; ++i) {
                            const std::int32_t s = slot(sub, i, j, k);
                            if (s < 0) {
                                to.block_table[to.table_index(i, j, k)] = s;
                                continue;
                            }
                            const float* src = sub.block_values(s);
                            float* dst = to.block_values(to.allocate_block(i, j, k));
                            // a window without a surface kept the scan's narrower band: its values are distances
                            // all the same, clamped where the result's band is wider
                            for (int n = 0; n < kBlockVoxels; ++n)
                                dst[n] = std::clamp(src[n], -to.background, to.background);
                        }
                ++done;
                detail::tick(progress, done_before + share * double(done) / total, "smooth_in_bricks");
            }
    result.record.roughness = roughness_of_histogram(result.roughness);
    result.record.seconds = seconds_since(t_pass);
    return result;
}

}  // namespace

int brick_halo_voxels(const SmoothOptions& opt, int iterations) {
    const double ell = opt.length_scale > 0 ? opt.length_scale : kDefaultLengthScale;
    const int refit_steps = opt.refit_max_steps > 0 ? opt.refit_max_steps : default_refit_steps(opt);
    const double refit_time = double(refit_steps) * std::min(double(opt.refit_dt), 1.0 / 6.0);
    double reach = 3.0 * std::sqrt(2.0 * refit_time);
    if (is_neighbourhood_filter(opt.mode)) {
        reach += 2.0 * 2.0 * double(opt.sigma_spatial) * ell;
    } else if (opt.mode != SmoothMode::MeanCurvature) {
        const int steps = opt.normal_steps > 0 ? opt.normal_steps : default_normal_steps(opt.mode);
        reach += 3.0 * std::sqrt(2.0 * double(steps) * std::min(double(opt.normal_dt), 1.0 / 6.0));
    }
    return int(std::ceil(reach * std::max(1, iterations) + engine::kHalfWidth));
}

Volume smooth_in_bricks(const Mesh& m, const ClosestTriangleQuery& q, const WindingNumber* wn,
                        const ScanConvertOptions& scan, const SmoothOptions& opt, const BrickOptions& bricks,
                        BrickReport* report, SmoothReport* smooth_report, Progress* progress,
                        const SmoothCheckpoint* checkpoint) {
    validate_smooth_options(opt, "smooth_in_bricks");
    if (bricks.brick_voxels < kBlockDim)
        throw InvalidInput("smooth_in_bricks: brick_voxels must be >= 8, got " + std::to_string(bricks.brick_voxels));
    if (bricks.halo_voxels < 0)
        throw InvalidInput("smooth_in_bricks: halo_voxels must be >= 0, got " + std::to_string(bricks.halo_voxels));
    const Grid grid = scan_grid(m, scan);
    const int iterations = opt.iterations > 0 ? opt.iterations : default_iterations(opt.mode);
    // Windows start on multiples of the filters' sample stride, so that each thins its samples as the whole grid.
    const int unit = std::lcm(kBlockDim, surface_sample_stride(opt)) / kBlockDim;  // in blocks
    const int halo = bricks.halo_voxels > 0 ? bricks.halo_voxels : brick_halo_voxels(opt, 1);
    const int brick_blocks = round_up((bricks.brick_voxels + kBlockDim - 1) / kBlockDim, unit);
    const int halo_blocks = round_up((halo + kBlockDim - 1) / kBlockDim, unit);
    BrickReport rep;
    rep.brick_voxels = brick_blocks * kBlockDim;
    rep.halo_voxels = halo_blocks * kBlockDim;
    for (int a = 0; a < 3; ++a)
        rep.bricks[a] = ((grid.dims[a] + kBlockDim - 1) / kBlockDim + brick_blocks - 1) / brick_blocks;

    // One main iteration at a time over all the bricks, each reading the last one's result around it: what the
    // whole run decides from the whole surface between its iterations is decided here the same way, and in the same
    // order: the refit, the volume constraint's shift (over the whole surface), then the band moved and φ
    // reinitialised (by the next iteration's bricks as they start, or a pass of its own).
    const bool auto_stop = opt.iterations == 0 && is_neighbourhood_filter(opt.mode);
    const bool keep_volume = is_neighbourhood_filter(opt.mode) && opt.preserve_volume;
    SmoothOptions one = opt;
    one.iterations = 1;
    one.refit_whole_time = true;
    one.defer_volume_shift = true;  // the volume constraint (where kept) and the roughness over the interiors
    one.final_reinitialise = false;
    SmoothReport sr;
    Volume cur, next;
    bool raw = false;  // cur is as the last refit left it: its band not moved, φ not reinitialised
    const auto reinitialise = [&] {
        next.reset(grid, engine::kHalfWidth);
        run_pass(m, q, wn, grid, scan, one, brick_blocks, halo_blocks, &cur, next, rep, progress, 1.0, 0.0, true);
        cur = std::move(next);
        raw = false;
    };
    detail::begin(progress, "bricks");
    for (int it = 0; it < iterations; ++it) {
        one.reinitialise_input = it == 0 || raw;
        next.reset(grid, engine::kHalfWidth);
        Pass p = run_pass(m, q, wn, grid, scan, one, brick_blocks, halo_blocks, it == 0 ? nullptr : &cur, next, rep,
                          progress, double(it) / iterations, 1.0 / iterations);
        ++rep.passes;
        add_new(sr.warnings, p.warnings);
        cur = std::move(next);
        if (!p.any) {  // no surface anywhere: the scan's volume, as smooth_volume returns one without a surface
            sr.warnings.push_back("the volume holds no surface (no sign change); returned unchanged");
            break;
        }
        raw = true;
        // The volume constraint on the whole surface: the bricks' interiors' changes and slopes summed.
        if (keep_volume && p.moved && p.volume_slope > 0) {
            // φ grows by the volume gained over its slope: the surface moves back inwards by as much
            const double shift = p.volume_change / p.volume_slope;  // voxels
            const float d = float(shift * grid.voxel_size);
            for (float& x : cur.values) x = std::clamp(x + d, -cur.background, cur.background);
            p.record.volume_shift = float(-shift);
        }
        sr.iterations.push_back(p.record);
        const bool more = it + 1 < iterations;
        if (!p.moved && more) {
            sr.stopped_unchanged = true;
            break;
        }
        if (more && auto_stop && p.record.roughness < kNeighbourhoodRoughness) {
            sr.stopped_smooth = true;
            break;
        }
        if (more && checkpoint && *checkpoint) {
            reinitialise();
            if (!(*checkpoint)(cur)) {
                sr.stopped_at_checkpoint = true;
                break;
            }
        }
    }
    if (raw) reinitialise();
    sr.seconds_refit = rep.seconds_smooth;
    if (smooth_report) *smooth_report = std::move(sr);
    if (report) *report = rep;
    return cur;
}

}  // namespace normalflow
