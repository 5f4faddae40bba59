// The scan conversion and the engine brick by brick (bricks.h).
#include "normals/bricks.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <deque>
#include <future>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>

#include "band/layout.h"
#include "core/errors.h"
#include "core/version.h"
#include "normals/stages/volume_constraint.h"

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
/// Voxels inside the held border over which it gives way (SmoothOptions::fixed_zone), at most: 16, four times the held
/// layer, the noise of fandisk_n0.3 at 512 (3.8 voxels) four times over; a quarter of the halo where that is less.
/// fandisk_n0.3 at 512 in bricks of 256 with a halo of 128: no window runs away (one did without it); at 256 in
/// bricks of 128 the result is the same with 0, 8 or 16.
constexpr int kFixedZone = 16;

// One main iteration over the bricks: each brick's window, scan-converted (the first iteration) or copied from the
// last iteration's result `from`, runs one iteration of the engine; its interior goes into `to`.
struct Pass {
    SmoothIteration record;  // the iteration over the whole: sums over the bricks, the roughness of their histograms
    std::vector<std::uint64_t> roughness;        // the bricks' interiors' roughness histograms summed
    double volume_change = 0, volume_slope = 0;  // Σ over the bricks' interiors (defer_volume_shift)
    std::vector<std::string> warnings;
    bool any = false;                  // some brick's engine ran
    bool moved = false;                // some brick's refit kept a step
    std::vector<double> refit_energy;  // the whole surface's D where the refit checks it: the bricks' interiors' summed
    bool refit_energy_aligned = true;  // every brick checked D as often (none restarted its refit, none of its
                                       // explicit steps ran away); else refit_energy sums the steps all took
};

// The result's band as the run holds it between passes: a volume's blocks and tiles, their values in floats or
// (BrickOptions::compact_band) in 16 bits over [−background, background], half the bytes: a step of 2·background /
// 65536 (2.4·10⁻⁴ voxel at the engine's band of 8 voxels), each value at the middle of its step, so that none is 0 and
// every sign is kept. Its arrays are reserved for the blocks the run expects, so that growing them never holds an old
// and a new copy at once.
class HeldBand {
public:
    void reset(const Grid& g, bool compact, std::size_t expected_blocks) {
        v_ = Volume(g, engine::kHalfWidth);
        compact_ = compact;
        q_.clear();
        q_.shrink_to_fit();
        v_.block_coords.reserve(expected_blocks);
        if (compact)
            q_.reserve(expected_blocks * kBlockVoxels);
        else
            v_.values.reserve(expected_blocks * kBlockVoxels);
    }
    const Volume& layout() const { return v_; }  ///< grid, tables and tiles (values only where not compact)
    std::size_t block_count() const { return v_.block_count(); }
    void set_tile(int i, int j, int k, std::int32_t tile) { v_.block_table[v_.table_index(i, j, k)] = tile; }
    /// Block (i, j, k) set to src, clamped to ±background.
    void write(int i, int j, int k, const float* src) {
        const float bg = v_.background;
        if (!compact_) {
            float* dst = v_.block_values(v_.allocate_block(i, j, k));
            for (int x = 0; x < kBlockVoxels; ++x) dst[x] = std::clamp(src[x], -bg, bg);
            return;
        }
        std::int32_t& slot = v_.block_table[v_.table_index(i, j, k)];
        if (slot < 0) {
            slot = std::int32_t(v_.block_coords.size());
            v_.block_coords.push_back({i, j, k});
            q_.resize(q_.size() + kBlockVoxels);
        }
        std::int16_t* dst = q_.data() + std::size_t(slot) * kBlockVoxels;
        for (int x = 0; x < kBlockVoxels; ++x) dst[x] = level(src[x], bg);
    }
    /// The 512 values of allocated block slot s.
    void read(std::int32_t s, float* dst) const {
        if (!compact_) {
            std::copy_n(v_.values.data() + std::size_t(s) * kBlockVoxels, kBlockVoxels, dst);
            return;
        }
        unpack(q_.data() + std::size_t(s) * kBlockVoxels, kBlockVoxels, v_.background, dst);
    }
    /// f(value) for every value of every allocated block, in order.
    template <class F>
    void for_each_value(F&& f) const {
        if (!compact_) {
            for (const float x : v_.values) f(x);
            return;
        }
        const float step = step_of(v_.background);
        for (const std::int16_t x : q_) f(value(x, step));
    }
    /// Every value moved by d (world units), clamped to ±background.
    void shift(float d) {
        const float bg = v_.background;
        if (!compact_) {
            for (float& x : v_.values) x = std::clamp(x + d, -bg, bg);
            return;
        }
        const float step = step_of(bg);
        for (std::int16_t& x : q_) x = level(value(x, step) + d, bg);
    }
    /// As a volume of floats: the held one itself, or (compact) a copy (6 bytes a sample while both live).
    const Volume& volume(Volume& scratch) const {
        if (!compact_) return v_;
        scratch = v_;
        scratch.values.resize(v_.block_count() * kBlockVoxels);
        unpack(q_.data(), q_.size(), v_.background, scratch.values.data());
        return scratch;
    }
    Volume take() && {
        Volume out = std::move(v_);
        if (compact_) {
            out.values.resize(q_.size());
            unpack(q_.data(), q_.size(), out.background, out.values.data());
            q_ = {};
        }
        return out;
    }

private:
    // x's step of the 65536 over [−bg, bg] (a NaN, which the engine does not leave, as the outside)
    static std::int16_t level(float x, float bg) {
        const float f = std::floor(std::clamp(x != x ? bg : x, -bg, bg) * (32768.0f / bg));
        return std::int16_t(std::clamp(f, -32768.0f, 32767.0f));
    }
    // the width of a step over [−bg, bg], and the value of level q: the middle of its step
    static float step_of(float bg) { return 2.0f * bg / 65536.0f; }
    static float value(std::int16_t q, float step) { return (float(q) + 0.5f) * step; }
    static void unpack(const std::int16_t* q, std::size_t n, float bg, float* dst) {
        const float step = step_of(bg);
        for (std::size_t x = 0; x < n; ++x) dst[x] = value(q[x], step);
    }
    Volume v_;
    std::vector<std::int16_t> q_;
    bool compact_ = false;
};

