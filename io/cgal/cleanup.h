#pragma once
/// \file cleanup.h
/// Cleanup of extracted surfaces for output: sliver and needle removal, small-component removal,
/// outward orientation, and decimation (edge collapse to a face count or to an error bound) or
/// isotropic remeshing, with CGAL 5.5 (GPL-3.0-or-later). All CGAL code is in cleanup.cpp.

#include <cstddef>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "metrics/surface_distance.h"

namespace normalflow::cgal {

/// How cleanup reduces or regularises the triangles (at most one of these).
enum class CleanupReduction {
    None,        ///< keep the triangles (only the repairs below)
    FaceCount,   ///< edge collapse until at most target_faces faces remain
    ErrorBound,  ///< edge collapse while the result stays within max_error of the input surface
    Remesh,      ///< isotropic remeshing to target_edge_length
};

/// Options of cleanup_mesh. Every step keeps a closed manifold closed and manifold.
struct CleanupOptions {
    /// Remove faces with zero area and collapse needles/caps (CGAL's remove_almost_degenerate_faces;
    /// with ErrorBound only zero-area faces, since collapsing needles on creases moves the surface).
    bool remove_degenerate = true;
    /// A face is a needle when its longest / shortest edge exceeds this; > 1 (CGAL's default 4).
    double needle_threshold = 4.0;
    /// A face is a cap when its largest angle's cosine is below this (-0.99 ~ 172 degrees); in (-1, 0).
    double cap_threshold = -0.99;
    /// Drop connected components (edge-connected) with fewer than this fraction of all faces;
    /// in [0, 1). 0 keeps everything.
    double min_component_fraction = 0.0;
    /// Orient each closed component outward (positive enclosed volume).
    bool orient_outward = true;
    CleanupReduction reduction = CleanupReduction::None;
    /// FaceCount: faces to keep at most, >= 4 (a closed mesh keeps at least a tetrahedron per component).
    std::size_t target_faces = 0;
    /// ErrorBound: largest distance, world units, of the result from the input surface (> 0).
    /// Enforced per collapse: the new point and 16 barycentric points of every new face (the 7 that
    /// sampled_hausdorff measures, and a step-1/4 grid) must lie within max_error of the input (exact
    /// closest-triangle distance). So result -> input is below max_error at those points, and between
    /// them up to the sampling (a conservative polyhedral envelope, CGAL's Polyhedral_envelope_filter,
    /// did not finish in 10 min on 287k faces; this takes 15 s there).
    double max_error = 0.0;
    /// Remesh: target edge length, world units (> 0).
    double target_edge_length = 0.0;
    /// Remesh: iterations of split/collapse/flip/relax, >= 1.
    int remesh_iterations = 3;
    /// Repair pairs of self-intersecting faces left by the steps above (or present in the input):
    /// CGAL's experimental::remove_self_intersections (local removal, hole filling and smoothing),
    /// kept only if the result stays as closed and manifold as before, has fewer pairs and (ErrorBound)
    /// stays within max_error of the input.
    bool repair_self_intersections = true;
    /// Samples per face (besides the vertices) used to measure the moved distance; >= 0.
    int distance_samples_per_face = 3;
};

/// What cleanup_mesh did and what the result is.
struct CleanupReport {
    std::size_t faces_before = 0;
    std::size_t faces_after = 0;
    std::size_t vertices_before = 0;
    std::size_t vertices_after = 0;
    std::size_t degenerate_removed = 0;  ///< faces removed by the degenerate/needle step
    std::size_t components_removed = 0;  ///< small components dropped
    std::size_t faces_in_removed_components = 0;
    std::size_t components_reversed = 0;  ///< closed components turned outward
    /// Symmetric sampled Hausdorff distance, world units, between input and result (vertices plus
    /// distance_samples_per_face points per face, each side against the other's triangles), and the
    /// one-sided parts: result -> input and input -> result. Removed components count in
    /// input_to_result (their surface is gone), so they are excluded from it: it measures the kept part.
    double hausdorff = 0.0;
    double result_to_input = 0.0;
    double input_to_result = 0.0;
    bool closed = false;                       ///< result has no boundary edge
    bool manifold = false;                     ///< result has no non-manifold edge or vertex
    std::size_t self_intersections = 0;        ///< pairs of intersecting faces in the result
    std::size_t self_intersections_found = 0;  ///< pairs before the self-intersection repair (0 if off)
    double seconds = 0.0;
    /// Problems of the result, e.g. "result is not closed (12 boundary edges)".
    std::vector<std::string> warnings;
};

/// Cleans m for output (modified in place): removes degenerate and needle faces, drops small
/// components, orients closed components outward, then reduces it (see CleanupReduction).
/// Method: CGAL Polygon_mesh_processing (remove_degenerate_faces, experimental::
/// remove_almost_degenerate_faces, connected_components, reverse_face_orientations), Surface_mesh_
/// simplification::edge_collapse (Lindstrom-Turk cost and placement; Count_stop_predicate for
/// FaceCount; a sampled distance filter for ErrorBound), PMP::isotropic_remeshing (Botsch & Kobbelt
/// 2004) for Remesh, then PMP::experimental::remove_self_intersections where faces intersect. The
/// result is checked (closed, manifold, self-intersections) and problems are reported in warnings,
/// never thrown.
/// Accepted input: any triangle mesh; exact duplicate points are merged first. Non-manifold input is
/// made manifold by duplicating vertices (CGAL's soup-to-mesh conversion) and reported.
/// \throw InvalidInput if a face index is out of range, a position is not finite, options are out of
///        range, or no face would remain.
/// Cost: O(F log F); about 9 s for 287k faces to 10k (FaceCount), 15 s for ErrorBound (fandisk at 128,
/// max_error 0.002 = 0.05 voxel), plus the repair where faces intersect. Single-threaded;
/// the result does not depend on the thread count.
CleanupReport cleanup_mesh(Mesh& m, const CleanupOptions& opt = {});

/// The sampled Hausdorff distance (lib/metrics/surface_distance.h), also under this namespace.
using normalflow::sampled_hausdorff;
using normalflow::sampled_max_distance;
using normalflow::SampledDistance;

}  // namespace normalflow::cgal
