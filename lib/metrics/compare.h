#pragma once
/// \file compare.h
/// Comparing a candidate mesh (a smoothing result) with a reference (the ground truth or the input)
/// without vertex correspondence: level-set output has new connectivity, so every measure here
/// works on the surfaces, not on vertex pairs. The one exception, correspondence_errors, is for a
/// candidate that kept the reference's connectivity (a mesh-side filter, the pipeline's
/// Connectivity::Keep, against the ground truth of the same noisy pair): face i against face i,
/// vertex i against vertex i, as mesh-denoising papers report their results.
///
/// Self-intersections need exact predicates (CGAL) and are not measured here: the CLI adds them
/// with io/cgal/repair.h count_self_intersections.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "metrics/surface_distance.h"

namespace normalflow {

/// Options of crease_preservation.
struct CreaseOptions {
    /// A reference edge is a feature edge when the angle between the normals of its two faces exceeds
    /// this, degrees, in (0, 180). The same threshold decides whether the candidate is still sharp.
    double angle_deg = 30.0;
    /// Radius of the neighbourhood searched on the candidate around each sample of a feature edge,
    /// as a fraction of the reference's bounding-box diagonal, > 0. It should exceed the candidate's
    /// edge length (so the two sides are averaged over several faces) and stay below the feature size.
    double radius_relative = 0.01;
};

/// How much of the reference's feature-edge length is still sharp on the candidate.
///
/// Protocol:
///  1. Reference feature edges: after exact welding, edges with exactly two non-degenerate faces
///     whose unit normals n1, n2 make an angle above angle_deg.
///  2. Each feature edge is cut into ceil(length / r) equal pieces (r = radius_relative × reference
///     bbox diagonal); the midpoint p of each piece is a sample carrying the piece's length.
///  3. The candidate faces with a point within distance r of p are split into two sides: the faces
///     whose unit normal is closer (larger dot product) to n1, and those closer to n2; faces facing
///     away from both (both dot products <= 0) are ignored. Each side's area-weighted mean normal is
///     formed (areas of the whole faces).
///  4. The sample is preserved when both sides are non-empty and the angle between the two mean
///     normals exceeds angle_deg. A sharp candidate gives the reference's dihedral angle; a rounded
///     one (fillet radius well above r) gives nearly parallel means; zero-mean noise averages out.
///  fraction = preserved length / feature length (1 when the reference has no feature edges).
struct CreasePreservation {
    double angle_deg = 30.0;        ///< threshold used
    double radius = 0.0;            ///< r, world units
    std::size_t feature_edges = 0;  ///< reference edges above the threshold
    std::size_t samples = 0;        ///< samples along them
    double feature_length = 0.0;    ///< total length of the reference's feature edges, world units
    double preserved_length = 0.0;  ///< length of the preserved samples, world units
    double fraction = 1.0;          ///< preserved_length / feature_length, in [0, 1]
    double mean_angle_deg = 0.0;    ///< length-weighted mean candidate side-to-side angle at the samples
};

/// Crease preservation of candidate with respect to reference (see CreasePreservation for the protocol).
/// Accepts any triangle soups (open, non-manifold, several components).
/// \throw InvalidInput if either mesh has no triangles, bad indices or non-finite positions, or the
///        options are out of range.
/// Cost: O(F log F) to weld and bin the candidate in a uniform grid of cell r, then O(k) per sample for
/// the k faces near it; TBB-parallel over samples, deterministic.
CreasePreservation crease_preservation(const Mesh& candidate, const Mesh& reference, const CreaseOptions& opt = {});

/// Errors of a candidate against a reference with the same vertices and triangles in the same order
/// (see correspondence_errors).
struct CorrespondenceErrors {
    std::size_t faces = 0;                       ///< triangles compared (non-degenerate in both meshes)
    std::size_t degenerate_faces = 0;            ///< triangles skipped: zero area (or a repeated index) in either mesh
    double mean_face_angle_deg = 0.0;            ///< unweighted mean over the compared faces, degrees; 0 if none
    double max_face_angle_deg = 0.0;             ///< largest face angle, degrees
    std::size_t vertices = 0;                    ///< vertices compared: every position, referenced or not
    double mean_vertex_distance = 0.0;           ///< mean over vertices of |p_i − q_i|, world units
    double max_vertex_distance = 0.0;            ///< largest |p_i − q_i|, world units
    double reference_diagonal = 0.0;             ///< bounding-box diagonal of the reference, world units
    double mean_vertex_distance_relative = 0.0;  ///< mean_vertex_distance / reference_diagonal (0 if the diagonal is)
    double max_vertex_distance_relative = 0.0;   ///< max_vertex_distance / reference_diagonal
};

/// Why candidate and reference do not correspond vertex for vertex and face for face, as the end of
/// an error message ("candidate has 1200 triangles, reference 1180", "candidate has 610 vertices,
/// reference 600", "triangle 17 differs: candidate (3, 4, 9), reference (3, 9, 4)"); an empty string
/// when they do: the same number of positions and the same triangle index lists in the same order.
/// Checks counts and indices only (not their range, not the positions). Cost: one pass over the triangles.
std::string correspondence_mismatch(const Mesh& candidate, const Mesh& reference);

/// Face-by-face and vertex-by-vertex errors of candidate against reference, which must share their
/// connectivity (correspondence_mismatch is empty), the measures of the mesh-denoising literature:
///  - face angle: the angle between the unit normals of triangle i in candidate and in reference
///    (atan2(|n × m|, n · m), accurate at small angles), averaged over triangles without area weights.
///    A triangle with zero area (or a repeated index) in either mesh has no normal: it is skipped and
///    counted in degenerate_faces;
///  - vertex distance: |p_i − q_i| over every position i, mean and max, in world units and relative to
///    the reference's bounding-box diagonal.
/// \throw InvalidInput "correspondence_errors: candidate has 1200 triangles, reference 1180" (any
///        correspondence_mismatch), or when a mesh has no triangles, bad indices or non-finite positions.
/// Cost: one pass over the triangles and one over the positions; single-threaded, deterministic.
CorrespondenceErrors correspondence_errors(const Mesh& candidate, const Mesh& reference);

/// Options of compare_meshes.
struct CompareOptions {
    SurfaceSamplingOptions sampling;  ///< how surface_distance samples the two surfaces
    CreaseOptions crease;             ///< crease preservation protocol
    /// Also measure correspondence_errors (MeshComparison::correspondence); the candidate must then have
    /// the reference's vertex count and triangles, else compare_meshes throws InvalidInput.
    bool correspondence = false;
};

/// Everything compare_meshes measures. Relative changes are (candidate − reference) / |reference|.
struct MeshComparison {
    SurfaceDistance distance;         ///< candidate (a) vs reference (b), world units
    double reference_diagonal = 0.0;  ///< bounding-box diagonal of the reference, world units
    double hausdorff_relative = 0.0;  ///< distance.hausdorff / reference_diagonal
    double mean_relative = 0.0;       ///< distance.mean / reference_diagonal
    double rms_relative = 0.0;        ///< distance.rms / reference_diagonal

