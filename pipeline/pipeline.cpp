#include "pipeline/pipeline.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <numeric>
#include <string>
#include <tuple>
#include <type_traits>

#include "core/band_memory.h"
#include "core/errors.h"
#include "core/mesh_report.h"
#include "core/stopwatch.h"
#include "core/union_find.h"
#include "extract/surface_attributes.h"
#include "fit/untangle.h"
#include "metrics/noise.h"
#include "metrics/surface_distance.h"
#include "pipeline/options.h"
#include "remesh/decimate.h"
#include "sdf/closest_triangle.h"
#include "sdf/memory_estimate.h"
#include "sdf/winding_number.h"
#ifdef NORMALFLOW_HAS_CGAL
#include "io/cgal/aabb_distance.h"
#include "io/cgal/repair.h"
#endif

namespace normalflow {

namespace {

/// The input's noise as the pipeline reads it everywhere (the report, the kept filter's stop, the guard's grid,
/// an automatic σ_s): along the steady normals, which the noise tilts less than each vertex's own.
double input_noise(const Mesh& m) { return estimate_noise(m, NoiseNormals::Steady).sigma; }

[[noreturn]] void bad_option(const std::string& field, const std::string& value, const char* expected) {
    throw InvalidInput("smooth_mesh: " + field + " = " + value + ": expected " + expected);
}

template <class T>
std::string str(T v) {
    if constexpr (std::is_floating_point_v<T>) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%g", double(v));
        return buf;
    } else {
        return std::to_string(v);
    }
}

long long self_intersection_pairs([[maybe_unused]] const Mesh& m, [[maybe_unused]] bool weld = false) {
#ifdef NORMALFLOW_HAS_CGAL
    return static_cast<long long>(weld ? count_self_intersections(m) : count_self_intersections_as_written(m));
#else
    return -1;
#endif
}

void append(std::vector<std::string>& to, const std::vector<std::string>& from) {
    to.insert(to.end(), from.begin(), from.end());
}

}  // namespace

const char* to_string(DistanceQuery q) {
    switch (q) {
        case DistanceQuery::EngineBvh: return "bvh";
        case DistanceQuery::CgalAabb: return "aabb";
    }
    return "?";
}

void validate(const PipelineOptions& o) {
    RunOptions run;
    run.pipeline = o;
    check_options(run, "smooth_mesh");  // each option's range, from the options table
    if (o.smoothing) {  // the engine's fields the table has not (an automatic sigma_spatial is resolved later)
        SmoothOptions s = o.smooth;
        if (s.sigma_spatial == 0) s.sigma_spatial = float(kMaxAutoSigmaSpatial);
        validate_smooth_options(s, "smooth_mesh", "smooth.");
    }
    // the rules between options
    if (o.sharpen && o.smoothing) bad_option("sharpen", "true", "false with smoothing (it sharpens a re-meshing)");
    if (o.sharpen && o.connectivity == Connectivity::Keep)
        bad_option("sharpen", "true", "false with connectivity keep (it sharpens a re-meshing)");
    for (const auto& [given, name] :
         {std::pair{o.target_faces > 0, "target_faces"}, {o.max_error > 0, "max_error"}, {o.closed, "closed"}})
        if (given && o.connectivity == Connectivity::Keep)
            throw InvalidInput(std::string("smooth_mesh: ") + name +
                               " re-meshes: it needs connectivity remesh or auto");
    if (o.max_error > 0 && o.decimator == Decimator::Meshoptimizer)
        throw InvalidInput("smooth_mesh: max_error: meshoptimizer decimates to a face count only");
#ifndef NORMALFLOW_HAS_CGAL
    if (o.target_faces > 0 && o.decimator == Decimator::Cgal)
        throw InvalidInput("smooth_mesh: decimator cgal: CGAL's edge collapse needs a build with CGAL");
#endif
#ifndef NORMALFLOW_HAS_MESHOPT
    if (o.target_faces > 0 && o.decimator == Decimator::Meshoptimizer)
        throw InvalidInput("smooth_mesh: decimator meshoptimizer: needs a build with meshoptimizer");
#endif
#ifndef NORMALFLOW_HAS_CGAL
    if (o.distance == DistanceQuery::CgalAabb)
        throw InvalidInput("smooth_mesh: distance = aabb: CGAL's AABB tree needs a build with CGAL");
#endif
}

ScanConvertOptions effective_scan_options(const PipelineOptions& o) {
    ScanConvertOptions s = o.scan;
    if (o.smoothing) s.half_width = std::max(s.half_width, kSmoothingScanBandVoxels);
    return s;
}

double check_memory(const Mesh& mesh, const PipelineOptions& o) {
    if (mesh.triangles.empty()) return 0;  // scan_convert gives the clear message
    const ScanConvertOptions s = effective_scan_options(o);
    const double longest = bounding_box(mesh).longest_side();
    const double h = s.voxel_size > 0 ? s.voxel_size : longest / s.resolution;
    if (!(h > 0) || !std::isfinite(h)) return 0;
    const MemoryEstimate e = estimate_memory(mesh, h, s.half_width, s.shell_thickness == 0);
    const double need = e.total(o.smoothing);
    const std::size_t limit = o.max_memory_bytes > 0 ? o.max_memory_bytes : available_memory_bytes();
    if (limit > 0 && need > double(limit))
        throw OutOfMemory("this run needs about " + format_bytes(need) + " at voxel size " + std::to_string(h) +
                          ", more than the " + format_bytes(double(limit)) +
                          (o.max_memory_bytes == 0 ? " available" : " allowed by --max-memory") +
                          "; lower --resolution or raise --max-memory");
    if (e.grid_samples / 512 > 2.0e9)
        throw OutOfMemory("the grid would have more than 2^31 blocks; lower --resolution");
    return need;
}

int auto_resolution(const Mesh& mesh, const PipelineOptions& options) {
    if (mesh.triangles.empty()) return kAutoResolutionMin;
    const double longest = bounding_box(mesh).longest_side();
    const double ell = options.length_scale > 0 ? options.length_scale : model_length_scale(mesh);
    double r = ell > 0 && longest > 0 ? std::ceil(kAutoVoxelsPerLength * longest / ell) : kAutoResolutionMin;
    int res = int(std::clamp(r, double(kAutoResolutionMin), double(kAutoResolutionMax)));
    PipelineOptions o = options;
    o.scan.voxel_size = 0;
    for (; res > kAutoResolutionMin; res = std::max(kAutoResolutionMin, int(res * 0.9))) {
        o.scan.resolution = res;
        try {
            check_memory(mesh, o);
            break;
        } catch (const OutOfMemory&) {}
    }
    return res;
}

