#pragma once
/// \file face_filter.h
/// A face-normal filter on the user's own mesh, guided by the volume: the last step of a kept result.
/// The volume's filtered normals are smooth, consistent and free of the mesh's tangles, but the grid
/// rounds every crease over about a voxel; the mesh's own faces can show a crease as sharp as the
/// input's tessellation allows. This filter takes the best of both (after Zhang et al. 2015, "Guided
/// mesh normal filtering", and Sun et al. 2007's vertex update): each face's normal is filtered over
/// its neighbours with a joint bilateral weight on a guidance normal, and the vertices follow.

#include <cstddef>
#include <vector>

#include "core/mesh.h"

namespace normalflow {

/// How the patch guidance measures a patch's consistency (FaceFilterOptions::saliency).
enum class PatchSaliency {
    Off,     ///< its spread alone
    On,      ///< its spread times its relative saliency (Zhang et al. 2015)
    Chosen,  ///< with stop_noise, both run and the one of the lower risk estimate is kept; otherwise Off
};

/// "off", "on", "chosen".
const char* to_string(PatchSaliency s);

/// The filter's weight on the guidance (FaceFilterOptions::range).
enum class RangeWeight {
    Guided,  ///< the joint bilateral weight on the guidance normals: a crease stays sharp
    None,    ///< none: a mean over the neighbourhood weighted by area and distance alone, a linear low-pass
    Chosen,  ///< with stop_noise, both run and the one of the lower risk estimate is kept; otherwise Guided
};

/// "guided", "none", "chosen".
const char* to_string(RangeWeight r);

/// Options for filter_faces.
struct FaceFilterOptions {
    int normal_steps = 1;   ///< >= 0: rounds of guidance, joint bilateral filter and vertex update; 0: none
    int vertex_steps = 10;  ///< >= 0: vertex-update iterations per round
    /// Range scale of the joint bilateral weight exp(−|g_f − g_k|² / 2σ_r²) on the guidance normals
    /// (a chord length, 2 sin(θ/2) for an angle θ between them; 0.35 as the engine's sigma_range). > 0.
    double sigma_r = 0.35;
    /// Spatial scale of the weight exp(−|c_f − c_k|² / 2σ_s²), a multiple of the mean distance between
    /// the centroids of faces that share a vertex. > 0.
    double sigma_s = 1.0;
    /// Neighbourhood of the filter, in rings of faces (the faces sharing a vertex with the face, then
    /// with those, ...). >= 1.
    int rings = 1;
    /// The guidance of a face is the area-weighted mean of the base normals (the given guidance, else
    /// the current normals) over a patch: the face's vertex ring, or, where a neighbour's vertex ring is
    /// clearly more consistent (Zhang et al.'s patch consistency: the largest distance of a normal from
    /// the patch's mean), that one. A patch that straddles a crease is not consistent, one on a side of
    /// it is: the guidance stays sharp at a crease and is the local mean elsewhere. When false, the
    /// guidance is the base normal itself.
    bool patch_guidance = true;
    /// "Clearly": a neighbour's patch replaces the face's own when its spread is below this fraction of
    /// the own patch's. On a curved surface every patch is about as consistent, and a neighbour's
    /// normal is tilted by the curvature: 1 is Zhang et al.'s choice of the most consistent patch,
    /// smaller keeps the own patch unless a crease runs through it. In (0, 1].
    double own_patch_bias = 0.35;
    /// The patch's spread times its relative saliency (Zhang et al.'s consistency): the largest normal difference
    /// across an edge inside the patch over the sum of them all. Noise spreads its differences over every edge and a
    /// crease puts them on a few, so a patch that straddles a crease counts as less consistent still and the
    /// guidance keeps to one side of a crease through heavier noise; on a curved surface it moves the guidance to a
    /// neighbour's patch, tilted by the curvature, more often. Chosen runs the rounds both ways and keeps the one of
    /// lower estimated error (the risk stop's, so only with stop_noise; otherwise Off), at twice the cost. Off by
    /// default: in the study's pipeline On gains the CAD parts (twelve_imp0.5 0.85° face by face, fandisk_n0.3
    /// 0.25°) and costs the smooth ones (sharpsphere 0.23°), and Chosen, whose estimate picks On on sharpsphere and
    /// igea too, keeps both trades (docs/history/benchmarks-2026.md, "The patch's saliency").
    PatchSaliency saliency = PatchSaliency::Off;
    /// The weight on the guidance, or none. A weight on the guidance keeps a crease and lets the filter tell it from
    /// noise; where the surface has no crease but relief as fine as the noise (a statue's), it snaps that relief
    /// into facets, and a mean without it keeps the relief as a low-pass filter does. Chosen runs the rounds both
    /// ways and keeps the one of lower estimated error (the risk stop's, so only with stop_noise; otherwise Guided),
    /// at about twice the filter's cost: in the study it takes the mean on julius_n0.2, fertility_n3 and vaselion_n3
    /// (sampled 4.76° → 4.71°, 4.19° → 4.19°, 10.99° → 10.58°, where Taubin's best reaches 10.66°) and the weight on
    /// every part (docs/history/benchmarks-2026.md, "The face filter's weight on the guidance, or none").
    RangeWeight range = RangeWeight::Chosen;
    /// World units, >= 0. > 0: the rounds stop once the vertices' root-mean-square distance from where
    /// they started reaches this length (normal_steps is then the most rounds). Given the input's noise
    /// (estimate_noise), this is Morozov's discrepancy principle: remove as much as the noise, no more.
    /// A filter run past it smooths away the surface's own detail; one stopped short leaves noise.
    double stop_displacement = 0;
    /// World units, >= 0 (not with stop_displacement). > 0: the deviation of the input's noise along its
    /// normals (estimate_noise with NoiseNormals::Steady), and the rounds stop where the vertices' error is
    /// least by Stein's unbiased risk estimate (SURE; Ramani, Blu and Unser 2008's Monte-Carlo divergence):
    /// after each round, the vertices' squared moves along their steady normals (steady_vertex_normals) less
    /// the noise's, plus twice its variance times the rounds' divergence, read from kRiskProbes copies of the
    /// input moved by kRiskProbe σ along the normals with random signs that run the same rounds. The filter
    /// runs until the estimate found no new least for kRiskPatience rounds (at most normal_steps) and returns
    /// the mesh of the least, no round at all included, blended with the round before or after it where the
    /// estimate of the blend (quadratic in its share) is lower still (FaceFilterReport::blend). Where the
    /// discrepancy principle stops every surface once it moved as far as the noise, this one runs a part's flat
    /// sides on while their error still falls and stops a statue where its detail starts to go. It costs
    /// 1 + kRiskProbes times the rounds.
    double stop_noise = 0;
};

/// The risk stop's probe, a fraction of the noise: small enough that the rounds respond to it as to a
/// small change, large enough to stand above rounding.
inline constexpr double kRiskProbe = 0.1;
/// Perturbed copies the risk stop averages its divergence over: its variance falls as their number, its cost
/// grows with it. With 1 the round chosen on trimstar_n3 ranged over 5 to 9 with the seed, with 4 over 6 to 8,
/// with 8 over 6 to 7 (the least true error at 6); the study and the speed tables of 2026-12-06 ran with 4.
inline constexpr int kRiskProbes = 4;
/// Rounds the risk stop runs past its least estimate before it stops.
inline constexpr int kRiskPatience = 3;

/// What filter_faces did.
struct FaceFilterReport {
    std::size_t faces = 0;           ///< faces filtered (non-degenerate)
    std::size_t reverted_moves = 0;  ///< vertex moves undone because a face would have turned over
    int rounds = 0;                  ///< rounds whose result was kept
    int rounds_run = 0;              ///< rounds run (the risk stop runs kRiskPatience past the one it keeps)
    /// with stop_noise: the blend kept between the least round and the one after it (> 0) or before it (< 0), the
    /// other round's share; 0: the least round itself
    double blend = 0;
    bool salient = false;         ///< the patches' consistency included their saliency (PatchSaliency)
    bool guided = true;           ///< the filter weighed the guidance (RangeWeight::Guided), or not (None)
    double estimated_error = 0;   ///< with stop_noise: the risk estimate's RMS error of the kept vertices, world units
    double rms_displacement = 0;  ///< world units: the vertices' root-mean-square distance from where they began
};

/// Filters m's face normals and moves its vertices to follow them; the vertices, faces and their order
/// stay. Each round: the guidance (above) of every face, the joint bilateral filter of the faces'
/// current normals over their neighbourhood weighted by area, distance and the guidance's agreement,
/// then vertex_steps iterations of Sun et al.'s vertex update toward the filtered normals.
/// guidance (optional, one unit normal per face, zero where unknown) is where each face should point:
/// the volume's normal at its centroid (volume_normals_at_faces), smooth and consistent but rounded
/// over a voxel at a crease, which the patch guidance sharpens. held (optional, one flag per position)
/// marks positions that do not move; vertices on an open boundary never move. filtered_normals (optional)
/// receives the filtered normals of the round whose mesh is kept, one per face (a measurement: how good the target
/// was; with the risk stop the least round's, the input's own normals where no round is kept; a blended mesh lies
/// between that round and the one beside it).
/// No face turns over: a vertex move that would turn a face to more than 90° from its filtered normal
/// is undone. With options.stop_displacement, the rounds stop once the vertices have moved that far; with
/// options.stop_noise, where the estimated error is least.
/// \throw InvalidInput for options out of range or sizes that do not match.
/// Cost: O(F · k · normal_steps + F · vertex_steps · normal_steps) for k faces in a neighbourhood;
/// TBB-parallel, the result does not depend on the thread count.
FaceFilterReport filter_faces(Mesh& m, const FaceFilterOptions& options = {},
                              const std::vector<Vec3d>* guidance = nullptr, const std::vector<char>* held = nullptr,
                              std::vector<Vec3d>* filtered_normals = nullptr);

}  // namespace normalflow