    double area_reference = 0.0, area_candidate = 0.0;      ///< squared world units
    double area_change = 0.0;                               ///< relative, e.g. −0.02 = 2 % smaller
    double volume_reference = 0.0, volume_candidate = 0.0;  ///< signed enclosed volume, cubed world units
    double volume_change = 0.0;                             ///< relative; meaningful for closed meshes

    std::size_t vertices_candidate = 0, faces_candidate = 0;
    std::size_t components_reference = 0, components_candidate = 0;
    bool closed_reference = false, closed_candidate = false;      ///< no boundary edges
    bool manifold_reference = false, manifold_candidate = false;  ///< no non-manifold edges or vertices

    CreasePreservation crease;                           ///< see crease_preservation
    std::optional<CorrespondenceErrors> correspondence;  ///< with CompareOptions::correspondence
    std::vector<std::string> warnings;                   ///< e.g. "candidate is open: volume change is only indicative"
};

/// Compares candidate with reference: surface distances (metrics/surface_distance.h, absolute and
/// relative to the reference's bbox diagonal), area and volume change, components, closed/manifold
/// (core/mesh_report.h) and crease preservation; with opt.correspondence also correspondence_errors.
/// \throw InvalidInput if either mesh has no triangles, bad indices or non-finite positions, or, with
///        opt.correspondence, if the two do not share their connectivity.
/// Cost: that of surface_distance plus crease_preservation plus two mesh_report calls.
MeshComparison compare_meshes(const Mesh& candidate, const Mesh& reference, const CompareOptions& opt = {});

}  // namespace normalflow