namespace {

/// The input of the scan conversion: the repaired copy (where repair ran), the options with the resolution and the
/// bricks resolved, the closest-triangle search.
struct ScanInput {
    Mesh repaired;
    const Mesh* mesh = nullptr;
    PipelineOptions o;
    std::unique_ptr<ClosestTriangleQuery> query;
    BrickPlan plan;  ///< where the run is bricked: the plan's band (compact or not, the blocks it expects)
};

/// Repair, resolution, memory check (and the bricks, where allowed: a run of the engine) and the search.
ScanInput prepare_scan(const Mesh& input, const PipelineOptions& options, PipelineReport& r, Progress* progress,
                       bool bricks_allowed, bool one_pass = false) {
    ScanInput in;
    in.o = options;
    PipelineOptions& o = in.o;
    Stopwatch clock;
    in.mesh = &input;
    if (o.repair) {
#ifdef NORMALFLOW_HAS_CGAL
        detail::begin(progress, "repair");
        in.repaired.positions = input.positions;  // scan conversion needs the geometry only
        in.repaired.triangles = input.triangles;
        r.repair = repair_mesh(in.repaired);
        r.repaired = true;
        in.mesh = &in.repaired;
        append(r.warnings, r.repair.warnings);
#else
        r.warnings.push_back("repair skipped: this build has no CGAL (NORMALFLOW_WITH_CGAL=OFF)");
#endif
    }
    r.seconds.repair = clock.lap();
    const Mesh& mesh = *in.mesh;
    if (o.scan.voxel_size == 0 && o.scan.resolution == 0) o.scan.resolution = auto_resolution(mesh, o);
    r.scan_options = effective_scan_options(o);
    if (!bricks_allowed) {
        o.brick_voxels = 0;
        r.memory_estimate_bytes = check_memory(mesh, o);
    } else if (!mesh.triangles.empty()) {
        // the grid and the length scale that a run in bricks takes (scan_and_smooth_in_bricks), so that the plan cuts
        // its windows; the noise taken as 0 gives the widest filter, and so the widest halo
        const double h = scan_grid(mesh, r.scan_options).voxel_size;
        const SmoothOptions so = engine_options(o, h, model_length_scale(input), 0.0);
        const int halo = o.brick_halo_voxels > 0 ? o.brick_halo_voxels : brick_halo_voxels(so, 1);
        const BrickPlan plan = plan_bricks(mesh, o, h, halo, &so, one_pass);
        in.plan = plan;
        o.brick_voxels = plan.brick_voxels;
        o.brick_halo_voxels = halo;
        r.memory_estimate_bytes = plan.estimate_bytes;
        r.estimated_window_blocks = plan.window_blocks;
    }
    r.distance = o.distance;
#ifdef NORMALFLOW_HAS_CGAL
    if (o.distance == DistanceQuery::CgalAabb) in.query = make_aabb_query(mesh);
#endif
    if (!in.query) in.query = make_bvh_query(mesh);
    return in;
}

Volume scan(const ScanInput& in, PipelineReport& r, Progress* progress) {
    Stopwatch clock;
    detail::begin(progress, "voxelize");
    Volume v = scan_convert(*in.mesh, *in.query, r.scan_options, &r.scan, progress);
    append(r.warnings, r.scan.warnings);
    r.seconds.voxelize = clock.lap();
    r.seconds.total = r.seconds.repair + r.seconds.voxelize;
    r.peak_memory_bytes = peak_memory_bytes();
    return v;
}

/// The scan conversion and the engine brick by brick (smooth_in_bricks), reported as the two stages.
Volume scan_and_smooth_in_bricks(const ScanInput& in, const Mesh& input, PipelineReport& r, Progress* progress,
                                 const SmoothCheckpoint* checkpoint, const BrickMessageRunner* remote) {
    const Mesh& mesh = *in.mesh;
    const Grid grid = scan_grid(mesh, r.scan_options);
    const double noise = input_noise(input);
    const SmoothOptions so = engine_options(in.o, grid.voxel_size, model_length_scale(input), noise, &r);
    std::unique_ptr<WindingNumber> wn;
    if (r.scan_options.shell_thickness == 0 && !remote) wn = std::make_unique<WindingNumber>(mesh);
    BrickOptions b;
    b.brick_voxels = in.o.brick_voxels;
    b.halo_voxels = in.o.brick_halo_voxels;
    b.compact_band = in.plan.compact_band;
    b.expected_band_blocks = std::size_t(in.plan.band_blocks);
    r.scan.grid = grid;
    // Elsewhere, as messages: the context (with the search the workers are to build) once per run.
    std::string context;
    const BrickRunner runner = [&](const BrickContext& c, int count, const std::function<BrickJob(int)>& make,
                                   const std::function<void(BrickOutcome &&)>& take) {
        if (context.empty()) context = char(in.o.distance) + brick_context_message(c);
        (*remote)(
            context, count, [&](int i) { return brick_message(make(i)); },
            [&](const std::string& outcome) { take(brick_outcome_from_message(outcome)); });
    };
    Volume v = smooth_in_bricks(mesh, *in.query, wn.get(), r.scan_options, so, b, &r.bricks, &r.smooth, progress,
                                checkpoint, remote && *remote ? &runner : nullptr);
    r.bricked = true;
    r.smoothed = true;
    r.scan.blocks = v.block_count();
    r.scan.memory_bytes = v.memory_bytes();
    append(r.warnings, r.smooth.warnings);
    r.seconds.voxelize = r.bricks.seconds_scan;
    r.seconds.smooth = r.bricks.seconds_smooth;
    r.seconds.total = r.seconds.repair + r.seconds.voxelize + r.seconds.smooth;
    r.peak_memory_bytes = peak_memory_bytes();
    return v;
}

/// The 8³ blocks a run of the engine allocates around m's surface on grid g, as the engine's band does: the blocks the
/// surface passes within a voxel of (|φ| < 1) and their 26 neighbours. Each triangle is cut into pieces of at most 3
/// voxels along its longest and its shortest edge (as many as its area and its perimeter need, a sliver's few), and
/// each piece marks the blocks that its bounding box, grown by a voxel, overlaps: a superset of the blocks the surface
/// crosses. The surface includes, on an open mesh, a cap over each run of boundary edges (a fan from the run's
/// centroid), where the winding number's sign closes the input across its holes; in shell mode (shell_thickness T >
/// 0) φ's zero lies T/2 off the triangles, so the boxes grow by T/2 more. Counted per cell of `cell` blocks along each
/// axis (1 where the grid, its padding included, is at most 2048 voxels long) as a summed-volume table: the blocks of
/// any box of cells in 8 lookups. Holds two bits per block of the grid while it counts (4.3 MB at 2048).
struct BlockCounts {
    std::array<int, 3> blocks{0, 0, 0};  // the grid's blocks along x, y, z
    int cell = 1;                        // blocks per cell side
    std::array<int, 3> dims{1, 1, 1};    // cells
    std::vector<std::uint32_t> sum;      // (dims + 1)³: sum[i][j][k] = the blocks of the cells below (i, j, k)
    double total = 0;
    double at(int i, int j, int k) const {
        return sum[(std::size_t(k) * std::size_t(dims[1] + 1) + std::size_t(j)) * std::size_t(dims[0] + 1) +
                   std::size_t(i)];
    }
    /// The blocks of the cells that hold any block lo <= b < hi (clipped to the grid).
    double box(std::array<int, 3> lo, std::array<int, 3> hi) const {
        for (int d = 0; d < 3; ++d) {
            lo[d] = std::clamp(lo[d], 0, blocks[d]) / cell;
            hi[d] = std::clamp((std::clamp(hi[d], 0, blocks[d]) + cell - 1) / cell, lo[d], dims[d]);
        }
        return at(hi[0], hi[1], hi[2]) - at(lo[0], hi[1], hi[2]) - at(hi[0], lo[1], hi[2]) - at(hi[0], hi[1], lo[2]) +
               at(lo[0], lo[1], hi[2]) + at(lo[0], hi[1], lo[2]) + at(hi[0], lo[1], lo[2]) - at(lo[0], lo[1], lo[2]);
    }
};

BlockCounts count_blocks(const Mesh& m, const Grid& g, double shell_thickness) {
    BlockCounts c;
    for (int d = 0; d < 3; ++d) c.blocks[d] = std::max(1, (g.dims[d] + kBlockDim - 1) / kBlockDim);
    const std::size_t bx = std::size_t(c.blocks[0]), by = std::size_t(c.blocks[1]), bz = std::size_t(c.blocks[2]);
    // one bit per block, rows of 64-bit words along x
    const std::size_t nw = (bx + 63) / 64;
    std::vector<std::uint64_t> bits(nw * by * bz, 0), grown(bits.size(), 0);
    const auto word = [&](std::size_t j, std::size_t k) { return (k * by + j) * nw; };
    const double reach = 1.0 + 0.5 * shell_thickness / g.voxel_size;  // voxels
    const auto mark = [&](const Vec3d& lo, const Vec3d& hi) {
        int b0[3], b1[3];
        for (int d = 0; d < 3; ++d) {
            b0[d] = std::clamp(int(std::floor((lo[d] - reach) / kBlockDim)), 0, c.blocks[d] - 1);
            b1[d] = std::clamp(int(std::floor((hi[d] + reach) / kBlockDim)), 0, c.blocks[d] - 1);
        }
        for (int k = b0[2]; k <= b1[2]; ++k)
            for (int j = b0[1]; j <= b1[1]; ++j)
                for (int i = b0[0]; i <= b1[0]; ++i)
                    bits[word(std::size_t(j), std::size_t(k)) + std::size_t(i) / 64] |= std::uint64_t(1) << (i % 64);
    };
    constexpr double kPiece = 3.0;  // voxels
    // A triangle (in grid indices) in pieces: from the corner between its longest edge (e1) and its shortest (e2),
    // cells of at most kPiece along each, each cut along its diagonal into two triangles; each of those that touch the
    // triangle marks its box (the parts beyond the triangle lie within a cell of it).
    const auto mark_triangle = [&](const Vec3d(&p)[3]) {
        double len[3];
        for (int e = 0; e < 3; ++e) len[e] = norm(p[(e + 1) % 3] - p[e]);  // edge e: p[e] to p[e + 1]
        const int longest = int(std::max_element(len, len + 3) - len);
        int shortest = (longest + 1) % 3;
        if (len[(longest + 2) % 3] < len[shortest]) shortest = (longest + 2) % 3;
        // their shared corner: edges e and e + 1 share p[e + 1]
        const int o = (shortest == (longest + 1) % 3) ? (longest + 1) % 3 : longest;
        const Vec3d& a = p[o];
        const Vec3d e1 = (longest == o ? p[(o + 1) % 3] : p[(o + 2) % 3]) - a;
        const Vec3d e2 = (shortest == o ? p[(o + 1) % 3] : p[(o + 2) % 3]) - a;
        const int n1 = std::max(1, int(std::ceil(norm(e1) / kPiece))),
                  n2 = std::max(1, int(std::ceil(norm(e2) / kPiece)));
        const Vec3d u = e1 / double(n1), v = e2 / double(n2);
        for (int j = 0; j < n2; ++j)
            for (int i = 0; i < n1 && double(i) / n1 + double(j) / n2 < 1.0; ++i) {
                const Vec3d q = a + u * double(i) + v * double(j), qu = q + u, qv = q + v;
                mark(cwise_min(q, cwise_min(qu, qv)), cwise_max(q, cwise_max(qu, qv)));
                // the far half touches the triangle where one of its near corners lies within it
                if (std::min(double(i + 1) / n1 + double(j) / n2, double(i) / n1 + double(j + 1) / n2) <= 1.0) {
                    const Vec3d quv = qu + v;
                    mark(cwise_min(quv, cwise_min(qu, qv)), cwise_max(quv, cwise_max(qu, qv)));
                }
            }
    };
    for (const Tri& t : m.triangles) {
        const Vec3d p[3] = {g.index(Vec3d(m.positions[t[0]])), g.index(Vec3d(m.positions[t[1]])),
                            g.index(Vec3d(m.positions[t[2]]))};
        mark_triangle(p);
    }
    if (shell_thickness == 0)
        for (const auto& cap : hole_caps(m)) {
            const Vec3d p[3] = {g.index(cap[0]), g.index(cap[1]), g.index(cap[2])};
            mark_triangle(p);
        }
    // the 26 neighbours: grown by a block along x (bits, across words), then y, then z
    const std::uint64_t last = bx % 64 == 0 ? ~std::uint64_t(0) : (std::uint64_t(1) << (bx % 64)) - 1;
    for (std::size_t row = 0; row < by * bz; ++row) {
        const std::uint64_t* w = bits.data() + row * nw;
        std::uint64_t* o = grown.data() + row * nw;
        for (std::size_t x = 0; x < nw; ++x) {
            const std::uint64_t left = x > 0 ? w[x - 1] >> 63 : 0, right = x + 1 < nw ? w[x + 1] << 63 : 0;
            o[x] = w[x] | (w[x] << 1) | left | (w[x] >> 1) | right;
        }
        o[nw - 1] &= last;
    }
    for (std::size_t k = 0; k < bz; ++k)
        for (std::size_t j = 0; j < by; ++j)
            for (std::size_t x = 0; x < nw; ++x)
                bits[word(j, k) + x] = grown[word(j, k) + x] | (j > 0 ? grown[word(j - 1, k) + x] : 0) |
                                       (j + 1 < by ? grown[word(j + 1, k) + x] : 0);
    for (std::size_t k = 0; k < bz; ++k)
        for (std::size_t j = 0; j < by; ++j)
            for (std::size_t x = 0; x < nw; ++x)
                grown[word(j, k) + x] = bits[word(j, k) + x] | (k > 0 ? bits[word(j, k - 1) + x] : 0) |
                                        (k + 1 < bz ? bits[word(j, k + 1) + x] : 0);
    // counted per cell, then summed
    c.cell = std::max(1, (std::max({c.blocks[0], c.blocks[1], c.blocks[2]}) + 255) / 256);
    for (int d = 0; d < 3; ++d) c.dims[d] = (c.blocks[d] + c.cell - 1) / c.cell;
    const std::size_t nx = std::size_t(c.dims[0]) + 1, ny = std::size_t(c.dims[1]) + 1, nz = std::size_t(c.dims[2]) + 1;
    c.sum.assign(nx * ny * nz, 0);
    const auto idx = [&](std::size_t i, std::size_t j, std::size_t k) { return (k * ny + j) * nx + i; };
    for (std::size_t k = 0; k < bz; ++k)
        for (std::size_t j = 0; j < by; ++j)
            for (std::size_t x = 0; x < nw; ++x)
                for (std::uint64_t w = grown[word(j, k) + x]; w != 0; w &= w - 1) {
                    const std::size_t i = x * 64 + std::size_t(std::countr_zero(w));
                    ++c.sum[idx(i / std::size_t(c.cell) + 1, j / std::size_t(c.cell) + 1, k / std::size_t(c.cell) + 1)];
                    c.total += 1;
                }
    for (std::size_t k = 1; k < nz; ++k)
        for (std::size_t j = 1; j < ny; ++j)
            for (std::size_t i = 1; i < nx; ++i)
                c.sum[idx(i, j, k)] += c.sum[idx(i - 1, j, k)] + c.sum[idx(i, j - 1, k)] + c.sum[idx(i, j, k - 1)] -
                                       c.sum[idx(i - 1, j - 1, k)] - c.sum[idx(i - 1, j, k - 1)] -
                                       c.sum[idx(i, j - 1, k - 1)] + c.sum[idx(i - 1, j - 1, k - 1)];
    return c;
}

}  // namespace

