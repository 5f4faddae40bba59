#pragma once
/// \file fit_mesh.h
/// The user's own mesh onto a processed volume: the other way out of the engine besides
/// extract_surface. The mesh keeps its vertices, faces and their order (so whatever a caller keeps
/// per vertex or per face still applies); only the positions move: each vertex to its closest point
/// on the zero level set, then a vertex update that turns the faces to the volume's normals (the
/// paper's two steps once more, on the mesh: the normals are given, the positions follow them).

#include <cstddef>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"

namespace normalflow {

/// Options for fit_mesh_to_volume.
struct FitOptions {
    int projection_steps = 8;  ///< >= 0: Newton steps x ← x − φ∇φ/|∇φ|² onto the zero level set
    int relax_steps = 0;       ///< >= 0: tangential relaxation iterations after the projection (below)
    int vertex_steps = 10;     ///< >= 0: vertex-update iterations (below)
    /// Vertices on an open boundary (an edge of one face, positions welded) and those within
    /// boundary_rings edge rings of one move by a fraction of their update: 0 on the boundary,
    /// rising linearly to 1 at boundary_rings + 1 rings. The volume of an open surface is closed
    /// by a cap; its smoothing rounds the rim, and a rim projected onto it would be pulled toward
    /// the cap. >= 0.
    int boundary_rings = 2;
};

/// What fit_mesh_to_volume did.
struct FitReport {
    std::size_t vertices = 0;           ///< distinct positions (welded)
    std::size_t boundary_vertices = 0;  ///< on an open boundary
    std::size_t outside_band = 0;       ///< positions where φ is the background: left where they were
    double mean_distance = 0;           ///< world units: mean |φ| at the vertices after the fit
    double max_distance = 0;            ///< world units: the largest
    /// Degrees: the area-weighted mean angle between the fitted faces and the volume's normal at
    /// their centroids (orientation ignored). How well the kept triangles can show the volume's
    /// surface: small when the noise moved the vertices across the surface only, large when it
    /// also tangled them along it (heavy noise), which no projection undoes.
    double mean_face_angle_deg = 0;
};

/// Moves m's vertices onto the zero level set of v and fits its faces to v's normals:
/// 1. projection: projection_steps Newton steps on φ, each at most one voxel long;
/// 1b. tangential relaxation: relax_steps Jacobi iterations moving each vertex half way toward the
///    mean of its neighbours within its tangent plane (∇φ), then two Newton steps back onto the level
///    set: what the noise moved along the surface (tangled, folded triangles) is undone;
/// 2. vertex update (Sun, Rosin, Martin & Langbein 2007, as in bilateral normal filtering): with
///    n_f the normalised ∇φ at the centroid of face f after step 1 (held fixed), vertex_steps
///    Jacobi iterations of x_v ← x_v + (1/|F_v|) Σ_{f∋v} n_f (n_f·(c_f − x_v)). The sign of n_f
///    does not matter, so inconsistently oriented faces are fitted as well.
/// φ and ∇φ are trilinear interpolations of the samples and of their central differences.
/// With targets (the engine's last filtered normal map, smooth_volume), step 2 turns the faces to N
/// interpolated at their centroids instead of ∇φ (which the grid smears across a crease), falling
/// back to ∇φ where the map has no normal; the report's face angle is still measured against ∇φ.
/// Coincident positions (a seam of an OBJ, an unwelded STL) are one vertex: they move together and
/// stay coincident. Positions in no triangle stay where they are.
///
/// Accepted input: any triangle mesh (faces may be degenerate, non-manifold, of any orientation);
/// a volume whose invariants hold.
/// \throw InvalidInput for negative options, an index out of range or a non-finite position.
/// Cost: O(V·projection_steps + F·vertex_steps) lookups, TBB parallel over vertices; the result
/// does not depend on the thread count.
FitReport fit_mesh_to_volume(Mesh& m, const Volume& v, const FitOptions& options = {},
                             const NormalMap* targets = nullptr);

/// The volume's normal at each face's centroid: with targets (the engine's last filtered normal map) its
/// interpolated normal, else (or where the map has none) the normalised ∇φ; zero where the centroid is
/// outside the band or the gradient vanishes. The sign is the volume's (outward).
/// Cost: O(F) lookups, TBB parallel.
std::vector<Vec3d> volume_normals_at_faces(const Mesh& m, const Volume& v, const NormalMap* targets = nullptr);

/// Whether m has an edge of exactly one face once coincident positions are welded (an open
/// surface: a scan, a sheet, a mesh with holes).
bool has_open_boundary(const Mesh& m);

}  // namespace normalflow