// The blocks of `from` in window w, as a volume of their own (the window's grid, the same band and tiles).
Volume window_of(const HeldBand& held, const BlockWindow& w) {
    const Volume& from = held.layout();
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
                held.read(s, v.block_values(d));
            }
    return v;
}

// The blocks of window `in` (a volume over window_grid(grid, w)) within blocks lo … hi of the grid, as a volume of
// their own over window_grid(grid, {lo, hi}): blocks and tile signs.
Volume interior_of(const Volume& in, const Grid& grid, const BlockWindow& w, const std::array<int, 3>& lo,
                   const std::array<int, 3>& hi) {
    Volume v(window_grid(grid, BlockWindow{lo, hi}), in.half_width);
    v.background = in.background;
    for (int k = lo[2]; k < hi[2]; ++k)
        for (int j = lo[1]; j < hi[1]; ++j)
            for (int i = lo[0]; i < hi[0]; ++i) {
                const std::int32_t s = in.block_table[in.table_index(i - w.lo[0], j - w.lo[1], k - w.lo[2])];
                if (s < 0) {
                    v.block_table[v.table_index(i - lo[0], j - lo[1], k - lo[2])] = s;
                    continue;
                }
                const std::int32_t d = v.allocate_block(i - lo[0], j - lo[1], k - lo[2]);
                std::copy_n(in.block_values(s), kBlockVoxels, v.block_values(d));
            }
    return v;
}

// The bricks one after the other, here.
void run_here(const BrickContext& c, int count, const std::function<BrickJob(int)>& make,
              const std::function<void(BrickOutcome&&)>& take) {
    for (int i = 0; i < count; ++i) take(run_brick(c, make(i)));
}

// The bricks `at_once` at a time on threads of their own: jobs made and outcomes taken on the calling thread, in
// order, the engine's threads shared out among the bricks.
BrickRunner run_on_threads(int at_once) {
    return [at_once](const BrickContext& c, int count, const std::function<BrickJob(int)>& make,
                     const std::function<void(BrickOutcome &&)>& take) {
        // A stop asked on the calling thread (which alone may ask c.progress) reaches the bricks through a flag.
        std::atomic<bool> stop{false};
        struct FlagStop final : Progress {
            const std::atomic<bool>* flag = nullptr;
            bool should_stop() override { return flag->load(); }
        } flag_stop;
        flag_stop.flag = &stop;
        BrickContext each = c;
        each.progress = c.progress ? &flag_stop : nullptr;
        const int threads =
            c.engine.threads > 0 ? c.engine.threads : int(std::max(1u, std::thread::hardware_concurrency()));
        each.engine.threads = std::max(1, threads / at_once);
        std::deque<std::future<BrickOutcome>> running;
        int made = 0;
        try {
            for (int taken = 0; taken < count; ++taken) {
                while (made < count && made - taken < at_once)
                    running.push_back(std::async(std::launch::async, run_brick, std::cref(each), make(made++)));
                // asked before the brick comes back, whether or not it is done: a stop takes no more bricks
                for (;;) {
                    if (c.progress && c.progress->should_stop()) throw Cancelled("smooth_in_bricks: cancelled");
                    if (!c.progress ||
                        running.front().wait_for(std::chrono::milliseconds(50)) == std::future_status::ready)
                        break;
                }
                BrickOutcome o = running.front().get();
                running.pop_front();
                take(std::move(o));
            }
        } catch (...) {
            stop = true;  // the bricks still running stop at their next step; running's futures wait for them
            throw;
        }
    };
}