SmoothOptions engine_options(const PipelineOptions& o, double voxel_size, double default_length_scale, double noise,
                             PipelineReport* report) {
    PipelineReport local;
    PipelineReport& r = report ? *report : local;
    SmoothOptions so = o.smooth;
    if (so.length_scale == 0) {
        r.length_scale = o.length_scale > 0 ? o.length_scale : default_length_scale;
        so.length_scale = float(r.length_scale / voxel_size);
    } else {
        r.length_scale = double(so.length_scale) * voxel_size;
    }
    r.noise = noise;
    if (so.sigma_spatial == 0) so.sigma_spatial = float(auto_sigma_spatial(noise, r.length_scale, voxel_size));
    r.sigma_spatial = so.sigma_spatial;
    return so;
}

BrickPlan plan_bricks(const Mesh& m, const PipelineOptions& o, double h, int halo_voxels, const SmoothOptions* engine,
                      bool one_pass) {
    BrickPlan plan;
    const ScanConvertOptions s = effective_scan_options(o);
    const MemoryEstimate e = estimate_memory(m, h, s.half_width, s.shell_thickness == 0);
    if (o.brick_voxels == 0) {
        try {
            plan.estimate_bytes = check_memory(m, o);
            return plan;  // the whole volume fits
        } catch (const OutOfMemory&) {}
    }
    const std::size_t limit = o.max_memory_bytes > 0 ? o.max_memory_bytes : available_memory_bytes();
    ScanConvertOptions grid_options = s;
    grid_options.voxel_size = h;
    const Grid grid = scan_grid(m, grid_options);
    // the engine's options on this grid, for the windows' cut (the filters' sample stride)
    const SmoothOptions so = engine ? *engine : engine_options(o, h, model_length_scale(m), 0.0);
    const BlockCounts blocks = count_blocks(m, grid, s.shell_thickness);
    plan.band_blocks = blocks.total;
    // What no brick size lowers: the mesh and the result's band, held whole between passes (φ alone: one float, or 16
    // bits where compact, of each of the engine's samples, and the block table). A pass that scans holds one copy, the
    // one it writes; a later pass two, the last pass's (which its windows read) and the one it writes; the closing
    // reinitialisation two, with windows that only reinitialise.
    const auto held = [&](int copies, bool compact) {
        return e.mesh_bytes + copies * (blocks.total * 512 * (compact ? 2 : 4) + e.grid_samples / 512 * 4);
    };
    const auto estimate = [&](int brick, bool compact) {
        // the most blocks one window holds: its engine's arrays, and the scanned window it starts from (φ of at most
        // as many blocks)
        const BrickBlocks cut = brick_blocks(so, brick, halo_voxels);
        double worst = 0;
        for (int k0 = 0; k0 < blocks.blocks[2]; k0 += cut.brick)
            for (int j0 = 0; j0 < blocks.blocks[1]; j0 += cut.brick)
                for (int i0 = 0; i0 < blocks.blocks[0]; i0 += cut.brick)
                    worst = std::max(worst, blocks.box({i0 - cut.halo, j0 - cut.halo, k0 - cut.halo},
                                                       {i0 + cut.brick + cut.halo, j0 + cut.brick + cut.halo,
                                                        k0 + cut.brick + cut.halo}));
        plan.window_blocks = worst;
        const double passes =
            held(one_pass ? 1 : 2, compact) + kEngineRoundingBytes + worst * 512 * (kEngineBytesPerSample + 4);
        // (the engine's untouched arrays cost no memory where it maps them in huge pages; elsewhere they are zeroed)
        const double reinitialise = detail::maps_huge_pages() ? kReinitialiseBytesPerSample : kEngineBytesPerSample + 4;
        const double closing = held(2, compact) + kEngineRoundingBytes + worst * 512 * reinitialise;
        // the band handed back in floats while its 16 bits still live (and likewise for a checkpoint)
        const double handed = compact ? held(1, false) + blocks.total * 512 * 2 : 0.0;
        return std::max({passes, closing, handed});
    };
    // The band in floats at every size first (bricks hold the whole run's surface to float rounding), then, in a run of
    // one pass, in 16 bits: only the closing reinitialisation reads it back (within 0.001 voxel of the floats; a second
    // pass of the filters from it moved a surface 0.01 to 0.12 voxel, as their choices amplify the change).
    double smallest = 0;
    int tried = 0;
    for (const bool compact : {false, true})
        for (const int brick : {512, 384, 256, 192, 128, 96, 64}) {
            if (compact && !one_pass) break;
            if (o.brick_voxels > 0 && brick != 512) break;  // the size given, once
            tried = o.brick_voxels > 0 ? o.brick_voxels : brick;
            const double need = estimate(tried, compact);
            smallest = need;
            if (limit == 0 || need <= double(limit)) {
                plan.brick_voxels = tried;
                plan.estimate_bytes = need;
                plan.compact_band = compact;
                return plan;
            }
        }
    throw OutOfMemory("this run needs about " + format_bytes(smallest) + " at voxel size " + std::to_string(h) +
                      (o.brick_voxels > 0 ? " in bricks of " : " even in bricks of ") + std::to_string(tried) +
                      " voxels (" + format_bytes(held(2, one_pass)) +
                      " of it the mesh and the result's band, held whole whatever the bricks), more than the " +
                      format_bytes(double(limit)) +
                      (o.max_memory_bytes == 0 ? " available" : " allowed by --max-memory") +
                      "; lower --resolution or raise --max-memory");
}

