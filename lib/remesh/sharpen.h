#pragma once
/// \file sharpen.h
/// Sharp creases and corners on an extracted mesh: its vertices moved onto the features of the surface it
/// approximates, keeping every face and its connectivity (so a closed manifold mesh stays closed and manifold).
///
/// Marching tetrahedra puts every vertex on a grid edge, so a crease becomes a bevel about a voxel wide and a
/// corner a small facet. Dual/primal optimisation (Ohtake & Belyaev, "Dual/primal mesh optimization for
/// polygonized implicit surfaces with sharp features", 2002) moves them back: each face's centroid is taken to
/// the surface (the dual point) with the surface's normal there, and each vertex then goes to the point nearest
/// to it that best fits the tangent planes of its faces' dual points (a quadric, solved with small eigenvalues
/// truncated, as dual contouring does): one plane moves a vertex across it only; two meet in the crease line, three
/// in the corner. A move that would turn or flatten one of the vertex's faces is not made.
#include <cstddef>
#include <functional>

#include "core/mesh.h"
#include "core/progress.h"
#include "core/vec.h"
#include "core/volume.h"
#include "sdf/closest_triangle.h"

namespace normalflow {

/// The surface the mesh approximates: for a point p, the nearest point q on it and the unit normal n there (either
/// orientation). False where it has none (p is then left out).
using SurfaceProbe = std::function<bool(const Vec3d& p, Vec3d& q, Vec3d& n)>;

/// The surface of a mesh: its closest point (q must outlive the probe) and that triangle's normal. For sharpening an
/// extraction of a mesh's own volume (a re-meshing), whose creases the mesh has exactly.
SurfaceProbe mesh_probe(const Mesh& reference, const ClosestTriangleQuery& q);

/// The zero level set of a volume: p taken there by Newton steps on the trilinear φ, the normal there the normal
/// map's (trilinear; the engine's last filtered normal map, sharp where the filter kept creases) or, without one,
/// ∇φ's (rounded at creases within a voxel or two, as the distance field is). v and map must outlive the probe.
SurfaceProbe volume_probe(const Volume& v, const NormalMap* map = nullptr);

struct SharpenOptions {
    int iterations = 3;  ///< dual/primal passes, >= 1
    /// World units, > 0: no vertex moves farther than this from where it started (a voxel or two: the bevel is that
    /// wide, and a vertex beyond it belongs to another feature).
    double max_move = 0;
    /// Eigenvalues of a vertex's quadric below this fraction of its largest are taken as zero: planes nearly
    /// parallel (a smooth bend) do not make a crease.
    double truncation = 0.05;
    int threads = 0;  ///< worker threads of the dual step (0: all); the result does not depend on it
};

struct SharpenReport {
    std::size_t vertices = 0;  ///< vertices of the mesh
    std::size_t moved = 0;     ///< vertices moved in the last pass
    std::size_t refused = 0;   ///< moves not made in the last pass (a face would turn or flatten)
    double mean_move = 0;      ///< world units: mean distance of the vertices from where they started
    double max_move = 0;       ///< world units: the largest
    double seconds = 0;
};

/// Moves m's vertices onto the features of the surface that probe describes (see the file comment); faces,
/// connectivity and attributes other than the normals are kept, and normals are dropped (they no longer hold).
/// \throw InvalidInput for bad options or an invalid mesh.
SharpenReport sharpen_mesh(Mesh& m, const SurfaceProbe& probe, const SharpenOptions& options,
                           Progress* progress = nullptr);

}  // namespace normalflow