// One main iteration over the bricks: each brick's window, scan-converted (the first iteration) or copied from the
// last iteration's result `from`, runs one iteration of the engine; its interior goes into `to`.
// reinitialise_only: each window of `from` only reinitialised (reinitialise_volume), as a run ends.
Pass run_pass(const BrickContext& c, const BrickRunner& runner, int brick_blocks, int halo_blocks, const HeldBand* from,
              HeldBand& to, BrickReport& rep, Progress* progress, double done_before, double share,
              bool reinitialise_input, bool reinitialise_only = false, const BrickRefit& refit = {}) {
    Pass result;
    const auto& gbd = to.layout().block_dims;
    std::array<int, 3> n{};
    for (int a = 0; a < 3; ++a) n[a] = (gbd[a] + brick_blocks - 1) / brick_blocks;
    const int total = n[0] * n[1] * n[2];
    const auto t_pass = Clock::now();
    const auto place = [&](int index) {
        BrickJob job;
        job.index = index;
        const std::array<int, 3> b{index % n[0], index / n[0] % n[1], index / (n[0] * n[1])};
        for (int a = 0; a < 3; ++a) {
            job.lo[a] = b[a] * brick_blocks;
            job.hi[a] = std::min(job.lo[a] + brick_blocks, gbd[a]);
            job.window.lo[a] = std::max(0, job.lo[a] - halo_blocks);
            job.window.hi[a] = std::min(gbd[a], job.hi[a] + halo_blocks);
        }
        return job;
    };
    const auto make = [&](int index) {
        if (index < 0 || index >= total) throw std::logic_error("smooth_in_bricks: no brick " + std::to_string(index));
        BrickJob job = place(index);
        job.scan = from == nullptr;
        job.reinitialise_only = reinitialise_only;
        job.reinitialise_input = reinitialise_input;
        job.refit = refit;
        const auto t0 = Clock::now();
        if (from) job.input = window_of(*from, job.window);
        rep.seconds_scan += seconds_since(t0);
        return job;
    };
    int next = 0;
    // Within a brick run here: the pass's share of the line moves on through the brick, and a stop asked for stops it.
    class WithinBrick final : public Progress {
    public:
        WithinBrick(Progress* outer, double from, double width, const int& next)
            : outer_(outer), from_(from), width_(width), next_(next) {}
        void progress(double f) override {
            outer_->progress(from_ + width_ * (double(next_) + std::clamp(f, 0.0, 1.0)));
        }
        bool should_stop() override { return outer_->should_stop(); }

    private:
        Progress* outer_;
        double from_, width_;
        const int& next_;
    } within(progress, done_before, share / total, next);
    BrickContext here = c;
    here.progress = progress ? &within : nullptr;
    const auto take = [&](BrickOutcome&& o) {
        if (o.index != next)
            throw std::logic_error("smooth_in_bricks: brick " + std::to_string(o.index) + " came back in place of " +
                                   std::to_string(next));
        ++next;
        rep.seconds_scan += o.seconds_scan;
        rep.seconds_smooth += o.seconds_smooth;
        if (o.ran && !reinitialise_only) {
            ++rep.bricks_run;
            rep.largest_window_blocks = std::max(rep.largest_window_blocks, o.window_blocks);
            const SmoothIteration& it = o.record;
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
            result.moved |= it.refit_steps > 0 || !is_neighbourhood_filter(c.engine.mode);
            if (!result.any) result.refit_energy.assign(it.refit_window_energy.size(), 0.0);
            // bricks that checked D a different number of times: the sums over the steps they all took
            if (it.refit_window_energy.size() != result.refit_energy.size()) {
                result.refit_energy_aligned = false;
                if (it.refit_window_energy.size() < result.refit_energy.size())
                    result.refit_energy.resize(it.refit_window_energy.size());
            }
            for (std::size_t e = 0; e < std::min(result.refit_energy.size(), it.refit_window_energy.size()); ++e)
                result.refit_energy[e] += it.refit_window_energy[e];
            result.any = true;
            add_new(result.warnings, o.warnings);
        }
        // The interior into the result: its blocks as the brick's engine left them, its tiles' signs.
        const Volume& in = o.interior;
        const std::array<int, 3> lo = place(o.index).lo;
        if (in.block_table.size() != std::size_t(in.block_dims[0]) * in.block_dims[1] * in.block_dims[2] ||
            in.values.size() != in.block_count() * kBlockVoxels)
            throw InvalidInput("smooth_in_bricks: brick " + std::to_string(o.index) + " came back malformed");
        for (int a = 0; a < 3; ++a)
            if (lo[a] + in.block_dims[a] > gbd[a])
                throw InvalidInput("smooth_in_bricks: brick " + std::to_string(o.index) + " came back too large");
        for (int k = 0; k < in.block_dims[2]; ++k)
            for (int j = 0; j < in.block_dims[1]; ++j)
                for (int i = 0; i < in.block_dims[0]; ++i) {
                    const std::int32_t s = in.block_table[in.table_index(i, j, k)];
                    // a window without a surface kept the scan's narrower band: its values are distances all the
                    // same, clamped where the result's band is wider
                    if (s < 0)
                        to.set_tile(i + lo[0], j + lo[1], k + lo[2], s);
                    else
                        to.write(i + lo[0], j + lo[1], k + lo[2], in.block_values(s));
                }
        detail::tick(progress, done_before + share * double(next) / total, "smooth_in_bricks");
    };
    runner(here, total, make, take);
    if (next != total)
        throw std::logic_error("smooth_in_bricks: " + std::to_string(total - next) + " bricks did not come back");
    result.record.roughness = roughness_of_histogram(result.roughness);
    result.record.seconds = seconds_since(t_pass);
    return result;
}