Volume mesh_to_volume(const Mesh& input, const PipelineOptions& options, PipelineReport* report, Progress* progress) {
    validate(options);
    PipelineReport local;
    PipelineReport& r = report ? *report : local;
    const ScanInput in = prepare_scan(input, options, r, progress, false);
    return scan(in, r, progress);
}

Mesh volume_to_mesh(const Volume& v, const PipelineOptions& o, PipelineReport* report, Progress* progress) {
    return volume_to_mesh(v, o, report, progress, nullptr);
}

namespace {

/// Gives vertices back their position in `before`, the vertices that had one position there (the corners of a soup,
/// which a fit moves together) together, so that no crack opens between them; each such group counts once.
class VertexRestorer {
public:
    VertexRestorer(Mesh& m, const std::vector<Vec3f>& before)
        : m_(m),
          before_(before),
          order_(m.positions.size()),
          group_of_(m.positions.size()),
          done_(m.positions.size(), 0),
          changed_(m.positions.size(), 0) {
        // the groups of coincident vertices in `before`: group g is order_'s run [start_[g], start_[g + 1])
        std::iota(order_.begin(), order_.end(), 0u);
        std::sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) {
            const Vec3f &p = before[a], &q = before[b];
            return std::tie(p.x, p.y, p.z, a) < std::tie(q.x, q.y, q.z, b);
        });
        for (std::size_t k = 0; k < order_.size(); ++k) {
            if (k == 0 || before[order_[k]] != before[order_[k - 1]]) start_.push_back(std::uint32_t(k));
            group_of_[order_[k]] = std::uint32_t(start_.size() - 1);
        }
        start_.push_back(std::uint32_t(order_.size()));
        for (std::size_t i = 0; i < m.positions.size(); ++i) changed_[i] = m.positions[i] != before[i];
    }

    /// Gives back the vertices of every face that intersects another face, touches one at a distinct vertex of the
    /// same position (two vertices moved onto one corner) or lost its area, until no face does (`before` is free of
    /// all three, or they are left where `before` had them). First the faces with a vertex moved since the last
    /// call (every moved one the first time), then only those whose vertices the last round gave back: any other
    /// pair was checked with the positions it still has. weld: the vertex indices are not the connectivity (a kept
    /// input, which may be a soup): faces meeting at coincident vertices share them. halve: halfway back each time,
    /// as flips does. The groups given back; -1 without CGAL, which finds the intersections.
    long long intersections(bool weld, bool halve = false) {
#ifdef NORMALFLOW_HAS_CGAL
        const long long before = restored_;
        std::vector<char> marked(m_.triangles.size());
        for (int round = 0; round < 64; ++round) {
            for (std::size_t f = 0; f < m_.triangles.size(); ++f) {
                const Tri& t = m_.triangles[f];
                marked[f] = changed_[t[0]] || changed_[t[1]] || changed_[t[2]];
            }
            std::fill(changed_.begin(), changed_.end(), 0);
            auto pairs = self_intersecting_pairs(m_, &marked, weld);
            for (std::size_t f = 0; f < m_.triangles.size(); ++f) {
                const Tri& t = m_.triangles[f];
                if (marked[f] && exactly_collinear(m_.positions[t[0]], m_.positions[t[1]], m_.positions[t[2]]))
                    pairs.emplace_back(std::uint32_t(f), std::uint32_t(f));
            }
            if (pairs.empty()) break;
            ++round_;
            for (const auto& [a, b] : pairs)
                for (const std::uint32_t f : {a, b}) give_back(m_.triangles[f], halve);
        }
        return restored_ - before;
#else
        (void)weld;
        (void)halve;
        return -1;
#endif
    }

    /// Moves back the vertices of every face that points against the volume (faces_against_volume) where the
    /// input's face (against[f], measured on `before`) did not, until none does: each time halfway to `before`, and
    /// all the way after kHalvings halvings, so that a vertex keeps as much of its move as leaves its faces the
    /// right way round. The groups moved back.
    long long flips(const Volume& v, const std::vector<char>& input_against) {
        const long long before = restored_;
        for (int round = 0; round < 64; ++round) {
            const std::vector<char> against = faces_against_volume(m_, v);
            ++round_;
            bool any = false;
            for (std::size_t f = 0; f < against.size(); ++f)
                if (against[f] && !input_against[f]) any |= give_back(m_.triangles[f], /*halve=*/true);
            if (!any) break;
        }
        return restored_ - before;
    }

    long long restored() const { return restored_; }

