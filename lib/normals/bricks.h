#pragma once
/// \file bricks.h
/// The scan conversion and the engine brick by brick: a volume too large for the memory at hand is processed one
/// window of its grid at a time, each window a brick's interior with a halo around it, and the interiors are put
/// together into the one volume the whole run would have made. Every stage is local (the scan conversion reads the
/// triangles near a sample, a filter pass its disc, the refit a bounded time, the band's move a few voxels), so a
/// brick whose halo covers what its interior depends on holds, in its interior, what the whole run holds there.

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"
#include "core/volume.h"
#include "normals/smooth.h"
#include "sdf/closest_triangle.h"
#include "sdf/scan_convert.h"

namespace normalflow {

/// How smooth_in_bricks cuts the grid.
struct BrickOptions {
    int brick_voxels = 128;  ///< the side of a brick's interior, voxels, >= 8 (rounded up to whole 8³ blocks)
    int halo_voxels = 0;     ///< the halo on each side, voxels (rounded up to whole blocks); 0: brick_halo_voxels
    /// Bricks run at once on threads of this process (each window held at once), >= 1; the engine's threads are
    /// shared out among them. The result does not depend on it. On 2 cores one brick at a time on both threads is
    /// faster (fandisk_n0.3 at 256 in bricks of 128: 23.2 s and 226 MB against 26.4–27.0 s and 393 MB with 2 at
    /// once), so the pipeline keeps 1.
    int concurrent = 1;
    /// The result's band held between passes in 16 bits per sample instead of a float (a step of 2.4·10⁻⁴ voxel at
    /// the engine's band of 8 voxels, every sign kept): half the bytes of the band, which the run holds whole besides a
    /// window. Meant for a run that stops after its first pass (a checkpoint), where only the closing reinitialisation
    /// reads it back: within 10⁻³ voxel of the floats (tests/normals/test_bricks.cpp). A second pass of the filters from
    /// it moved a test scene's surface by 0.01 to 0.12 voxel (their choices amplify the change). plan_bricks asks for it
    /// where floats do not fit such a run.
    bool compact_band = false;
    /// The blocks the result's band is expected to hold (plan_bricks's count; 0: unknown): its arrays are reserved for
    /// them, so that growing one never holds two copies at once.
    std::size_t expected_band_blocks = 0;
};

/// The halo smooth_in_bricks gives a brick by default: what one main iteration reaches, times the iterations, and
/// the engine's band. A main iteration of the surface-sample filters reads its disc (2 sigma_spatial ℓ) twice (the
/// filter, the extension) and refits for a time T = refit steps × refit_dt, a diffusion whose reach is taken as
/// 3 √(2T) (its kernel is below 1% there); the diffusions' normal loop runs for normal_steps × normal_dt in the same
/// way; the band is engine::kHalfWidth. opt's defaults must be resolved (length_scale in voxels, sigma_spatial > 0).
int brick_halo_voxels(const SmoothOptions& opt, int iterations);

/// The whole 8³ blocks of a brick's interior and of its halo as smooth_in_bricks cuts them: brick_voxels and the halo
/// (halo_voxels, or brick_halo_voxels(opt, 1) where 0) each rounded up to whole blocks, then to a multiple of the
/// filters' sample stride (surface_sample_stride), on which the windows start. Brick (i, j, k) covers the blocks
/// [i·brick, (i + 1)·brick) along x (likewise y, z), its window those and halo more on each side, both clipped to the
/// grid.
struct BrickBlocks {
    int brick = 0;  ///< the interior's side, blocks
    int halo = 0;   ///< the halo on each side, blocks
};
BrickBlocks brick_blocks(const SmoothOptions& opt, int brick_voxels, int halo_voxels);

/// What smooth_in_bricks did.
struct BrickReport {
    int brick_voxels = 0;                ///< the interior's side, voxels (whole blocks)
    int halo_voxels = 0;                 ///< the halo, voxels (whole blocks)
    std::array<int, 3> bricks{0, 0, 0};  ///< bricks along x, y, z
    int bricks_run = 0;  ///< bricks whose engine ran (their interior near a surface), summed over the iterations
    int passes = 0;      ///< main iterations run over the bricks
    std::size_t largest_window_blocks = 0;  ///< the most allocated blocks one brick's window held in the engine
    double seconds_scan = 0;                ///< wall seconds of the windows' scan conversions
    double seconds_smooth = 0;              ///< wall seconds of the engine over the bricks (reinitialisation too)
                                            ///< (summed over the bricks, where ever they ran)
    bool elsewhere = false;                 ///< the bricks ran where a BrickRunner sent them
    bool compact_band = false;              ///< the result's band was held in 16 bits (BrickOptions::compact_band)
    /// passes run again because the whole surface's refit would not have kept every super step (smooth_in_bricks):
    /// with its decision replayed in every brick, or (refit_passes_windowed of them) each brick deciding in its window
    int refit_passes_redone = 0;
    int refit_passes_windowed = 0;
    /// iterations whose refit went on in explicit steps (after the super steps' restarts), their patient stop
    /// decided on the whole surface's D: the steps probed in every brick (passes counted in refit_passes_redone)
    int refit_explicit_tails = 0;
    int total() const { return bricks[0] * bricks[1] * bricks[2]; }
};

/// What every brick of a run reads: the grid, the options, and (for the first iteration's scan of its window) the
/// mesh with its closest-triangle search and winding number.
struct BrickContext {
    const Mesh* mesh = nullptr;
    const ClosestTriangleQuery* query = nullptr;
    const WindingNumber* wn = nullptr;  ///< null only with scan.shell_thickness > 0
    Grid grid;                          ///< scan_grid(*mesh, scan)
    ScanConvertOptions scan;
    SmoothOptions engine;  ///< one main iteration's options, as every brick runs them (its window's fields aside)
    /// Ticks and cancellation within a brick (its window's scan: the stop; its engine: the steps), on the thread that
    /// runs the pass only: smooth_in_bricks sets it for the bricks it runs one after the other here, so that a brick
    /// of many minutes still moves the progress line and stops when asked. Bricks on threads of their own
    /// (BrickOptions::concurrent) read a stop the calling thread sets; a runner of the caller's gets null. Never
    /// carried in a message.
    Progress* progress = nullptr;
};

/// One brick of a pass over the bricks: its interior and window, and what the window starts from.
/// A pass's refit, the same for all its bricks: SmoothOptions' refit_whole_time, refit_replay_count and refit_replay
/// (the whole surface's decisions, replayed in every brick), refit_explicit_probe and refit_explicit_replay (its
/// explicit steps), over the context's engine options.
struct BrickRefit {
    bool whole_time = true;
    int replay_count = 0;
    std::array<int, kRefitSuperStepAttempts> replay{};
    int explicit_probe = 0;    ///< SmoothOptions::refit_explicit_probe
    int explicit_replay = -1;  ///< SmoothOptions::refit_explicit_replay
};

struct BrickJob {
    int index = 0;                   ///< its place in the pass (bricks in order of z, then y, then x)
    std::array<int, 3> lo{0, 0, 0};  ///< the interior, blocks of the grid
    std::array<int, 3> hi{0, 0, 0};
    BlockWindow window;              ///< the interior and its halo, blocks of the grid
    bool scan = false;               ///< the window is scan-converted (the first iteration); else `input`
    bool reinitialise_only = false;  ///< the window is only reinitialised (reinitialise_volume), as a run ends
    bool reinitialise_input = true;  ///< SmoothOptions::reinitialise_input for the engine's run
    Volume input;                    ///< the window of the last iteration's result (window_grid), unless scan
    BrickRefit refit;                ///< the pass's refit
};

/// What a brick made: its interior as its engine left it.
struct BrickOutcome {
    int index = 0;
    bool ran = false;        ///< its engine ran (the interior near a surface); `record` and `warnings` are its
    Volume interior;         ///< on window_grid(grid, {lo, hi}): the interior's blocks and tile signs
    SmoothIteration record;  ///< the engine's iteration (the fields smooth_in_bricks sums)
    std::vector<std::string> warnings;
    std::size_t window_blocks = 0;  ///< blocks the window held in the engine
    double seconds_scan = 0;        ///< wall seconds of the window's scan conversion
    double seconds_smooth = 0;      ///< wall seconds of its engine (or reinitialisation)
};

/// One brick's work, where ever it runs: the same job gives the same outcome, bit for bit, on any machine running
/// the same build, with any number of threads.
BrickOutcome run_brick(const BrickContext& context, BrickJob job);

/// Runs the bricks of one pass somewhere (smooth_in_bricks's default: one after the other, here): make(i) builds
/// brick i's job, for i in [0, count), when the runner is ready for it (a runner that holds one job at a time
/// holds one window); take() puts the outcomes back, in order of their index (what the pass sums does not depend
/// on where or when a brick ran).
using BrickRunner = std::function<void(const BrickContext& context, int count, const std::function<BrickJob(int)>& make,
                                       const std::function<void(BrickOutcome&&)>& take)>;

/// The messages that carry a brick elsewhere (Python's Dask bricks): a job, an outcome, and the context (the mesh,
/// the grid and the options; a search and winding number are the receiver's to build). Each starts with this
/// build's version and its options' sizes: a message from another build is refused (InvalidInput), as is a
/// truncated one.
std::string brick_message(const BrickJob& job);
std::string brick_message(const BrickOutcome& outcome);
BrickJob brick_job_from_message(std::string_view message);
BrickOutcome brick_outcome_from_message(std::string_view message);
/// The context's mesh (positions and triangles only), grid and options; its search pointers are not carried.
std::string brick_context_message(const BrickContext& context);
/// Fills `context` (but its search pointers) from a message, the mesh into `mesh` (context.mesh = &mesh). The
/// receiver builds the search, and the winding number where context.scan.shell_thickness is 0.
void brick_context_from_message(std::string_view message, BrickContext& context, Mesh& mesh);

/// scan_convert(m, q, scan) followed by smooth_volume(·, opt), brick by brick. The grid (scan_grid) is cut into
/// bricks of bricks.brick_voxels (whole blocks, on multiples of the filters' sample stride); the run goes one main
/// iteration at a time over all the bricks, each brick's window (its interior and halo) taken from the scan
/// (scan_convert_window, bit for bit the whole scan there) or from the last iteration's result, and its interior
/// copied into the next one. Between iterations the run does what the one run does, in the same order, on the
/// whole surface: the volume constraint's shift (preserve_volume: the bricks' interiors' volume changes and slopes
/// summed, SmoothOptions::defer_volume_shift), the filters' automatic stop (opt.iterations = 0: the roughness of
/// the iteration over the bricks' interiors' samples together, SmoothIteration::roughness_histogram), the checkpoint, and then the
/// band moved and φ reinitialised. Within an iteration each brick's refit keeps its whole time
/// (SmoothOptions::refit_whole_time), as the whole run does wherever D falls to the end; where the bricks' D summed
/// shows that the whole run would have undone a super step, the pass runs again with that decision replayed in every
/// brick (SmoothOptions::refit_replay). The result has the grid
/// and layout smooth_volume returns (a band of engine::kHalfWidth voxels). Memory: one window's engine at a time,
/// plus two copies of the result's band (the last iteration's and the next).
///
/// Where the halo covers what an interior depends on (brick_halo_voxels) the result is the whole run's within
/// rounding: tests/normals/test_bricks.cpp measures 0 on a noisy sphere and box, bricks a quarter of the grid.
///
/// \param wn m's winding number (null only with scan.shell_thickness > 0).
/// \param smooth_report receives one record per iteration over the whole (sums over the bricks; the refit's
///        steps and evaluations the most of any brick) and the stops decided.
/// \param checkpoint asked after each iteration but the last with the volume reinitialised (SmoothCheckpoint).
/// \param runner where the bricks run (null: here, one after the other); the result does not depend on it.
/// \throw InvalidInput for bad options; what scan_convert_window and smooth_volume throw; Cancelled via progress.
Volume smooth_in_bricks(const Mesh& m, const ClosestTriangleQuery& q, const WindingNumber* wn,
                        const ScanConvertOptions& scan, const SmoothOptions& opt, const BrickOptions& bricks,
                        BrickReport* report = nullptr, SmoothReport* smooth_report = nullptr,
                        Progress* progress = nullptr, const SmoothCheckpoint* checkpoint = nullptr,
                        const BrickRunner* runner = nullptr);

}  // namespace normalflow