/// The shift (voxels; φ ← φ + shift) that gives the volume back, with the whole run's Newton steps (restore_volume):
/// the first from the volume the bricks' interiors gained and its slope, the others from the change a shift makes
/// on the samples within half a voxel of the surface, all of which an engine's active band holds. With the first step
/// alone the surface stood up to 0.02 voxel from the whole run's after two iterations.
float volume_shift(const HeldBand& v, double gained, double slope) {
    float shift = float(gained / slope);
    const float h = float(v.layout().grid.voxel_size);
    for (int it = 1; it < engine::kVolumeNewtonSteps; ++it) {
        double change = 0.0, at = 0.0;  // the volume's change from shift 0 to shift, and its slope there
        v.for_each_value([&](const float x) {
            const float f = x / h;
            if (!(std::abs(f) < 0.5f + std::abs(shift))) return;
            change += double(engine::inside_share(f + shift) - engine::inside_share(f));
            at += engine::on_slope(f + shift) ? 1.0 : 0.0;
        });
        if (!(at > 0.0)) break;
        shift += float((gained + change) / at);
    }
    return shift;
}

}  // namespace

BrickOutcome run_brick(const BrickContext& c, BrickJob job) {
    BrickOutcome o;
    o.index = job.index;
    const BlockWindow& w = job.window;
    auto t0 = Clock::now();
    Volume sub;
    if (job.scan) {
        if (!c.mesh || !c.query) throw InvalidInput("run_brick: a brick to scan needs the mesh and its search");
        // the window's scan stops when asked; the line moves with the engine's steps alone (the scan's own 0 to 1
        // would run it back)
        struct StopOnly final : Progress {
            Progress* outer;
            explicit StopOnly(Progress* p) : outer(p) {}
            bool should_stop() override { return outer->should_stop(); }
        } stop_only(c.progress);
        sub =
            scan_convert_window(*c.mesh, *c.query, c.wn, c.grid, w, c.scan, nullptr, c.progress ? &stop_only : nullptr);
    } else {
        sub = std::move(job.input);
        const Grid g = window_grid(c.grid, w);
        if (sub.grid.dims != g.dims ||
            sub.block_table.size() != std::size_t(sub.block_dims[0]) * sub.block_dims[1] * sub.block_dims[2])
            throw InvalidInput("run_brick: brick " + std::to_string(job.index) + "'s window does not fit its grid");
    }
    o.seconds_scan = seconds_since(t0);
    const auto slot = [&](int i, int j, int k) {
        return sub.block_table[sub.table_index(i - w.lo[0], j - w.lo[1], k - w.lo[2])];
    };
    // Only a window whose interior holds (or lies within the band of) a surface runs the engine.
    bool interior_band = false;
    for (int k = job.lo[2]; k < job.hi[2] && !interior_band; ++k)
        for (int j = job.lo[1]; j < job.hi[1] && !interior_band; ++j)
            for (int i = job.lo[0]; i < job.hi[0] && !interior_band; ++i) interior_band = slot(i, j, k) >= 0;
    if (interior_band && job.reinitialise_only) {
        t0 = Clock::now();
        reinitialise_volume(sub, c.engine.threads);
        o.seconds_smooth = seconds_since(t0);
        o.ran = true;
    } else if (interior_band) {
        SmoothOptions brick = c.engine;
        brick.reinitialise_input = job.reinitialise_input;
        brick.refit_whole_time = job.refit.whole_time;
        brick.refit_replay_count = job.refit.replay_count;
        brick.refit_replay = job.refit.replay;
        brick.refit_explicit_probe = job.refit.explicit_probe;
        brick.refit_explicit_replay = job.refit.explicit_replay;
        const std::array<int, 3> gbd{(c.grid.dims[0] + kBlockDim - 1) / kBlockDim,
                                     (c.grid.dims[1] + kBlockDim - 1) / kBlockDim,
                                     (c.grid.dims[2] + kBlockDim - 1) / kBlockDim};
        for (int a = 0; a < 3; ++a) {
            brick.sample_origin[a] = w.lo[a] * kBlockDim;
            brick.window_lo[a] = job.lo[a] - w.lo[a];
            brick.window_hi[a] = job.hi[a] - w.lo[a];
            // the window's sides within the grid hold still: the surface runs on past them
            brick.fixed_lo[a] = w.lo[a] > 0 ? kFixedBorder : 0;
            brick.fixed_hi[a] = w.hi[a] < gbd[a] ? kFixedBorder : 0;
        }
        // a quarter of the halo at most: the zone's pull reaches inwards as the refit does, and three quarters of the
        // halo stay between it and the interior
        int halo = 1 << 30;
        for (int a = 0; a < 3; ++a) {
            if (brick.fixed_lo[a] > 0) halo = std::min(halo, (job.lo[a] - w.lo[a]) * kBlockDim);
            if (brick.fixed_hi[a] > 0) halo = std::min(halo, (w.hi[a] - job.hi[a]) * kBlockDim);
        }
        brick.fixed_zone = std::min(kFixedZone, halo / 4);
        t0 = Clock::now();
        SmoothReport r = smooth_volume(sub, brick, c.progress);
        o.seconds_smooth = seconds_since(t0);
        // (a window whose surface lies beyond it, only its band's edge in the interior, has nothing to say)
        if (!r.iterations.empty()) {
            o.ran = true;
            o.record = std::move(r.iterations.front());
            o.warnings = std::move(r.warnings);
            o.window_blocks = sub.block_count();
        }
    }
    o.interior = interior_of(sub, c.grid, w, job.lo, job.hi);
    return o;
}