private:
    static constexpr int kHalvings = 4;

    /// Gives t's vertices (and their groups) back, or with `halve` halfway back until they have been halved
    /// kHalvings times; whether any moved.
    bool give_back(const Tri& t, bool halve = false) {
        bool any = false;
        for (const std::uint32_t vtx : t) {
            if (m_.positions[vtx] == before_[vtx]) continue;
            const std::uint32_t g = group_of_[vtx];
            const std::uint32_t lead = order_[start_[g]];
            if (moved_in_[lead] == round_) continue;  // once a round, whatever the number of its faces
            moved_in_[lead] = round_;
            restored_ += !done_[lead];
            done_[lead] = 1;
            const bool all_the_way = !halve || ++halved_[lead] > kHalvings;
            for (std::uint32_t k = start_[g]; k < start_[g + 1]; ++k) {
                const std::uint32_t u = order_[k];
                if (m_.positions[u] == before_[u]) continue;
                m_.positions[u] = all_the_way ? before_[u] : before_[u] + (m_.positions[u] - before_[u]) * 0.5f;
                changed_[u] = 1;
                any = true;
            }
        }
        return any;
    }

    Mesh& m_;
    const std::vector<Vec3f>& before_;
    std::vector<std::uint32_t> order_, group_of_, start_;
    std::vector<char> done_, changed_;
    std::vector<std::uint8_t> halved_ = std::vector<std::uint8_t>(m_.positions.size(), 0);
    std::vector<int> moved_in_ = std::vector<int>(m_.positions.size(), 0);
    int round_ = 0;
    long long restored_ = 0;
};

}  // namespace

namespace {

/// The compact default (PipelineOptions::full_density false): m decimated within kCompactErrorVoxels of the field's
/// tangent planes and kCompactNormalDeviationDeg of its normals (which m gets here, set_volume_normals), by the
/// quadric decimation and its local repair only: where that result would break what m is (closed, manifold, free of
/// self-intersections), m stays as it is, with a warning, rather than going to CGAL's edge collapse, which takes
/// tens of minutes on a surface of millions of faces. Fills r's decimate, decimated, compacted, seconds.decimate.
void compact_surface(Mesh& m, const Volume& v, const PipelineOptions& o, PipelineReport& r, Progress* progress) {
    // --decimator applies to --target-faces and --max-error; the compact default is the quadric decimation
    Stopwatch clock;
    detail::begin(progress, "decimate");
    set_volume_normals(m, v);
    Mesh decimated = m;
    // The guarantees the decimation keeps are the extraction's, closed and manifold by construction (and kept by the
    // removal of extra components and by sharpening, which move no edge): not measured again (0.45 s on 627,576 faces).
    // A surface trimmed to an open input's footprint is measured.
    MeshReport extracted;
    extracted.closed = r.extract.closed;
    extracted.manifold = r.extract.manifold;
    DecimationReport d = decimate_mesh(decimated, {.max_error = kCompactErrorVoxels * v.grid.voxel_size,
                                                   .decimator = Decimator::Quadric,  // the normal bound is its own
                                                   .tangent_planes = !o.sharpen,
                                                   .max_normal_deviation_deg = kCompactNormalDeviationDeg,
                                                   .input_report = r.trimmed ? nullptr : &extracted,
                                                   .local_repair = true});
    r.decimate = d;
    r.decimated = true;
    if (d.warnings.empty()) {
        m = std::move(decimated);
        r.compacted = true;
    } else {
        r.warnings.push_back("kept every triangle: the compact decimation's result was not clean (" +
                             d.warnings.front() + ")");
    }
    r.seconds.decimate = clock.lap();
}

}  // namespace

Mesh volume_to_mesh(const Volume& v, const PipelineOptions& o, PipelineReport* report, Progress* progress,
                    const Mesh* reference) {
    if (o.target_faces > 0 && o.target_faces < 4) bad_option("target_faces", str(o.target_faces), "0 or >= 4");
    if (o.sharpen && o.smoothing)
        throw InvalidInput(
            "sharpen applies to a re-meshing without smoothing (the smoothed surface's creases are its own)");
    if (o.sharpen && !reference) throw InvalidInput("sharpen needs the mesh the volume was made from");
    if (!(o.max_error >= 0) || !std::isfinite(o.max_error)) bad_option("max_error", str(o.max_error), ">= 0");
    PipelineReport local;
    PipelineReport& r = report ? *report : local;
    Stopwatch clock;
    detail::begin(progress, "extract");
    Mesh m = extract_surface(v, o.extract, &r.extract);
    r.seconds.extract = clock.lap();
    if (m.empty()) {
        if (o.smoothing)
            throw InvalidInput(
                "the surface vanished during smoothing (parts thinner than a few voxels "
                "shrink away); raise --resolution or lower --iterations");
        throw InvalidInput("the volume holds no surface (every sample has the same sign)");
    }
    if (reference) {
        // the input's parts, welded as mesh_report counts them; a re-meshing adds none
        const std::size_t parts = mesh_report(*reference).components;
        r.components = remove_extra_components(m, parts, kExtraComponentAreaFraction);
        const std::size_t left = r.components.components - r.components.removed;
        if (r.components.removed > 0)
            r.warnings.push_back("removed " + std::to_string(r.components.removed) +
                                 " small closed pieces the volume added (each under " +
                                 str(100 * kExtraComponentAreaFraction) +
                                 "% of the area: where the input's inside was uncertain, or specks the processing "
                                 "split off)");
        if (left > parts)
            r.warnings.push_back("the result has " + std::to_string(left) + " parts, the input " +
                                 std::to_string(parts) +
                                 ": the processing split a part thinner than a few voxels (raise --resolution)");
    }
    if (o.sharpen) {
        detail::begin(progress, "sharpen");
        const std::vector<Vec3f> extracted = m.positions;
        const auto q = make_bvh_query(*reference);
        SharpenOptions so;
        so.max_move = kSharpenMaxMoveVoxels * v.grid.voxel_size;
        so.threads = o.scan.threads;
        r.sharpen = sharpen_mesh(m, mesh_probe(*reference, *q), so, progress);
        r.sharpen_restored = VertexRestorer(m, extracted).intersections(/*weld=*/false);
        if (r.sharpen_restored < 0)
            r.warnings.push_back("sharpened without the self-intersection check (a build without CGAL)");
        r.sharpened = true;
        r.seconds.extract += clock.lap();
    }
    const bool compact = !o.full_density && o.target_faces == 0 && o.max_error == 0;
    if (compact) {
        compact_surface(m, v, o, r, progress);
    } else if (o.target_faces > 0 || o.max_error > 0) {
        detail::begin(progress, "decimate");
        // Hermite data: the field's normal at each vertex, so that the quadrics see the surface the
        // volume holds rather than the extraction's one-voxel bevels at creases (docs/history/benchmarks-2026.md,
        // "Sharp extraction"); a sharpened surface's own faces lie on the input's planes already.
        set_volume_normals(m, v);
        r.decimate = decimate_mesh(m, {.target_faces = o.target_faces,
                                       .max_error = o.max_error,
                                       .decimator = o.decimator,
                                       .tangent_planes = !o.sharpen});
        r.decimated = true;
        append(r.warnings, r.decimate.warnings);
        r.seconds.decimate = clock.lap();
    }
    set_volume_normals(m, v);  // the processed surface's own normals: viewers shade it smooth
    place_mesh(m, v.grid.placement);
    r.seconds.total += r.seconds.extract + r.seconds.decimate;
    r.peak_memory_bytes = peak_memory_bytes();
    return m;
}

