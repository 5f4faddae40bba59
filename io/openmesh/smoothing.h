#pragma once
/// \file smoothing.h
/// Mesh-side smoothing baselines that normalflow is compared against: Laplacian smoothing (which
/// shrinks), Taubin's λ|μ smoothing (which does not) and bilateral normal filtering (which keeps
/// creases). They run on OpenMesh's half-edge mesh; the conversion happens inside
/// openmesh_mesh.cpp and no OpenMesh type appears here.
///
/// Common behaviour of the three functions:
///  - Input: any triangle soup. Positions with identical coordinates are welded first (so a mesh
///    split per face still smooths as one surface). Faces OpenMesh cannot add to a manifold
///    half-edge mesh (a third face on an edge, a face that would make a vertex non-manifold,
///    repeated corners) are left out of the neighbourhoods; they are counted in
///    SmoothingReport::faces_skipped and a warning is added. Their corners still move if other faces
///    use them.
///  - Output: the same Mesh, modified in place: the triangles are unchanged, only positions move;
///    every copy of a welded point moves the same way; unreferenced points stay put. Colours and
///    texture coordinates stay; normals, when the mesh has them, are recomputed from the moved faces
///    (set_face_normals).
///  - Boundary vertices (on an edge with one face) stay fixed unless the options say otherwise.
///  - Deterministic: every iteration reads one position buffer and writes another (TBB
///    parallel_for over vertices), so the result does not depend on the number of threads.
///  - Empty input (no triangles) throws InvalidInput, as do out-of-range indices and non-finite
///    positions.

#include <cstddef>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"

namespace normalflow {

/// Weights of the umbrella operator L(p_i) = Σ_j w_ij (p_j − p_i) / Σ_j w_ij.
enum class LaplacianWeights {
    Uniform,  ///< w_ij = 1 (Taubin 1995's choice)
    Cotan     ///< w_ij = (cot α_ij + cot β_ij) / 2 of the input geometry, negative ones clamped to 0
              ///< (falls back to uniform where all weights of a vertex vanish)
};

/// Options of laplacian_smooth.
struct LaplacianOptions {
    double lambda = 0.5;                                   ///< step factor per iteration, in (0, 1]; p ← p + λ L(p)
    int iterations = 10;                                   ///< number of steps, >= 0
    LaplacianWeights weights = LaplacianWeights::Uniform;  ///< umbrella weights (fixed from the input)
    bool fix_boundary = true;                              ///< keep vertices on open boundaries in place
};

/// Options of taubin_smooth. One iteration is a λ step followed by a μ step (Taubin 1995, §4).
struct TaubinOptions {
    double lambda = 0.5;  ///< shrinking step, in (0, 1]
    double mu = -0.53;    ///< inflating step, negative with |μ| > λ (pass band k_PB = 1/λ + 1/μ ≈ 0.11)
    int iterations = 10;  ///< number of λ|μ pairs, >= 0
    LaplacianWeights weights = LaplacianWeights::Uniform;  ///< umbrella weights (fixed from the input)
    bool fix_boundary = true;                              ///< keep vertices on open boundaries in place
};

/// Options of bilateral_normal_filter.
struct BilateralNormalOptions {
    int normal_iterations = 20;  ///< face-normal filtering passes, >= 0 (Zheng et al. use 1 to 20)
    int vertex_iterations = 10;  ///< vertex-update passes after the normals are filtered, >= 0
    /// σ_s of the spatial Gaussian, world units; 0 = the mean distance between the centroids of
    /// edge-adjacent faces (Zheng et al.'s default). >= 0.
    double sigma_spatial = 0.0;
    /// σ_r of the range Gaussian on |n_i − n_j| (unitless, in (0, 2]); small values keep creases.
    double sigma_range = 0.35;
    bool fix_boundary = true;  ///< keep vertices on open boundaries in place
};

/// What a smoother did.
struct SmoothingReport {
    std::size_t vertices = 0;           ///< welded vertices smoothed over
    std::size_t faces = 0;              ///< faces in the half-edge mesh
    std::size_t faces_skipped = 0;      ///< faces OpenMesh could not add (non-manifold, degenerate)
    std::size_t boundary_vertices = 0;  ///< vertices on an open boundary
    int iterations = 0;                 ///< iterations run (Taubin: λ|μ pairs; bilateral: normal passes)
    double max_displacement = 0.0;      ///< largest distance any vertex moved, world units
    double seconds = 0.0;               ///< wall-clock time
    std::vector<std::string> warnings;  ///< e.g. "3 non-manifold faces left out of the neighbourhoods"
};

/// Plain Laplacian (umbrella) smoothing, p ← p + λ L(p), repeated `iterations` times.
/// It is the classic low-pass filter that *shrinks*: a sphere loses volume at every step (Taubin
/// 1995 uses it to motivate λ|μ). Modified in place; see the file comment for accepted input.
/// \throw InvalidInput for empty meshes, bad indices, non-finite positions or options out of range;
///        Cancelled through p.
/// Cost: O(iterations · E), TBB-parallel over vertices; 10 iterations on 70k faces take ~10 ms.
SmoothingReport laplacian_smooth(Mesh& m, const LaplacianOptions& opt = {}, Progress* p = nullptr);

/// Taubin's λ|μ smoothing (G. Taubin, "A signal processing approach to fair surface design",
/// SIGGRAPH 1995): a λ > 0 Laplacian step, then a μ < −λ step, repeated; a low-pass filter that
/// barely shrinks. Modified in place; see the file comment for accepted input.
/// \throw InvalidInput for empty meshes, bad indices, non-finite positions or λ, μ out of range;
///        Cancelled through p.
/// Cost: O(iterations · E), TBB-parallel over vertices.
SmoothingReport taubin_smooth(Mesh& m, const TaubinOptions& opt = {}, Progress* p = nullptr);

/// Bilateral normal filtering (Y. Zheng, H. Fu, O. K.-C. Au, C.-L. Tai, "Bilateral normal filtering
/// for mesh denoising", IEEE TVCG 17(10), 2011; local iterative scheme):
///   n_i ← normalize( Σ_j A_j W_s(‖c_i − c_j‖) W_r(‖n_i − n_j‖) n_j ),
/// over the faces j sharing a vertex with face i (i included), W(x) = exp(−x² / 2σ²), A_j the area
/// and c_j the centroid of face j; then the vertices are fitted to the filtered normals
/// (Sun et al. 2007): x_v ← x_v + 1/|F_v| Σ_{f∋v} n_f (n_f · (c_f − x_v)), `vertex_iterations` times.
/// Modified in place; see the file comment for accepted input.
/// \throw InvalidInput for empty meshes, bad indices, non-finite positions or options out of range;
///        Cancelled through p.
/// Cost: O(normal_iterations · Σ_i |N(i)| + vertex_iterations · F), TBB-parallel over faces/vertices.
SmoothingReport bilateral_normal_filter(Mesh& m, const BilateralNormalOptions& opt = {}, Progress* p = nullptr);

}  // namespace normalflow