int brick_halo_voxels(const SmoothOptions& opt, int iterations) {
    const double ell = opt.length_scale > 0 ? opt.length_scale : kDefaultLengthScale;
    double reach = 3.0 * std::sqrt(2.0 * refit_time(opt));
    if (is_neighbourhood_filter(opt.mode)) {
        reach += 2.0 * 2.0 * double(opt.sigma_spatial) * ell;
    } else if (opt.mode != SmoothMode::MeanCurvature) {
        const int steps = opt.normal_steps > 0 ? opt.normal_steps : default_normal_steps(opt.mode);
        reach += 3.0 * std::sqrt(2.0 * double(steps) * std::min(double(opt.normal_dt), 1.0 / 6.0));
    }
    return int(std::ceil(reach * std::max(1, iterations) + engine::kHalfWidth));
}

BrickBlocks brick_blocks(const SmoothOptions& opt, int brick_voxels, int halo_voxels) {
    // Windows start on multiples of the filters' sample stride, so that each thins its samples as the whole grid.
    const int unit = std::lcm(kBlockDim, surface_sample_stride(opt)) / kBlockDim;  // in blocks
    const int halo = halo_voxels > 0 ? halo_voxels : brick_halo_voxels(opt, 1);
    return {round_up((brick_voxels + kBlockDim - 1) / kBlockDim, unit),
            round_up((halo + kBlockDim - 1) / kBlockDim, unit)};
}