const char* to_string(KeepFilter k) {
    switch (k) {
        case KeepFilter::Faces: return "faces";
        case KeepFilter::Volume: return "volume";
        case KeepFilter::Fit: return "fit";
    }
    return "?";
}

const char* to_string(Connectivity c) {
    switch (c) {
        case Connectivity::Keep: return "keep";
        case Connectivity::Remesh: return "remesh";
        default: return "auto";
    }
}

double median_edge_length(const Mesh& m) {
    std::vector<double> len;
    len.reserve(m.triangles.size() * 3);
    for (const auto& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            const auto d = m.positions[std::size_t(t[(k + 1) % 3])] - m.positions[std::size_t(t[k])];
            len.push_back(std::sqrt(double(dot(d, d))));
        }
    if (len.empty()) return 0;
    auto mid = len.begin() + std::ptrdiff_t(len.size() / 2);
    std::nth_element(len.begin(), mid, len.end());
    return *mid;
}

double model_length_scale(const Mesh& m) {
    const double edge = median_edge_length(m);
    if (m.triangles.empty()) return edge;
    const double longest = bounding_box(m).longest_side();
    const double coarsest_unit = longest * kAutoVoxelsPerLength / kAutoResolutionMin;
    return coarsest_unit > 0 ? std::min(edge, coarsest_unit) : edge;
}

namespace {

/// Checks the result as it will be written (PipelineReport::output) and says what breaks a promise: a re-meshed
/// surface is manifold, without degenerate faces, free of self-intersections and, unless it was trimmed to an
/// open input's footprint, closed; a kept mesh has no more intersecting pairs than the input had (input_pairs).
void check_output(const Mesh& m, PipelineReport& r, bool remeshed, bool closed, long long input_pairs = 0) {
    r.output = mesh_report(m);
    r.output_self_intersections = self_intersection_pairs(m, !remeshed);
    r.checked = true;
    const MeshReport& o = r.output;
    std::string what;
    const auto add = [&](const std::string& s) { what += (what.empty() ? "" : ", ") + s; };
    if (remeshed) {
        if (closed && !o.closed) add(std::to_string(o.boundary_edges) + " boundary edges");
        if (!o.manifold)
            add(std::to_string(o.non_manifold_edges) + " non-manifold edges and " +
                std::to_string(o.non_manifold_vertices) + " non-manifold vertices");
        if (o.degenerate_faces > 0) add(std::to_string(o.degenerate_faces) + " degenerate faces");
    }
    if (r.output_self_intersections > std::max(0LL, input_pairs))
        add(std::to_string(r.output_self_intersections) + " pairs of intersecting faces" +
            (input_pairs > 0 ? " (the input had " + std::to_string(input_pairs) + ")" : ""));
    if (!remeshed && r.flipped_faces > std::max(0LL, r.input_flipped_faces))
        add(std::to_string(r.flipped_faces) + " faces turned over against the surface (the input had " +
            std::to_string(r.input_flipped_faces) + ")");
    if (!what.empty()) r.warnings.push_back("the result has " + what);
}

}  // namespace

