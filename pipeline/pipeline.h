#pragma once
/// \file pipeline.h
/// The whole mesh-to-mesh pipeline of normalflow in one call: repair → scan conversion → level-set
/// normal-map smoothing (Tasdizen et al. 2003) → marching-tetrahedra extraction → decimation.
/// The normalflow tool (voxelize, extract, smooth) and the pipeline benchmarks run exactly this.
/// No CGAL type appears here; repair needs a build with NORMALFLOW_WITH_CGAL, decimation runs in any
/// build (CGAL adds its self-intersection check and fallback).

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh.h"
#include "core/mesh_report.h"
#include "core/progress.h"
#include "core/volume.h"
#include "extract/extract_surface.h"
#include "fit/face_filter.h"
#include "fit/fit_mesh.h"
#include "fit/untangle.h"
#include "io/cgal/cleanup.h"
#include "io/cgal/repair.h"
#include "metrics/surface_distance.h"
#include "normals/bricks.h"
#include "normals/smooth.h"
#include "pipeline/system_memory.h"
#include "remesh/sharpen.h"
#include "remesh/trim_to_footprint.h"
#include "sdf/scan_convert.h"

namespace normalflow {

/// Which closest-triangle search scan conversion uses. Both give the exact closest point (up to
/// rounding) and hence the same distances.
enum class DistanceQuery {
    EngineBvh,  ///< lib/sdf make_bvh_query: the engine's own BVH (less than half the cost of CGAL's tree)
    CgalAabb,   ///< io/cgal make_aabb_query: CGAL's AABB tree (needs a build with CGAL)
};

/// "bvh" or "aabb", as the command line spells it.
const char* to_string(DistanceQuery q);

/// Band half-width, voxels, that scan conversion uses at least when smooth_volume runs next:
/// smooth_volume rebuilds its own 8-voxel band (engine::kHalfWidth, lib/band/layout.h) from the
/// surface, so a 3-voxel band holds all it reads.
inline constexpr float kSmoothingScanBandVoxels = 3.0f;

/// scan.resolution = 0 (and no voxel size): the resolution is chosen from the input,
/// kAutoVoxelsPerLength voxels per model length unit along the longest side, clamped to
/// [kAutoResolutionMin, kAutoResolutionMax] and lowered until the memory estimate fits.
inline constexpr double kAutoVoxelsPerLength = 5.0;
inline constexpr int kAutoResolutionMin = 128;
inline constexpr int kAutoResolutionMax = 512;

/// Options of smooth_mesh (and of its halves, mesh_to_volume and volume_to_mesh).
/// What smooth_mesh hands back.
enum class Connectivity {
    Auto,    ///< Keep for an open input (has_open_boundary), and for a closed one whose kept result is manifold with
             ///< no pair of faces intersecting (as clean as a re-meshed one); Remesh for the other closed ones: a
             ///< non-manifold input at once, one whose kept result has intersecting faces by running again
             ///< (PipelineReport::keep_declined says why)
    Keep,    ///< the input mesh itself, its faces filtered or its vertices moved onto the processed surface
             ///< (KeepFilter): the same vertices, faces and order, open where the input was open
    Remesh,  ///< the extracted zero level set: a new mesh, closed and manifold
};

/// "auto", "keep", "remesh".
const char* to_string(Connectivity c);

/// How a kept mesh is smoothed.
enum class KeepFilter {
    /// The input's own faces filtered (filter_faces): each face's normal over its neighbours, guided by its
    /// most consistent patch, the vertices following, for the rounds that leave the least error by Stein's
    /// unbiased risk estimate for the input's noise (FaceFilterOptions::stop_noise; estimate_noise along
    /// steady normals), at most kMaxFaceRounds. The
    /// smoothed volume decides Auto's keep on a closed input; the volume guards the result against faces that
    /// turn over or intersect. On an open input (kept under Keep or Auto alike, no decision needed) the engine
    /// does not run: the guard's volume is the input's own distance.
    Faces,
    /// The vertices fitted to the processed volume (fit_mesh_to_volume), then the face filter guided by
    /// the volume's normals (one round unless faces.normal_steps says otherwise): the paper's surface on
    /// the input's mesh.
    Volume,
    /// The fit to the processed volume alone.
    Fit,
};

/// "faces", "volume", "fit".
const char* to_string(KeepFilter k);

/// KeepFilter::Faces: the most rounds of the face filter. The risk estimate ends the rounds (kRiskPatience past
/// its least); this only bounds the cost, each round costing 1 + kRiskProbes filters of the whole mesh. The study's
/// pairs keep 1 (pierrot_i3) to 40 (fandisk_n6) rounds and run 4 to 43: a bound of 30 cut fandisk_n6 short
/// by 0.15° face by face (docs/history/benchmarks-2026.md, "The face filter's rounds").
inline constexpr int kMaxFaceRounds = 100;

/// A kept mesh's folds are unfolded (untangle) with no vertex moving farther than this many times the input's noise
/// (PipelineReport::noise) from where it was: the noise moved its vertices about that far along the surface (3σ holds
/// 99.7% of Gaussian noise), and a mesh whose folds are not the noise's stays nearly as it was. On the study's heavily
/// noisy pairs the reach of 3σ unfolds as much as no limit, and leaves fandisk_n6 0.3° better face by face.
inline constexpr double kUntangleNoiseReach = 3.0;

/// PipelineOptions::sharpen: no vertex moves farther than this many voxels (the bevel marching tetrahedra cuts is
/// about one voxel wide; two let vertices cross and meet: fandisk at 256, docs/history/benchmarks-2026.md "Sharp re-meshing").
inline constexpr double kSharpenMaxMoveVoxels = 1.0;

/// A re-meshed result is decimated by default (PipelineOptions::full_density false) while each collapse stays
/// within this many voxels of the surface's tangent planes: the marching-tetrahedra surface has several triangles
/// per voxel, far more than its shape needs. How many faces stay is decided by the normal bound below: on the
/// study's four re-meshed pairs 0.05 and 0.1 voxel keep the same count within 1.5%, so the distance is bounded as
/// tightly as costs no faces; 0.1 moved the mean normal angle by up to +0.14° from the full-density result, 0.05 by
/// at most +0.08° (docs/history/benchmarks-2026.md, "Compact output by default").
inline constexpr double kCompactErrorVoxels = 0.05;
/// ... and while no face turns more than this (degrees) from the surface's normals at its corners: the distance
/// alone lets faces grow on gentle bends until their shading is visibly faceted.
inline constexpr double kCompactNormalDeviationDeg = 4.0;
/// Components of a re-meshed result beyond the input's count are removed when each has less than this fraction of
/// the result's area (remove_extra_components): bubbles where the input's inside was uncertain, specks a smoothing
/// split off. Larger ones stay, with a warning.
inline constexpr double kExtraComponentAreaFraction = 0.01;

/// Which decimator target_faces runs (decimate_mesh).
enum class Decimator {
    Auto,           ///< Quadric, its result checked; CGAL's edge collapse instead where that result breaks a
                    ///< guarantee the input had (closed, manifold, free of self-intersections) and the
                    ///< build has CGAL
    Quadric,        ///< normalflow's own quadric edge collapse (lib/remesh decimate_mesh_qem) only: its
                    ///< result is checked and reported, never replaced
    Meshoptimizer,  ///< meshoptimizer's simplifier (io/meshopt; fast, but version 0.18 leaves extracted
                    ///< surfaces non-manifold and self-intersecting: docs/history/benchmarks-2026.md, "Decimation")
    Cgal,           ///< CGAL's edge collapse (io/cgal cleanup_mesh, FaceCount): the decimator before version 0.2
};

/// "auto", "quadric", "meshoptimizer", "cgal".
const char* to_string(Decimator d);

/// What decimate_mesh did and what the result is.
struct DecimationReport {
    std::string decimator;  ///< the decimator whose result was kept: "quadric", "meshoptimizer" or "cgal"
    std::string fallback;   ///< Decimator::Auto: why CGAL re-did the quadric decimation ("" when it did not)
    std::size_t faces_before = 0;
    std::size_t faces_after = 0;
    std::size_t vertices_before = 0;
    std::size_t vertices_after = 0;
    /// Sampled distances between the result and the input, world units (sampled_max_distance: from the
    /// result its vertices and 3 points per face, from the input its vertices), and their maximum.
    double hausdorff = 0.0;
    double result_to_input = 0.0;
    double input_to_result = 0.0;
    bool closed = false;                ///< the result has no boundary edge
    bool manifold = false;              ///< the result has no non-manifold edge or vertex
    long long self_intersections = -1;  ///< pairs of intersecting faces; -1: not checked (a build without CGAL)
    /// Decimator::Auto: pairs the quadric decimation left that CGAL's local repair then removed.
    std::size_t repaired_self_intersections = 0;
    double seconds_decimate = 0.0;  ///< the decimation itself (both decimators' when CGAL re-did it)
    double seconds = 0.0;           ///< the whole call: decimation, checks and distances
    std::vector<std::string> warnings;
};

struct PipelineOptions {
    /// Scan conversion: resolution (0: automatic, auto_resolution) or voxel size, band half-width (raised to
    /// kSmoothingScanBandVoxels when smoothing), shell thickness, threads.
    ScanConvertOptions scan{.resolution = 0};
    /// Repair the mesh first (io/cgal repair_mesh: merge points, drop degenerate and duplicate
    /// faces, orient). Without CGAL it is skipped with a warning.
    bool repair = true;
    /// Closest-triangle search of the scan conversion.
    DistanceQuery distance = DistanceQuery::EngineBvh;
    /// Run smooth_volume between scan conversion and extraction (false: voxelize and extract only).
    bool smoothing = true;
    /// The engine's options (mode, iterations, ...); used when smoothing. Its length_scale, when
    /// 0, is set from length_scale below. The pipeline's default mode is Bilateral (the engine's
    /// own default, Anisotropic, is the paper's): docs/history/benchmarks-2026.md, "Normal filters beyond
    /// the paper", has the study that chose it.
    /// Its sigma_spatial, when 0, follows the input's noise (auto_sigma_spatial).
    SmoothOptions smooth{.mode = SmoothMode::Bilateral};
    /// World units, >= 0: the model's length unit for the engine (SmoothOptions::length_scale);
    /// 0: the input's median edge length, at most 1/25.6 of its longest side (model_length_scale).
    double length_scale = 0;
    /// What comes back: the input's own mesh fitted to the result, or a new one extracted from it.
    /// Auto keeps an open input's, and a closed input's whose kept result is manifold with no faces intersecting, and
    /// re-meshes the others. Keep refuses target_faces.
    Connectivity connectivity = Connectivity::Auto;
    /// An open input re-meshed comes back open: the cap that closed its volume is trimmed off
    /// (trim_to_footprint). closed = true keeps the closed, watertight surface instead (3D printing,
    /// tetrahedra); with Auto it re-meshes an open input; Keep refuses it.
    bool closed = false;
    /// The fit of the input's mesh (Connectivity::Keep).
    FitOptions fit;
    /// How a kept mesh is smoothed: its own faces filtered (the default), or fitted to the volume.
    KeepFilter keep_filter = KeepFilter::Faces;
    /// The kept mesh's face filter (filter_faces). faces.normal_steps: the most rounds; 0 (the default) is
    /// kMaxFaceRounds for KeepFilter::Faces (which stops by the risk estimate) and 1 for KeepFilter::Volume.
    /// faces.stop_noise is set from the input's noise (KeepFilter::Faces).
    FaceFilterOptions faces{.normal_steps = 0};
    /// Turn the kept mesh's faces to the engine's last filtered normal map (smooth_volume's normal_map)
    /// rather than to ∇φ of the result.
    bool fit_to_normal_map = false;
    /// Extraction of the zero level set.
    ExtractOptions extract;
    /// > 0: decimate the extracted mesh to at most this many faces, >= 4 (decimate_mesh); 0: keep
    /// every triangle.
    std::size_t target_faces = 0;
    /// > 0: decimate the extracted mesh while each collapse stays within this distance (world units) of
    /// the surface's tangent planes (QemOptions::max_error); with target_faces, whichever stops first.
    /// An adaptive mesh: few large faces where the surface is flat, small ones where it bends.
    double max_error = 0;
    /// The decimator target_faces and max_error run.
    Decimator decimator = Decimator::Auto;
    /// false (the default): a re-meshed result without target_faces or max_error is decimated within
    /// kCompactErrorVoxels of its surface and kCompactNormalDeviationDeg of its normals, a mesh whose size follows
    /// its shape; true: every triangle of the extraction is kept.
    bool full_density = false;
    /// A re-meshing without smoothing (smoothing = false, the surface re-meshed): move the extracted vertices onto
    /// the input's creases and corners (sharpen_mesh, the input as the reference) before any decimation, which then
    /// keeps them (face planes, not the field's rounded normals). Faces a move made intersect get their vertices
    /// back (builds with CGAL). Refused with smoothing: the smoothed surface's creases are its own, and sharpening
    /// towards its volume was measured worse (docs/history/benchmarks-2026.md, "Sharp re-meshing").
    bool sharpen = false;
    /// Refuse, before anything big is allocated, a run estimated to need more than this many
    /// bytes; 0: the memory the system has available now (MemAvailable).
    std::size_t max_memory_bytes = 0;
    /// The engine brick by brick (smooth_in_bricks): the side of a brick, voxels (whole 8³ blocks); 0 (the default):
    /// the whole volume at once where its estimate fits the memory limit (max_memory_bytes, or the memory available),
    /// otherwise the largest bricks whose estimate fits (plan_bricks). A run that does not smooth does not brick.
    int brick_voxels = 0;
    /// The halo of a brick, voxels; 0: brick_halo_voxels (what one main iteration reaches).
    int brick_halo_voxels = 0;
};

/// Wall seconds of each stage of a run.
struct PipelineSeconds {
    double repair = 0;
    double voxelize = 0;  ///< memory check and scan conversion (distance-query build included)
    double smooth = 0;
    double extract = 0;  ///< extraction, or the fit of the input's mesh when its connectivity is kept
    double decimate = 0;
    double total = 0;
};

/// What smooth_mesh (or one of its halves) did.
struct PipelineReport {
    bool repaired = false;                              ///< repair ran (options.repair and a build with CGAL)
    RepairReport repair;                                ///< valid when repaired
    DistanceQuery distance = DistanceQuery::EngineBvh;  ///< the query used
    ScanConvertOptions scan_options;                    ///< the scan conversion's options as run (band rule applied)
    double memory_estimate_bytes = 0;                   ///< estimated peak of the run (see check_memory)
    double estimated_window_blocks = 0;  ///< bricked: the most blocks one window's engine was planned for (plan_bricks)
    ScanConvertReport scan;
    double length_scale = 0;         ///< world units: the model length unit the engine ran with (0: not smoothed)
    double noise = 0;                ///< world units: the input's noise (estimate_noise; 0: not estimated)
    double sigma_spatial = 0;        ///< length units: the spatial scale the model-unit filters ran with
    bool smoothed = false;           ///< smooth_volume ran
    SmoothReport smooth;             ///< valid when smoothed
    ExtractReport extract;           ///< valid when !connectivity_kept
    bool connectivity_kept = false;  ///< the result is the input's mesh (Connectivity::Keep, or Auto's keep)
    /// Connectivity::Auto re-meshed a closed input because of these defects: the input's non-manifold edges and
    /// vertices, or its kept result's pairs of intersecting faces (without CGAL, faces turned over against the
    /// surface); "" otherwise.
    std::string keep_declined;
    bool fitted = false;          ///< the input's mesh was fitted to the volume (KeepFilter::Volume, Fit)
    FitReport fit;                ///< valid when fitted
    bool faces_filtered = false;  ///< the kept mesh's faces were filtered (filter_faces)
    FaceFilterReport faces;       ///< valid when faces_filtered
    /// KeepFilter::Faces: the input's faces folded over against the volume unfolded along its surface before the
    /// filter (untangle_input) and those the filter folded after it (untangle_filtered); valid when untangled.
    bool untangled = false;
    UntangleReport untangle_input, untangle_filtered;
    /// Kept: vertices moved back toward their input position (halfway each time, all the way after four halvings)
    /// because the fit made their faces intersect others, lose their area or turn over against the volume's surface
    /// (faces_against_volume; the smoothed one, or the input's own where the engine did not run) where the input's
    /// did not; -1: the intersections not checked (a build without CGAL).
    long long fit_restored = 0;
    bool trimmed = false;    ///< an open input's re-meshed result was trimmed to its footprint
    TrimReport trim;         ///< valid when trimmed
    bool sharpened = false;  ///< the extraction was sharpened to the input (options.sharpen)
    SharpenReport sharpen;   ///< valid when sharpened
    /// Sharpened: vertices given back their extracted position because their faces intersected others; -1: not
    /// checked (a build without CGAL).
    long long sharpen_restored = 0;
    ComponentsRemoved components;  ///< the extraction's components and those removed as extra (re-meshed inputs)
    bool decimated = false;        ///< decimation ran (target_faces, max_error, or the compact default)
    bool compacted = false;        ///< the decimation was the compact default (not asked for)
    DecimationReport decimate;     ///< valid when decimated
    /// What the written result is, checked at the end: closed, manifold, degenerate faces, and the pairs of faces
    /// that intersect as the file has them (count_self_intersections_as_written; -1 without CGAL).
    bool checked = false;
    MeshReport output;
    long long output_self_intersections = -1;
    /// Kept: the pairs the input had, counted the same way (welded: a kept input may be a soup); -1 otherwise.
    long long input_self_intersections = -1;
    /// Kept: the faces of the result, and of the input, that point against the volume's surface (the smoothed one,
    /// or the input's own where the engine did not run: KeepFilter::Faces); -1 otherwise.
    long long flipped_faces = -1, input_flipped_faces = -1;
    bool bricked = false;  ///< the engine ran brick by brick (options.brick_voxels, or a volume over the memory limit)
    BrickReport bricks;    ///< valid when bricked
    PipelineSeconds seconds;
    std::size_t peak_memory_bytes = 0;  ///< peak resident memory of the process at the end (Linux; 0 elsewhere)
    std::vector<std::string> warnings;  ///< every stage's warnings, in stage order
};

/// What smooth_mesh returns: the result and the report of the run.
struct PipelineResult {
    Mesh mesh;
    PipelineReport report;
};

/// Where a bricked run's bricks run when not here (Python's client=, a Dask cluster), as messages: called once per
/// pass over the bricks with the run's context (its mesh, grid and options; equal bytes on every pass of a run),
/// the number of bricks, make(i): brick i's job, and take(outcome): a brick's outcome, given back in order of i.
/// A worker runs a job with BrickWorker.
using BrickMessageRunner =
    std::function<void(const std::string& context, int count, const std::function<std::string(int)>& make,
                       const std::function<void(const std::string&)>& take)>;

/// Smooths a triangle mesh through its signed distance volume: repairs a copy of m (optional),
/// scan-converts it (scan_convert) into a narrow band of max(scan.half_width,
/// kSmoothingScanBandVoxels) voxels, filters the normal map and refits (smooth_volume, Tasdizen
/// et al. 2003), extracts the zero level set as a closed manifold mesh (extract_surface), and
/// decimates it (optional). With options.smoothing = false the volume goes to extraction as
/// scanned (a remeshing).
///
/// Accepted input: what scan_convert accepts (any triangle soup; open sheets need
/// scan.shell_thickness). The re-meshed result is closed and manifold (before decimation by
/// construction); with options.connectivity Keep (Auto: for an open input) it is m itself with its
/// vertices moved (options.keep_filter: its own faces filtered, with no engine run on an open m; or
/// fitted to the volume, fit_mesh_to_volume), as open as m was. An open input re-meshed is trimmed to its
/// footprint (trim_to_footprint), unless options.closed.
/// Attributes: the result has vertex normals from the processed volume (set_volume_normals), or, kept on its own
/// faces, from those faces (compute_vertex_normals). Kept
/// connectivity keeps m's colours and texture coordinates; re-meshing takes m's colours by closest
/// point (transfer_colors) and drops its texture coordinates, with a warning.
/// \throw InvalidInput for bad options (the message names the field, e.g. "smooth.mu"), a mesh
///        scan_convert refuses, or a surface that vanished during smoothing;
///        OutOfMemory when the estimated peak exceeds the limit (check_memory);
///        NumericalError, Cancelled as the stages throw them.
/// Messages do not name the input; a caller that has a file name prefixes it.
/// Threading: scan.threads and smooth.threads; the result does not depend on them.
/// \param bricks where a bricked run's bricks go (Python's client=, a Dask cluster); null: here. The result is the
///        same either way, bit for bit. A run that does not brick ignores it (its report says so).
PipelineResult smooth_mesh(const Mesh& m, const PipelineOptions& options = {}, Progress* progress = nullptr,
                           const BrickMessageRunner* bricks = nullptr);

/// What a worker of a bricked run does with its bricks (Python's Dask bricks): built from the run's context message
/// (BrickMessageRunner), it runs the jobs' messages and returns their outcomes' (run_brick). The mesh's search and
/// winding number are built on the first brick that scans its window, and kept. run() may be called from several
/// threads at once.
class BrickWorker {
public:
    /// \throw InvalidInput for a message that is not a brick context of this build.
    explicit BrickWorker(std::string_view context);
    ~BrickWorker();
    BrickWorker(const BrickWorker&) = delete;
    BrickWorker& operator=(const BrickWorker&) = delete;
    /// \throw InvalidInput for a message that is not a job of this build; what run_brick throws.
    std::string run(std::string_view job) const;

private:
    struct State;
    std::unique_ptr<State> state_;
};

/// The first half of smooth_mesh: validation, repair, memory check and scan conversion. When
/// options.smoothing, the band is at least kSmoothingScanBandVoxels and the memory check counts the
/// engine. Fills the repair, scan and seconds parts of report (and its warnings).
Volume mesh_to_volume(const Mesh& m, const PipelineOptions& options = {}, PipelineReport* report = nullptr,
                      Progress* progress = nullptr);

/// The second half of smooth_mesh: extraction and, with options.target_faces > 0 or options.max_error > 0,
/// decimation (decimate_mesh by the tangent planes of v's normals at the vertices); the result has vertex
/// normals from v (set_volume_normals). options.smoothing only selects the message
/// when the volume holds no surface. The mesh is placed in the volume's world (place_mesh with
/// v.grid.placement).
/// \throw InvalidInput if the volume holds no surface.
Mesh volume_to_mesh(const Volume& v, const PipelineOptions& options = {}, PipelineReport* report = nullptr,
                    Progress* progress = nullptr);
/// volume_to_mesh with options.sharpen: the extraction sharpened to reference (the mesh v was made from) before
/// the decimation. reference is not used without options.sharpen.
Mesh volume_to_mesh(const Volume& v, const PipelineOptions& options, PipelineReport* report, Progress* progress,
                    const Mesh* reference);

/// The model length unit smooth_volume_input gives the engine for a volume that did not come from a mesh (a
/// volume file), in voxels of its grid: the scale of a scan's noise and of a binary mask's staircase. The
/// command line counts it in the file's coarsest spacing instead (the same for isotropic files), as the
/// staircase of an anisotropic file is as coarse as that. Chosen on the ball mask: docs/history/benchmarks-2026.md,
/// "Volumes in and out".
inline constexpr double kVolumeLengthScaleVoxels = 1.0;

/// The spatial scale of the model-unit filters (bilateral, guided, tv) when sigma_spatial is 0 (`auto`), in
/// length units: twice the input's noise (estimate_noise, world units), so that the filter averages over
/// the scale the noise moved the vertices and no further (σ = 0.3 edges gives 0.6, the default); never
/// more than kMaxAutoSigmaSpatial (a coarse model's curvature and creases read as noise), never below one
/// voxel (a smaller disc holds no neighbour); kMaxAutoSigmaSpatial when the noise is unknown (0: a volume
/// input). length_unit and voxel_size in world units. Not the default: on the study's pairs the noise
/// alone does not say how much to smooth (at the same σ = 0.2 edges julius gains 1.2° and bunny loses
/// 0.8°; benchmarks/README.md, "Kept mesh").
inline constexpr double kMaxAutoSigmaSpatial = 0.6;
double auto_sigma_spatial(double noise, double length_unit, double voxel_size);

/// The smoothing stage of smooth_mesh on its own: smooth_volume on v with options.smooth, its length
/// unit (when options.smooth.length_scale is 0) options.length_scale, else default_length_scale (world
/// units), and its sigma_spatial (when 0) auto_sigma_spatial of noise (world units; 0: unknown). Fills
/// report's length_scale, noise, sigma_spatial, smoothed, smooth, seconds.smooth and warnings. checkpoint
/// (optional): smooth_volume's, asked after each main iteration but the last whether to go on.
void smooth_volume_stage(Volume& v, const PipelineOptions& options, double default_length_scale, double noise = 0,
                         PipelineReport* report = nullptr, Progress* progress = nullptr,
                         NormalMap* normal_map = nullptr, const SmoothCheckpoint* checkpoint = nullptr);
/// The smoothed volume of a mesh, without extraction (the command line's volume output): mesh_to_volume and
/// smooth_volume_stage, or, where the whole volume does not fit the memory or options.brick_voxels asks for bricks,
/// the two brick by brick as smooth_mesh runs them (report.bricked). A normal map (normal_map not null) is the whole
/// run's: with it the run is not bricked (over the memory it is refused, OutOfMemory).
Volume smooth_mesh_to_volume(const Mesh& m, const PipelineOptions& options, PipelineReport* report = nullptr,
                             Progress* progress = nullptr, NormalMap* normal_map = nullptr);
/// smooth_volume_stage of a volume scan-converted from input: the length unit and the noise are input's
/// (model_length_scale, estimate_noise).
void smooth_volume_stage(Volume& v, const PipelineOptions& options, const Mesh& input, PipelineReport* report = nullptr,
                         Progress* progress = nullptr, NormalMap* normal_map = nullptr,
                         const SmoothCheckpoint* checkpoint = nullptr);

/// smooth_mesh for a volume (a level set, or an image made into one, image_to_volume): smooths v in place
/// (options.smoothing; the length unit kVolumeLengthScaleVoxels voxels unless options.length_scale) and
/// extracts and decimates it (volume_to_mesh), unless want_mesh is false (the caller writes the volume).
/// The mesh is in the volume's world (its grid's placement). Connectivity::Keep and options.closed have
/// no input mesh to keep and are refused, as is a scan conversion option (scan.resolution, shell).
/// 	hrow InvalidInput for bad options or a volume without a surface; as smooth_mesh otherwise.
/// normal_map, when given, receives the engine's last filtered normal map (smooth_volume).
PipelineResult smooth_volume_input(Volume& v, const PipelineOptions& options = {}, Progress* progress = nullptr,
                                   bool want_mesh = true, NormalMap* normal_map = nullptr);

/// Maps a mesh from a volume grid's frame to the world of its file (Placement): positions, normals, and the
/// faces' orientation where the placement reflects (so they still face outwards). Nothing for the identity.
void place_mesh(Mesh& m, const Placement& placement);

/// What decimate_mesh does.
struct DecimationOptions {
    std::size_t target_faces = 0;  ///< faces to keep at most, >= 4; 0: none (then max_error > 0)
    /// > 0: no collapse beyond this quadric error, world units (QemOptions::max_error); CGAL's fallback then
    /// bounds its sampled distance to m by it instead (cleanup_mesh, ErrorBound). Not for meshoptimizer.
    double max_error = 0;
    Decimator decimator = Decimator::Auto;
    /// The quadric decimator builds its quadrics from the tangent planes of m.normals (QemOptions::
    /// tangent_planes): for an extracted surface with the field's normals (set_volume_normals).
    bool tangent_planes = false;
    /// With tangent_planes, > 0: no face of the result turned more than this (degrees) from m.normals at its
    /// corners (QemOptions::max_normal_deviation_deg); the quadric decimator only.
    double max_normal_deviation_deg = 0;
    /// m's mesh_report, when the caller has it: the guarantees are checked against it instead of
    /// computing it again (0.7 s for a million faces).
    const MeshReport* input_report = nullptr;
    /// false: DecimationReport's distances are left at 0, for a caller that measures its own final result.
    bool measure_distance = true;
    /// Decimator::Quadric: also try CGAL's local self-intersection repair on its result, as Auto does (builds with
    /// CGAL), without Auto's fallback to CGAL's edge collapse of the whole mesh.
    bool local_repair = false;
};

/// Decimates m in place with options.decimator to at most options.target_faces faces and/or within
/// options.max_error; see the overload below, which this one generalises.
DecimationReport decimate_mesh(Mesh& m, const DecimationOptions& options);

/// Decimates m in place to at most target_faces faces (>= 4) with the chosen decimator, then checks
/// the result: closed and manifold where m was, free of self-intersections (builds with CGAL), and its
/// sampled Hausdorff distance to m. Decimator::Auto runs normalflow's quadric edge collapse
/// (decimate_mesh_qem: manifold by construction, no folds); where two parts were decimated through
/// each other and the build has CGAL, CGAL's local self-intersection repair on that result (kept if it
/// clears them all); where a guarantee is still broken, CGAL's edge collapse (cleanup_mesh) on m
/// instead, with the reason in DecimationReport::fallback. Attributes: the quadric and meshoptimizer decimators keep the surviving
/// vertices' normals, colours and texture coordinates; CGAL's result has none.
/// \throw InvalidInput for an empty or invalid mesh, target_faces < 4, or a decimator this build lacks.
/// Cost: fandisk extracted at resolution 256 (1.1 M faces) to 20,000 faces: docs/history/benchmarks-2026.md,
/// "Decimation" (nf_bench_decimate).
DecimationReport decimate_mesh(Mesh& m, std::size_t target_faces, Decimator decimator = Decimator::Auto);

/// The distances decimate_mesh reports between a decimated result and its input (world units): from the
/// result its vertices and 3 points per face, from the input (dense, so they suffice) its vertices only
/// (sampled_max_distance both ways).
SampledDistance decimation_distance(const Mesh& result, const Mesh& input);

/// The median length of the mesh's edges (each triangle's three, so an inner edge counts twice),
/// world units; 0 for a mesh without triangles.
double median_edge_length(const Mesh& m);

/// What smooth_mesh takes as the model's length unit when PipelineOptions::length_scale is 0: the
/// median edge length (the noise of a scan or of a noisy mesh is about an edge long, and features
/// narrower than an edge are not in the mesh), but at most kAutoVoxelsPerLength voxels of the
/// coarsest automatic grid, the longest side of the bounding box / (kAutoResolutionMin /
/// kAutoVoxelsPerLength) = 1/25.6 of it. The automatic resolution puts kAutoVoxelsPerLength voxels
/// on the unit; an input so coarse that even kAutoResolutionMin puts more on its median edge (fewer
/// than 26 edges along its longest side: a low-poly or CAD export, a part of a few hundred
/// triangles) has facets that are its shape rather than the scale of its noise, and smoothing at
/// the facets' scale would round that shape and cost time ∝ (edge in voxels)²: such an input is
/// smoothed at the unit of the coarsest grid instead. Every input that reaches the automatic
/// resolution's lower bound by its edges alone is concerned; no other one is.
double model_length_scale(const Mesh& m);

/// The resolution smooth_mesh uses for scan.resolution = 0: kAutoVoxelsPerLength × the longest
/// side of the bounding box / the model length unit (length_scale, or model_length_scale(m)),
/// within [kAutoResolutionMin, kAutoResolutionMax], lowered by 10% steps while check_memory
/// refuses it (the last step's refusal is then check_memory's to give).
int auto_resolution(const Mesh& m, const PipelineOptions& options);

/// The bricks a smoothing run of m takes (PipelineOptions::brick_voxels): their side in voxels (0: none, the whole
/// volume at once) and the estimated peak. With brick_voxels = 0, none where the whole run's estimate (check_memory)
/// fits the limit; otherwise the largest side of 512, 384, 256, 192, 128, 96 or 64 voxels whose estimate fits, with
/// the result's band held in floats, and failing that, in a run of one pass, in 16 bits (compact_band: only the
/// closing reinitialisation reads it back). The estimate: the mesh and its search
/// trees, the result's band (φ only) and one window's engine and scanned volume; two copies of the band in a pass
/// after the first (the last pass's, which the windows read, and this one's), one in the first (the one it writes),
/// and two in the closing reinitialisation, whose windows hold less. one_pass: the run stops after its first pass (a
/// checkpoint: a closed mesh kept on its own faces), so no pass but the closing one holds two copies. The blocks
/// are counted, not estimated from the area: those
/// the input's surface passes within a voxel of and their 26 neighbours, as the engine allocates them, over the whole
/// grid for the band and within each window (brick and halo, cut as smooth_in_bricks cuts them) for the engine.
/// halo_voxels: the halo the engine needs (voxels); engine: the options the bricks will run with, whose filters' sample
/// stride cuts the windows (null: engine_options of options on this grid, with m's length scale).
/// \throw OutOfMemory when no brick size fits (the message names the limit and the smallest estimate).
struct BrickPlan {
    int brick_voxels = 0;
    double estimate_bytes = 0;
    double band_blocks = 0;     ///< blocks of the result's band, counted (0 where the whole volume fits)
    double window_blocks = 0;   ///< the most blocks one window's engine holds at the size chosen, counted (likewise)
    bool compact_band = false;  ///< the result's band held in 16 bits (BrickOptions::compact_band): floats do not fit
};
BrickPlan plan_bricks(const Mesh& m, const PipelineOptions& options, double voxel_size, int halo_voxels,
                      const SmoothOptions* engine = nullptr, bool one_pass = false);

/// The engine's options of a run on a grid of voxel_size: options.smooth with its length scale in voxels
/// (options.length_scale, or default_length_scale) and sigma_spatial's automatic value (auto_sigma_spatial of noise)
/// resolved; report (optional) receives the length scale, noise and sigma_spatial.
SmoothOptions engine_options(const PipelineOptions& options, double voxel_size, double default_length_scale,
                             double noise, PipelineReport* report = nullptr);

/// Checks every option smooth_mesh uses before any work is done.
/// \throw InvalidInput naming the field ("scan.resolution = 0: expected >= 1").
void validate(const PipelineOptions& options);

/// The scan conversion options smooth_mesh runs with: options.scan with the band rule applied.
ScanConvertOptions effective_scan_options(const PipelineOptions& options);

/// Refuses, before anything big is allocated, a run whose estimated peak (estimate_memory,
/// sdf/memory_estimate.h) exceeds options.max_memory_bytes or, when 0, what the system has
/// available. Returns the estimate in bytes (0 for a mesh without triangles or a bad voxel size,
/// which scan_convert refuses with a clear message).
/// \throw OutOfMemory "this run needs about ... at voxel size ..., more than the ... available; lower
///        --resolution or raise --max-memory".
double check_memory(const Mesh& m, const PipelineOptions& options);

}  // namespace normalflow