Volume smooth_in_bricks(const Mesh& m, const ClosestTriangleQuery& q, const WindingNumber* wn,
                        const ScanConvertOptions& scan, const SmoothOptions& opt, const BrickOptions& bricks,
                        BrickReport* report, SmoothReport* smooth_report, Progress* progress,
                        const SmoothCheckpoint* checkpoint, const BrickRunner* runner) {
    validate_smooth_options(opt, "smooth_in_bricks");
    if (bricks.brick_voxels < kBlockDim)
        throw InvalidInput("smooth_in_bricks: brick_voxels must be >= 8, got " + std::to_string(bricks.brick_voxels));
    if (bricks.halo_voxels < 0)
        throw InvalidInput("smooth_in_bricks: halo_voxels must be >= 0, got " + std::to_string(bricks.halo_voxels));
    const Grid grid = scan_grid(m, scan);
    const int iterations = opt.iterations > 0 ? opt.iterations : default_iterations(opt.mode);
    const BrickBlocks cut = normalflow::brick_blocks(opt, bricks.brick_voxels, bricks.halo_voxels);
    const int brick_blocks = cut.brick, halo_blocks = cut.halo;
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
    BrickContext context;
    context.mesh = &m;
    context.query = &q;
    context.wn = wn;
    context.grid = grid;
    context.scan = scan;
    context.engine = one;
    if (bricks.concurrent < 1)
        throw InvalidInput("smooth_in_bricks: concurrent must be >= 1, got " + std::to_string(bricks.concurrent));
    // a runner of the caller's gets no progress in its context: it may run bricks on threads of its own
    const BrickRunner elsewhere = [runner](const BrickContext& c, int count, const std::function<BrickJob(int)>& make,
                                           const std::function<void(BrickOutcome &&)>& take) {
        BrickContext without = c;
        without.progress = nullptr;
        (*runner)(without, count, make, take);
    };
    const BrickRunner& run = runner && *runner       ? elsewhere
                             : bricks.concurrent > 1 ? run_on_threads(bricks.concurrent)
                                                     : BrickRunner(run_here);
    rep.elsewhere = runner && *runner;
    rep.compact_band = bricks.compact_band;
    SmoothReport sr;
    HeldBand cur, next;
    // the blocks the next pass is expected to write: the plan's count, or the last pass's (its arrays reserved for them)
    std::size_t expected = bricks.expected_band_blocks;
    const auto fresh = [&] {
        expected = std::max(expected, cur.block_count() + cur.block_count() / 8);
        next.reset(grid, bricks.compact_band, expected);
    };
    bool raw = false;  // cur is as the last refit left it: its band not moved, φ not reinitialised
    const auto reinitialise = [&] {
        fresh();
        run_pass(context, run, brick_blocks, halo_blocks, &cur, next, rep, progress, 1.0, 0.0, false, true);
        cur = std::move(next);
        raw = false;
    };
    detail::begin(progress, "bricks");
    // The refit's checks. Each brick keeps every super step (its D is its window's, which its border alone can raise),
    // and the whole surface's D, the bricks' interiors' summed, says what the whole run would have decided
    // (decide_super_steps). Where it would have undone a super step (one that ran away, a patient stop, a last step
    // that raised D), the pass runs again with that decision replayed in every brick (SmoothOptions::refit_replay),
    // and the attempt after it checked the same way. Where the whole run would go on in explicit steps, or a brick's
    // D cannot be summed with the others' (a stage that was not finite), each brick decides in its own window (the
    // windows then decide apart: a few tenths of a voxel from the whole run), with a warning.
    const bool checked_refit = opt.refit_super_steps > 0 && opt.mode != SmoothMode::MeanCurvature &&
                               (is_neighbourhood_filter(opt.mode) || opt.mode == SmoothMode::TotalVariation);
    for (int it = 0; it < iterations; ++it) {
        fresh();
        const double share = 1.0 / iterations;
        BrickRefit refit;
        const auto pass = [&] {
            return run_pass(context, run, brick_blocks, halo_blocks, it == 0 ? nullptr : &cur, next, rep, progress,
                            double(it) * share, share, it == 0 || raw, false, refit);
        };
        // a brick that keeps every super step can keep one that runs away until its φ is no longer finite (a
        // NumericalError): its D is then no decision's, as where it cannot be summed
        Pass p;
        bool failed = false;
        const auto checked_pass = [&] {
            try {
                p = pass();
                failed = false;
            } catch (const NumericalError&) {
                if (!checked_refit) throw;
                failed = true;
            }
        };
        checked_pass();
        double left = refit_time(context.engine);
        const double dt = refit_step_dt(context.engine);
        const auto redo = [&] {
            fresh();
            ++rep.refit_passes_redone;
            checked_pass();
        };
        const auto windowed = [&] {
            refit = BrickRefit{.whole_time = false};
            fresh();
            ++rep.refit_passes_redone;
            p = pass();
            ++rep.refit_passes_windowed;
            add_new(sr.warnings,
                    {"iteration " + std::to_string(it + 1) +
                     ": the whole surface's refit could not be followed in bricks; each brick decided in its "
                     "window (the result may differ from the whole run's by a few tenths of a voxel)"});
        };
        while (checked_refit && (failed || p.any)) {
            using Then = SuperStepDecision::Then;
            const SuperStepDecision d = !failed && p.refit_energy_aligned
                                            ? decide_super_steps(p.refit_energy, context.engine, left)
                                            : SuperStepDecision{};
            if (d.then == Then::KeepAll) break;
            if (!(d.then == Then::Stop || (d.then == Then::Restart && refit.replay_count < kRefitSuperStepAttempts))) {
                windowed();
                break;
            }
            refit.replay[std::size_t(refit.replay_count++)] = d.then == Then::Stop ? -d.kept - 1 : d.kept;
            left -= d.time_kept;
            // After the last restart, or one from the first super step, the whole run goes on in explicit steps
            // until its patient stop: every brick runs some of them, each step's D in its record, and the stop is
            // decided on the sum (a longer probe where it is not within them) and replayed.
            const bool explicit_steps = d.then == Then::Restart && left > 0.5 * dt &&
                                        (refit.replay_count == kRefitSuperStepAttempts || !(d.time_kept > 0.0));
            const int rest = std::max(int(std::lround(left / dt)), 1);
            if (explicit_steps) refit.explicit_probe = std::min(4 * refit_explicit_patience(context.engine), rest);
            redo();
            // the refit ends with the decision replayed: nothing after it to check
            if (!explicit_steps) {
                if (d.then == Then::Stop || !(left > 0.5 * dt)) break;
                continue;
            }
            ++rep.refit_explicit_tails;
            for (;;) {
                using Next = ExplicitStepDecision::Then;
                // where a brick's steps ran away (φ not finite), the decision only if it falls before
                ExplicitStepDecision e =
                    !failed ? decide_explicit_steps(p.refit_energy, context.engine, rest) : ExplicitStepDecision{};
                if (!p.refit_energy_aligned && !(e.then == Next::Keep && e.steps < int(p.refit_energy.size()) - 1))
                    e = ExplicitStepDecision{};
                if (e.then == Next::Unknown) {
                    windowed();
                    break;
                }
                if (e.then == Next::Longer) {
                    refit.explicit_probe = std::min(2 * refit.explicit_probe, rest);
                    redo();
                    continue;
                }
                // the probe kept every step it ran; where the stop keeps fewer, they are replayed
                if (e.steps < int(p.refit_energy.size()) - 1) {
                    refit.explicit_probe = 0;
                    refit.explicit_replay = e.steps;
                    redo();
                    if (failed) windowed();
                }
                break;
            }
            break;
        }
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
            const float shift = volume_shift(cur, p.volume_change, p.volume_slope);  // voxels
            cur.shift(float(double(shift) * grid.voxel_size));
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
            Volume scratch;
            if (!(*checkpoint)(cur.volume(scratch))) {
                sr.stopped_at_checkpoint = true;
                break;
            }
        }
    }
    if (raw) reinitialise();
    sr.seconds_refit = rep.seconds_smooth;
    if (smooth_report) *smooth_report = std::move(sr);
    if (report) *report = rep;
    return std::move(cur).take();
}

}  // namespace normalflow