PipelineResult smooth_mesh(const Mesh& m, const PipelineOptions& o, Progress* progress,
                           const BrickMessageRunner* bricks) {
    validate(o);  // every field, the engine's too where it will not run
    PipelineResult result;
    PipelineReport& r = result.report;
    const bool open = has_open_boundary(m);
    const bool automatic = o.connectivity == Connectivity::Auto && o.target_faces == 0 && o.max_error == 0 && !o.closed;
    bool keep = o.connectivity == Connectivity::Keep || (automatic && open);
    const bool own_faces = o.keep_filter == KeepFilter::Faces;
    // Auto keeps a closed input's own mesh where the kept result comes out as clean as a re-meshed one is by
    // construction: manifold, and no two faces intersecting. The kept mesh has the input's connectivity, so a
    // non-manifold input is re-meshed at once; the intersections are the kept result's to count (the noise makes the
    // input's, which the filter undoes; its guard lets no face come to intersect another, but leaves those it found),
    // so the input is kept, the engine stopping after its first iteration, and where the kept result has intersecting
    // faces the whole run is made again, re-meshed. A closed, oriented, manifold surface that does not intersect itself
    // bounds a solid, every face looking out of it: a face that the smoothed surface sees turned over there lies where
    // the surface does not resolve the mesh (a crevice or a fin narrower than its voxels: the ground truth of the
    // study's vaselion has 7) and is reported, not a reason to re-mesh.
    if (automatic && !open) {
        const MeshReport in = mesh_report(m);
        keep = in.manifold;
        if (!keep) {
            const auto count = [](std::size_t n, const char* what) {
                return n ? std::to_string(n) + " non-manifold " + what : std::string();
            };
            const std::string edges = count(in.non_manifold_edges, "edges"),
                              vertices = count(in.non_manifold_vertices, "vertices");
            r.keep_declined = edges + (edges.empty() || vertices.empty() ? "" : " and ") + vertices + " in the input";
        }
    }
    // A mesh kept and filtered on its own faces takes nothing from the engine but the guard's reference below (which
    // side of the surface each face looks to) and the unfolding's (the surface's plane at a fold). On an open input the
    // input's own distance serves that, and the engine does not run (nor counts in the memory check): on the open
    // scans of the study the result is within 0.02° face by face. On a closed one the engine runs its first iteration:
    // the noisy distance of the study's closed pairs (1.3 to 2.3 voxels of noise against 0.6 to 1.1 on the scans)
    // turned faces the filter had right, and the guard moving them back cost 0.1 to 0.55° (docs/history/
    // benchmarks-2026.md, "The stop rule's curves, and the kept mesh without the engine"). It runs wherever its surface
    // is used too: a re-meshed result, and the fit.
    const bool engine = o.smoothing && !(keep && own_faces && open);
    PipelineOptions scan = o;
    scan.smoothing = engine;
    if (keep && own_faces && o.scan.resolution == 0 && o.scan.voxel_size == 0) {
        // The kept mesh's volume tells which side of the surface a face looks to, by a gradient over two voxels that
        // the noise cannot turn once a voxel is twice the noise (the automatic resolution puts 0.6 to 1.1 of the scans'
        // noise in a voxel, 1.3 to 2.3 of the closed pairs'); it need not be finer than that. Nor coarser than half the
        // automatic resolution: the volume must still hold the parts the automatic grid resolves (a fin or a crevice
        // of the study's vaselion two voxels across at 512 lost 0.17° face by face at 187, none at 250), and the
        // unfolding moves vertices in its planes. A closed input's engine, which runs here for that volume alone, costs
        // as its voxels: the study's closed pairs took 2.1 to 4.7 times less time (docs/history/benchmarks-2026.md,
        // "The kept mesh's grid").
        r.noise = input_noise(m);
        const double longest = bounding_box(m).longest_side();
        const int automatic_resolution = auto_resolution(m, scan);
        scan.scan.resolution = automatic_resolution;
        if (r.noise > 0 && longest > 0)
            scan.scan.resolution =
                std::clamp(int(std::ceil(longest / (2 * r.noise))),
                           std::max(std::min(kAutoResolutionMin, automatic_resolution), (automatic_resolution + 1) / 2),
                           automatic_resolution);
    }
    // The engine brick by brick where the whole volume does not fit the memory (or bricks were asked for); not for
    // the fit to the normal map, which reads the engine's last normals.
    // A closed input kept on its own faces reads the engine's volume only for the guard and the unfolding: the engine
    // stops after its first iteration (and in bricks holds one copy of the result's band while it runs).
    const bool early = own_faces && !open && keep;
    const ScanInput scan_input = prepare_scan(m, scan, r, progress, engine && !o.fit_to_normal_map, early);
    const bool bricked = engine && scan_input.o.brick_voxels > 0;
    if (bricks && *bricks && !bricked)
        r.warnings.push_back(engine ? "the run fits in memory whole: it ran here, not in bricks on the workers (give "
                                      "brick-size to run it in bricks)"
                                    : "the engine does not run for this input: nothing ran on the workers");
    Volume v;
    if (!bricked) v = normalflow::scan(scan_input, r, progress);
    NormalMap normal_map;  // the engine's last filtered normals, when the fit is to turn faces to them
    // The kept result on a smoothed surface (the engine's, or the input's own distance where the engine did not run):
    // the input's own faces filtered (KeepFilter::Faces), or the input fitted to the surface and its faces turned to
    // the surface's normals (Volume, Fit); then guarded and checked. Its time is the caller's to count.
    const auto kept_result = [&](const Volume& surface) {
        Mesh kept = m;
        FaceFilterOptions faces = o.faces;
        std::vector<Vec3d> guide;
        if (own_faces) {
            // smooth_volume_stage measured it when the engine ran, or the guard's resolution; otherwise it is measured
            // here
            if (!r.smoothed && r.noise == 0) r.noise = input_noise(m);
            faces.stop_noise = r.noise;
            if (faces.normal_steps == 0) faces.normal_steps = faces.stop_noise > 0 ? kMaxFaceRounds : 0;
            detail::begin(progress, "faces");
        } else {
            detail::begin(progress, "fit");
            r.fit = fit_mesh_to_volume(kept, surface, o.fit, normal_map[0].values.empty() ? nullptr : &normal_map);
            r.fitted = true;
            if (o.keep_filter == KeepFilter::Fit)
                faces.normal_steps = 0;
            else if (faces.normal_steps == 0)
                faces.normal_steps = 1;
            if (faces.normal_steps > 0)
                guide = volume_normals_at_faces(kept, surface, normal_map[0].values.empty() ? nullptr : &normal_map);
        }
        if (own_faces || faces.normal_steps > 0) {
            // Heavy noise folds the input's faces over along the surface, which the filter's vertex update (along the
            // faces' normals) cannot undo, and the update can fold a few more where the noise tilted a patch past a
            // right angle: both are unfolded along the volume's surface, no vertex moving farther than the noise's
            // reach.
            const double reach = kUntangleNoiseReach * r.noise;
            if (own_faces) r.untangle_input = untangle(kept, surface, reach);
            r.faces = filter_faces(kept, faces, own_faces ? nullptr : &guide);
            if (own_faces) r.untangle_filtered = untangle(kept, surface, reach);
            r.untangled = own_faces;
            r.faces_filtered = true;
        }
        // The fit moves each vertex on its own: where two sheets of the input lie closer than the noise, faces can be
        // pushed through each other. The vertices of faces that now intersect (or lost their area) move back toward
        // where the input had them (halfway each round, all the way in the end), until none does: the kept mesh has no
        // intersection the input did not have. Nor may a face turn over against the volume's surface (smoothed, or the
        // input's own where the engine did not run) where the input's face did not: its vertices move back the same
        // way. Moving vertices back for one reason can break the other, so the two alternate until both hold.
        {
            const std::vector<char> input_against = faces_against_volume(m, surface);
            r.input_flipped_faces = std::count(input_against.begin(), input_against.end(), char(1));
            VertexRestorer back(kept, m.positions);
            back.flips(surface, input_against);
            for (int round = 0; round < 8 && back.intersections(/*weld=*/true, /*halve=*/true) > 0; ++round)
                if (back.flips(surface, input_against) == 0) break;
            r.fit_restored = back.restored();
            const std::vector<char> against = faces_against_volume(kept, surface);
            r.flipped_faces = std::count(against.begin(), against.end(), char(1));
        }
        // replaces the input's normals, which belong to the noisy surface
        if (own_faces)
            compute_vertex_normals(kept);
        else
            set_volume_normals(kept, surface);
        r.connectivity_kept = true;
        if (!own_faces && r.fit.outside_band > 0)
            r.warnings.push_back(std::to_string(r.fit.outside_band) + " of the " + std::to_string(r.fit.vertices) +
                                 " vertices were left unsmoothed: the smoothed surface is farther from them than its "
                                 "band (at open borders, spikes, strays or parts thinner than a voxel)");
        r.input_self_intersections = self_intersection_pairs(m, true);
        check_output(kept, r, false, false, r.input_self_intersections);
        return kept;
    };
    const SmoothCheckpoint go_on = [](const Volume&) { return false; };
    if (bricked)
        v = scan_and_smooth_in_bricks(scan_input, m, r, progress, early ? &go_on : nullptr, bricks);
    else if (engine)
        smooth_volume_stage(v, o, m, &r, progress, o.fit_to_normal_map ? &normal_map : nullptr,
                            early ? &go_on : nullptr);
    Stopwatch kept_clock;
    Mesh kept;
    if (keep) kept = kept_result(v);
    const double kept_seconds = kept_clock.lap();
    r.seconds.extract += kept_seconds;
    r.seconds.total += kept_seconds;
    if (automatic && !open && keep) {
        // Where the kept result has pairs of intersecting faces (or, in a build without CGAL, which cannot count them,
        // faces turned over against the surface, which stand in for them), the input is re-meshed after all, the whole
        // run again (the first attempt's time, scan conversion and first iteration included, counted with its
        // extraction).
        std::string defects;
        if (r.output_self_intersections > 0)
            defects = std::to_string(r.output_self_intersections) + " pairs of intersecting faces in the kept result";
        else if (r.output_self_intersections < 0 && r.flipped_faces > 0)
            defects = std::to_string(r.flipped_faces) + " faces turned over against the surface in the kept result";
        if (!defects.empty()) {
            PipelineOptions remesh = o;
            remesh.connectivity = Connectivity::Remesh;
            try {
                PipelineResult again = smooth_mesh(m, remesh, progress, bricks);
                again.report.keep_declined = defects;
                again.report.seconds.extract += r.seconds.total;
                again.report.seconds.total += r.seconds.total;
                return again;
            } catch (const OutOfMemory& e) {
                // a run planned for one pass (one copy of the band, or 16 bits) can fit where the re-meshed run of
                // every pass does not: the kept result stays, with its defects said, rather than none after the work
                r.warnings.push_back(defects + ", which re-meshing would remove, but " + e.what());
            }
        }
    }
    // The scan conversion's note on an open mesh is about the volume: a result that keeps the input's openings
    // (its own mesh, or the surface trimmed to its footprint) needs no word on them; a closed one spans them.
    if (open && !r.scan.open_mesh_warning.empty()) {
        std::erase(r.warnings, r.scan.open_mesh_warning);
        if (!keep && o.closed)
            r.warnings.push_back("the input is open: the closed result spans its holes and boundaries");
    }
    if (keep) {
        result.mesh = std::move(kept);
        r.peak_memory_bytes = peak_memory_bytes();
        return result;
    }
    // An open input's surface is trimmed before the compact default decimates it: the cut then runs through the
    // extraction's small faces, and the decimation keeps the open border where the cut left it.
    const bool trim = open && !o.closed;
    const bool compact_after_trim = trim && !o.full_density && o.target_faces == 0 && o.max_error == 0;
    PipelineOptions extraction = o;
    extraction.full_density = extraction.full_density || compact_after_trim;
    result.mesh = volume_to_mesh(v, extraction, &r, progress, &m);
    std::unique_ptr<ClosestTriangleQuery> q;
    if (trim) {
        Stopwatch trim_clock;
        q = make_bvh_query(m);
        // the cap lies away from the input; the smoothed surface within its noise (a fraction of an edge)
        const double h = v.grid.voxel_size;
        r.trim = trim_to_footprint(result.mesh, m, *q, h, 3 * std::max(h, model_length_scale(m)));
        r.trimmed = true;
        if (result.mesh.empty())
            throw InvalidInput(
                "nothing of the surface is left after trimming it to the open input's footprint; "
                "--closed keeps the closed surface");
        const double seconds = trim_clock.lap();  // counted with the extraction
        r.seconds.extract += seconds;
        r.seconds.total += seconds;
    }
    if (compact_after_trim) {
        compact_surface(result.mesh, v, o, r, progress);
        set_volume_normals(result.mesh, v);
        r.seconds.total += r.seconds.decimate;
    }
    if (m.has_colors()) transfer_colors(result.mesh, m, q ? *q : *(q = make_bvh_query(m)));
    if (m.has_texcoords())
        r.warnings.push_back(
            "texture coordinates dropped: re-meshing makes new vertices "
            "(--connectivity keep keeps them)");
    check_output(result.mesh, r, true, !r.trimmed);
    return result;
}

