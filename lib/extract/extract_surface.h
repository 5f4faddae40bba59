#pragma once
/// \file extract_surface.h
/// Extraction: the iso-surface of a sparse signed distance Volume as a closed manifold triangle mesh.

#include <cstddef>

#include "core/mesh.h"
#include "core/volume.h"

namespace normalflow {

/// Options for extract_surface.
struct ExtractOptions {
    double iso = 0;  ///< iso value, world units; |iso| < v.background
};

/// What extract_surface produced.
struct ExtractReport {
    std::size_t vertices = 0;  ///< welded vertices
    std::size_t triangles = 0;
    bool closed = true;    ///< no boundary edges (true by construction, see extract_surface)
    bool manifold = true;  ///< every edge in two triangles, every vertex a disk (by construction)
};

/// The iso-surface {phi = iso} of v as a welded triangle mesh in world coordinates, oriented
/// outward (counter-clockwise seen from the positive side).
///
/// Method: marching tetrahedra (Doi & Koide 1991) on the Kuhn (Freudenthal) subdivision of every
/// grid cube into 6 tetrahedra around its main diagonal; all cubes are split the same way, so the
/// faces of neighbouring tetrahedra match. phi is piecewise linear on the tetrahedra, and a sample
/// equal to iso counts as above it (symbolic perturbation), so the level set is a closed
/// 2-manifold without self-intersections: unlike classic marching cubes (Lorensen & Cline 1987)
/// there are no ambiguous cases. Each vertex lies on a grid edge (an axis edge, a face diagonal or
/// the cube diagonal), keyed by that edge, so vertices are welded exactly; its position is the
/// linear interpolation clamped to [0.001, 0.999] along the edge, which keeps every triangle inside
/// its tetrahedron (so the surface stays embedded) and keeps vertices distinct. Samples outside
/// the grid count as +background, so the surface is closed even where it reaches the border.
/// Sliver triangles are kept (none has zero area up to rounding of float positions).
///
/// Accepted input: any Volume whose invariant holds (every sample with |phi| < half_width · h lies
/// in an allocated block). Cubes with a corner in an allocated block are visited, and so are the cubes
/// of inside tiles that touch an outside tile or the grid's border: the surface also passes there when
/// a volume's inside reaches the border or an inside tile meets an outside one (the closed volume of
/// an open mesh), and it stays closed.
/// An empty volume gives an empty mesh. Genus and components are whatever the level set has.
///
/// \throw InvalidInput if iso is not finite or |iso| >= v.background, or v breaks its invariants
///        (Volume::check); NumericalError if v holds a NaN/Inf sample.
/// Cost: O(allocated blocks) time and memory; TBB parallel_for over blocks, output identical for any
/// thread count (vertices ordered by grid-edge key, triangles in block order).
Mesh extract_surface(const Volume& v, const ExtractOptions& opt = {}, ExtractReport* report = nullptr);

}  // namespace normalflow