// ---- Messages -------------------------------------------------------------------------------------------------

namespace normalflow {

namespace {

// A message starts with its kind, this build's version and the sizes of the structs it copies byte for byte: a
// message between two builds that lay them out differently is refused rather than misread.
constexpr std::uint32_t kJob = 0x4a42464e, kOutcome = 0x4f42464e, kContext = 0x4342464e;  // "NFBJ", "NFBO", "NFBC"

struct Writer {
    std::string out;
    template <class T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        out.append(reinterpret_cast<const char*>(&v), sizeof(T));
    }
    template <class T>
    void put_vector(const std::vector<T>& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        put(std::uint64_t(v.size()));
        if (!v.empty()) out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    void put_string(const std::string& s) {
        put(std::uint64_t(s.size()));
        out.append(s);
    }
    void header(std::uint32_t kind) {
        put(kind);
        put_string(version());
        put(std::uint32_t(sizeof(SmoothOptions)));
        put(std::uint32_t(sizeof(ScanConvertOptions)));
        put(std::uint32_t(sizeof(Grid)));
    }
    // field(): the same name as Reader's, so that one list of a message's fields (message_fields) serves both
    template <class T>
    void field(const T& v) {
        if constexpr (std::is_same_v<T, Volume>)
            put_volume(v);
        else if constexpr (std::is_same_v<T, std::string>)
            put_string(v);
        else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
            put(std::uint64_t(v.size()));
            for (const std::string& x : v) put_string(x);
        } else if constexpr (requires {
                                 v.data();
                                 v.size();
                                 typename T::value_type;
                             } &&
                             !std::is_trivially_copyable_v<T>)
            put_vector(v);
        else
            put(v);
    }
    void put_volume(const Volume& v) {
        put(v.grid);
        put(v.background);
        put(v.half_width);
        put(v.block_dims);
        put_vector(v.block_table);
        put_vector(v.block_coords);
        put_vector(v.values);
    }
};

struct Reader {
    std::string_view in;
    std::size_t at = 0;
    const char* what;
    [[noreturn]] void bad(const std::string& why) const { throw InvalidInput(std::string(what) + ": " + why); }
    void need(std::size_t n) const {
        if (in.size() - at < n) bad("the message is truncated");
    }
    template <class T>
    T get() {
        static_assert(std::is_trivially_copyable_v<T>);
        need(sizeof(T));
        T v;
        std::memcpy(&v, in.data() + at, sizeof(T));
        at += sizeof(T);
        return v;
    }
    template <class T>
    std::vector<T> get_vector() {
        const auto n = get<std::uint64_t>();
        if (n > (in.size() - at) / sizeof(T)) bad("the message is truncated");
        std::vector<T> v(n);
        if (n > 0) std::memcpy(v.data(), in.data() + at, n * sizeof(T));  // (an empty vector's data() may be null)
        at += n * sizeof(T);
        return v;
    }
    std::string get_string() {
        const auto n = get<std::uint64_t>();
        need(n);
        std::string s(in.substr(at, n));
        at += n;
        return s;
    }
    void header(std::uint32_t kind) {
        if (get<std::uint32_t>() != kind) bad("not a brick message of this kind");
        const std::string from = get_string();
        const auto so = get<std::uint32_t>(), sc = get<std::uint32_t>(), gr = get<std::uint32_t>();
        if (from != version() || so != sizeof(SmoothOptions) || sc != sizeof(ScanConvertOptions) || gr != sizeof(Grid))
            bad("the message comes from normalflow " + from + ", this is normalflow " + version() +
                " (every machine of a run must run the same build)");
    }
    template <class T>
    void field(T& v) {
        if constexpr (std::is_same_v<T, Volume>)
            v = get_volume();
        else if constexpr (std::is_same_v<T, std::string>)
            v = get_string();
        else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
            const auto n = get<std::uint64_t>();
            if (n > in.size() - at) bad("the message is truncated");
            v.clear();
            for (std::uint64_t i = 0; i < n; ++i) v.push_back(get_string());
        } else if constexpr (requires {
                                 v.data();
                                 v.size();
                                 typename T::value_type;
                             } &&
                             !std::is_trivially_copyable_v<T>)
            v = get_vector<typename T::value_type>();
        else
            v = get<T>();
    }
    Volume get_volume() {
        Volume v;
        v.grid = get<Grid>();
        v.background = get<float>();
        v.half_width = get<float>();
        v.block_dims = get<std::array<int, 3>>();
        v.block_table = get_vector<std::int32_t>();
        v.block_coords = get_vector<std::array<int, 3>>();
        v.values = get_vector<float>();
        std::size_t blocks = 1;
        for (int a = 0; a < 3; ++a) {
            if (v.block_dims[a] < 0 || v.block_dims[a] != (v.grid.dims[a] + kBlockDim - 1) / kBlockDim)
                bad("a volume's blocks do not fit its grid");
            blocks *= std::size_t(v.block_dims[a]);
        }
        if (v.block_table.size() != blocks || v.values.size() != v.block_coords.size() * kBlockVoxels)
            bad("a volume's blocks do not fit its grid");
        for (std::int32_t s : v.block_table)
            if (s >= std::int32_t(v.block_coords.size()) || s < kBlockInside) bad("a volume's block table is broken");
        return v;
    }
    void end() const {
        if (at != in.size()) bad("the message has " + std::to_string(in.size() - at) + " bytes too many");
    }
};

}  // namespace