double auto_sigma_spatial(double noise, double length_unit, double voxel_size) {
    if (!(noise > 0) || !(length_unit > 0)) return kMaxAutoSigmaSpatial;
    return std::clamp(2.0 * noise / length_unit, std::min(voxel_size / length_unit, kMaxAutoSigmaSpatial),
                      kMaxAutoSigmaSpatial);
}

void smooth_volume_stage(Volume& v, const PipelineOptions& o, double default_length_scale, double noise,
                         PipelineReport* report, Progress* progress, NormalMap* normal_map,
                         const SmoothCheckpoint* checkpoint) {
    PipelineReport local;
    PipelineReport& r = report ? *report : local;
    Stopwatch clock;
    const SmoothOptions so = engine_options(o, v.grid.voxel_size, default_length_scale, noise, &r);
    r.smooth = smooth_volume(v, so, progress, normal_map, checkpoint);
    r.smoothed = true;
    append(r.warnings, r.smooth.warnings);
    r.seconds.smooth = clock.lap();
    r.seconds.total += r.seconds.smooth;
}

Volume smooth_mesh_to_volume(const Mesh& m, const PipelineOptions& o, PipelineReport* report, Progress* progress,
                             NormalMap* normal_map) {
    validate(o);
    PipelineReport local;
    PipelineReport& r = report ? *report : local;
    PipelineOptions scan = o;
    scan.smoothing = true;
    const ScanInput in = prepare_scan(m, scan, r, progress, normal_map == nullptr);
    if (in.o.brick_voxels > 0) return scan_and_smooth_in_bricks(in, m, r, progress, nullptr, nullptr);
    Volume v = normalflow::scan(in, r, progress);
    smooth_volume_stage(v, o, m, &r, progress, normal_map);
    return v;
}

void smooth_volume_stage(Volume& v, const PipelineOptions& o, const Mesh& input, PipelineReport* report,
                         Progress* progress, NormalMap* normal_map, const SmoothCheckpoint* checkpoint) {
    smooth_volume_stage(v, o, model_length_scale(input), input_noise(input), report, progress, normal_map, checkpoint);
}

PipelineResult smooth_volume_input(Volume& v, const PipelineOptions& o, Progress* progress, bool want_mesh,
                                   NormalMap* normal_map) {
    validate(o);
    if (o.connectivity == Connectivity::Keep)
        throw InvalidInput("connectivity keep: a volume has no input mesh to keep; its surface is extracted");
    if (o.closed) throw InvalidInput("closed: a volume's surface is extracted closed already");
    if (o.scan.resolution != 0 || o.scan.shell_thickness != 0)
        throw InvalidInput("scan conversion options (resolution, shell) do not apply to a volume input");
    v.check("smooth_volume_input");
    PipelineResult result;
    PipelineReport& r = result.report;
    r.scan.grid = v.grid;
    if (o.smoothing)
        smooth_volume_stage(v, o, kVolumeLengthScaleVoxels * v.grid.voxel_size, 0, &r, progress, normal_map);
    if (want_mesh) {
        result.mesh = volume_to_mesh(v, o, &r, progress);
        check_output(result.mesh, r, true, true);
    }
    r.peak_memory_bytes = peak_memory_bytes();
    return result;
}

void place_mesh(Mesh& m, const Placement& p) {
    if (p.is_identity()) return;
    for (Vec3f& x : m.positions) {
        const Vec3d w = p.point(Vec3d{x.x, x.y, x.z});
        x = Vec3f{float(w.x), float(w.y), float(w.z)};
    }
    for (Vec3f& n : m.normals) {
        const Vec3d d = p.direction(Vec3d{n.x, n.y, n.z});
        n = Vec3f{float(d.x), float(d.y), float(d.z)};
    }
    if (p.reflects())
        for (auto& t : m.triangles) std::swap(t[1], t[2]);
}

}  // namespace normalflow

namespace normalflow {

struct BrickWorker::State {
    Mesh mesh;
    BrickContext context;
    DistanceQuery distance = DistanceQuery::EngineBvh;
    std::once_flag built;
    std::unique_ptr<ClosestTriangleQuery> query;
    std::unique_ptr<WindingNumber> wn;
};

BrickWorker::BrickWorker(std::string_view context) : state_(std::make_unique<State>()) {
    if (context.empty()) throw InvalidInput("brick context: the message is empty");
    const int distance = static_cast<unsigned char>(context[0]);
    if (distance != int(DistanceQuery::EngineBvh) && distance != int(DistanceQuery::CgalAabb))
        throw InvalidInput("brick context: not a brick context of this build");
    state_->distance = DistanceQuery(distance);
    brick_context_from_message(context.substr(1), state_->context, state_->mesh);
}

BrickWorker::~BrickWorker() = default;

std::string BrickWorker::run(std::string_view message) const {
    BrickJob job = brick_job_from_message(message);
    State& s = *state_;
    BrickContext c = s.context;
    if (job.scan) {
        std::call_once(s.built, [&] {
#ifdef NORMALFLOW_HAS_CGAL
            if (s.distance == DistanceQuery::CgalAabb) s.query = make_aabb_query(s.mesh);
#endif
            if (!s.query) s.query = make_bvh_query(s.mesh);
            if (s.context.scan.shell_thickness == 0) s.wn = std::make_unique<WindingNumber>(s.mesh);
        });
        c.query = s.query.get();
        c.wn = s.wn.get();
    }
    return brick_message(run_brick(c, std::move(job)));
}

}  // namespace normalflow
