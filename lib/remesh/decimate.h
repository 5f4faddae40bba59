#pragma once
/// \file decimate.h
/// Decimation to a face count by quadric-error edge collapse (Garland & Heckbert 1997) that keeps a
/// manifold mesh manifold: every collapse passes the link condition (Dey, Edelsbrunner, Guha &
/// Nekhayev 1999), turns no face by more than max_normal_change_deg and makes no face degenerate or
/// worse-shaped below min_quality. Free of GPL code; deterministic; fandisk extracted at resolution 256
/// (1.1 M faces) to 20,000 faces in under 2 seconds on 2 cores (docs/history/benchmarks-2026.md,
/// "Decimation").

#include <cstddef>

#include "core/mesh.h"

namespace normalflow {

/// Options of decimate_mesh_qem.
struct QemOptions {
    /// Faces to keep at most, >= 4, or 0 for no face target (then max_error > 0 stops the decimation). The
    /// decimation stops short of it when no collapse is left that passes the checks (a closed component
    /// keeps at least a tetrahedron; locked borders stay).
    std::size_t target_faces = 0;
    /// A collapse that turns a face's normal by more than this (degrees, in (0, 180]) is refused: it
    /// would fold the surface onto itself.
    double max_normal_change_deg = 60.0;
    /// A collapse that leaves a face of shape quality 4√3·area / Σ edge² (1 for an equilateral triangle,
    /// 0 for a degenerate one) below this, and below what that face had, is refused; in [0, 1). Low:
    /// an extracted surface starts with many slivers, and decimating a flat patch passes through thin
    /// triangles (0.05 left an extracted cube at 77k of its 84k faces; 0.001 reaches 300).
    double min_quality = 0.001;
    /// > 0: no collapse whose quadric error, as a distance (QemReport::max_error's measure: the area-weighted
    /// RMS distance of the merged vertex to the planes it stands for), exceeds this (world units). Not a
    /// bound on the Hausdorff distance: pipeline/ decimate_mesh measures that.
    double max_error = 0.0;
    /// Hermite data: true to build each vertex's quadric from its own tangent plane, the plane through it
    /// normal to m.normals (weighted by a third of the area of its faces), instead of the planes of its
    /// faces. For an extracted surface whose vertices lie on the iso-surface and whose normals come from
    /// the field (set_volume_normals): collapses across a one-voxel crease bevel then cost nothing and put
    /// the merged vertex on the crease, where the face planes would keep the bevel as a narrow face.
    /// Vertices with a zero normal use their faces' planes. The merged vertex is then placed by a
    /// truncated solve (eigenvalues below 2% of the largest dropped, as dual contouring does), so nearly
    /// parallel planes do not slide it along a crease they do not make.
    bool tangent_planes = false;
    /// > 0 (degrees; m needs normals): a collapse that leaves a face turned from the surface's normal
    /// (m.normals) at one of its corners by more than this, and by more than that face was before, is refused. The
    /// bound on the shading error that max_error, a distance, does not give: on a bend of radius R a face of
    /// width w turns w / 2R from its corners' normals, so faces stay small where the surface bends and grow
    /// where it is flat. 0: no bound.
    double max_normal_deviation_deg = 0.0;
};

/// What decimate_mesh_qem did.
struct QemReport {
    std::size_t faces_before = 0;
    std::size_t faces_after = 0;
    std::size_t vertices_before = 0;
    std::size_t vertices_after = 0;
    std::size_t collapses = 0;
    /// The largest quadric error of a collapse made, as a distance (world units): √(Q(x) / Σ area), an
    /// area-weighted RMS distance of the new vertex to the planes of the faces it stands for.
    double max_error = 0.0;
    bool reached_target = false;  ///< faces_after <= target_faces
    /// Edges flipped afterwards to open folds the collapses left between faces (unfold_by_flips).
    std::size_t folds_flipped = 0;
    double seconds = 0.0;
};

/// Decimates m in place to at most opt.target_faces faces by edge collapses in the order of least
/// quadric error, each placing the merged vertex where the summed quadric of its faces' planes is least
/// (the endpoint or midpoint with the least error where that system is ill-conditioned, so creases
/// and corners stay put). Vertices on open borders and on non-manifold edges never move or go: an open
/// scan keeps its outline. Each collapse keeps the mesh manifold where it was (link condition, and no
/// vertex left with fewer than three neighbours) and is refused where it would fold a face or make it
/// degenerate (QemOptions). Self-intersections between parts that are not neighbours are not checked:
/// callers that need them absent check the result (pipeline/ decimate_mesh does).
/// Attributes: the surviving vertices keep theirs (a merged vertex keeps the attributes of the endpoint
/// it replaces), in their original order; unreferenced vertices are dropped. Vertex indices are taken as
/// the connectivity: weld coincident positions first where they should be joined.
/// \throw InvalidInput if m breaks the Mesh invariant (check_mesh), has no triangles, the options are
///        out of range, or tangent_planes is set and m has no normals.
/// Method: passes. Each costs the edges whose ends moved since the last pass (TBB parallel, into a slot
/// per face corner), takes the cheapest quarter of the edges in order of cost, picks greedily those whose
/// ends are not at or next to the ends of an edge picked before (so no two collapses share a face or
/// read what another writes), and makes those collapses in parallel. An edge the checks refuse waits
/// until its neighbourhood changes. Cost: O(F log F) time per pass, a few dozen passes; about 350 bytes
/// per vertex at most. The result does not depend on the thread count.
QemReport decimate_mesh_qem(Mesh& m, const QemOptions& opt);

/// Opens folds: where two faces on a manifold edge meet at an inner angle under min_inner_deg (their normals nearly
/// opposite: the surface doubles back, and tetrahedra there are slivers), the edge is flipped to the other diagonal
/// of the two faces if that makes the sharpest angle at the five edges involved less sharp and the new edge is not
/// one already. Sequential passes over the faces in order (deterministic), at most 8. Vertices and attributes are
/// untouched; a consistently oriented mesh stays so. Returns the number of flips. decimate_mesh_qem runs it with
/// 30°: a collapse checks the folds around its own vertex only, not at the edges of its ring, which its neighbours'
/// collapses in the same pass may change.
std::size_t unfold_by_flips(Mesh& m, double min_inner_deg);

}  // namespace normalflow