// A job's and an outcome's fields, in the order their messages hold them: written (Writer) or read (Reader) alike.
template <class IO, class Job>
void job_fields(IO& io, Job& job) {
    io.field(job.index);
    io.field(job.lo);
    io.field(job.hi);
    io.field(job.window);
    io.field(job.scan);
    io.field(job.reinitialise_only);
    io.field(job.reinitialise_input);
    io.field(job.input);
    io.field(job.refit.whole_time);
    io.field(job.refit.replay_count);
    io.field(job.refit.replay);
    io.field(job.refit.explicit_probe);
    io.field(job.refit.explicit_replay);
}

template <class IO, class Outcome>
void outcome_fields(IO& io, Outcome& o) {
    io.field(o.index);
    io.field(o.ran);
    io.field(o.interior);
    auto& it = o.record;  // the fields smooth_in_bricks sums
    io.field(it.filter_points);
    io.field(it.band_voxels);
    io.field(it.allocated_voxels);
    io.field(it.refit_steps);
    io.field(it.refit_evaluations);
    io.field(it.mu);
    io.field(it.volume_before);
    io.field(it.volume_after);
    io.field(it.volume_slope);
    io.field(it.roughness_histogram);
    io.field(it.refit_window_energy);
    io.field(o.warnings);
    io.field(o.window_blocks);
    io.field(o.seconds_scan);
    io.field(o.seconds_smooth);
}

std::string brick_message(const BrickJob& job) {
    Writer w;
    w.header(kJob);
    job_fields(w, job);
    return std::move(w.out);
}

BrickJob brick_job_from_message(std::string_view message) {
    Reader r{message, 0, "brick job"};
    r.header(kJob);
    BrickJob job;
    job_fields(r, job);
    r.end();
    for (int a = 0; a < 3; ++a)
        if (!(job.window.lo[a] <= job.lo[a] && job.lo[a] < job.hi[a] && job.hi[a] <= job.window.hi[a]))
            r.bad("the brick's interior is not inside its window");
    if (job.refit.replay_count < 0 || job.refit.replay_count > kRefitSuperStepAttempts)
        r.bad("its refit replays " + std::to_string(job.refit.replay_count) + " attempts");
    if (job.refit.explicit_probe < 0 || job.refit.explicit_replay < -1)
        r.bad("its refit's explicit steps are " + std::to_string(job.refit.explicit_probe) + " probed, " +
              std::to_string(job.refit.explicit_replay) + " replayed");
    return job;
}

std::string brick_message(const BrickOutcome& o) {
    Writer w;
    w.header(kOutcome);
    outcome_fields(w, o);
    return std::move(w.out);
}

BrickOutcome brick_outcome_from_message(std::string_view message) {
    Reader r{message, 0, "brick outcome"};
    r.header(kOutcome);
    BrickOutcome o;
    outcome_fields(r, o);
    r.end();
    return o;
}

std::string brick_context_message(const BrickContext& c) {
    Writer w;
    w.header(kContext);
    w.put(c.grid);
    w.put(c.scan);
    w.put(c.engine);
    static const Mesh none;
    const Mesh& m = c.mesh ? *c.mesh : none;
    w.put_vector(m.positions);
    w.put_vector(m.triangles);
    return std::move(w.out);
}

void brick_context_from_message(std::string_view message, BrickContext& c, Mesh& mesh) {
    Reader r{message, 0, "brick context"};
    r.header(kContext);
    c.grid = r.get<Grid>();
    c.scan = r.get<ScanConvertOptions>();
    c.engine = r.get<SmoothOptions>();
    mesh = Mesh{};
    mesh.positions = r.get_vector<Vec3f>();
    mesh.triangles = r.get_vector<Tri>();
    r.end();
    for (const Tri& t : mesh.triangles)
        for (std::uint32_t v : t)
            if (v >= mesh.positions.size()) r.bad("a triangle names a vertex the mesh does not have");
    validate_smooth_options(c.engine, "brick context");
    c.mesh = &mesh;
    c.query = nullptr;
    c.wn = nullptr;
}

}  // namespace normalflow
