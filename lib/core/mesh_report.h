#pragma once
/// \file mesh_report.h
/// What a mesh has: size, topology and defects of a polygon soup, measured after exact welding.
///
/// The definitions below reproduce the defect counts in shared/data/SOURCES.md (and hence the
/// official Thingi10K `geometry_data.csv`) for every mesh there: V/F, components, duplicate faces,
/// boundary / non-manifold / inconsistently oriented edges, degenerate faces, non-manifold vertices
/// and the Euler characteristic of the closed models (tests/core/test_mesh_report.cpp checks them).
/// Self-intersections need exact predicates and live in io/cgal/repair.h.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace normalflow {

/// Topology and defects of a triangle soup. Every count is taken after *exact welding*: positions
/// with identical float coordinates (+0 and -0 count as equal) are one vertex. "Welded face" = the
/// face with its corners replaced by welded vertex ids.
struct MeshReport {
    std::size_t input_vertices = 0;       ///< m.positions.size()
    std::size_t vertices = 0;             ///< unique positions after exact welding (referenced or not)
    std::size_t referenced_vertices = 0;  ///< welded vertices used by at least one face
    std::size_t faces = 0;                ///< m.triangles.size() (every face, degenerate ones included)
    std::size_t edges = 0;                ///< distinct undirected welded edges {a,b}, a != b, of all faces

    /// Connected components: faces are connected when they share a welded *vertex* (so two cubes
    /// touching at one corner are 1 component). Unreferenced vertices are not components.
    /// (Edge-connectivity would give 19 instead of SOURCES.md's 4 on simplify_brain.obj.)
    std::size_t components = 0;

    /// Edges used by exactly one face (summed over all faces, degenerate and duplicate ones included).
    std::size_t boundary_edges = 0;
    /// Boundary loops: sets of boundary edges connected through their vertices (a hole is one loop;
    /// two holes meeting at one vertex count as one).
    std::size_t boundary_loops = 0;
    /// Edges used by more than two faces (a duplicated face makes its three edges non-manifold;
    /// a face (a,b,a) uses edge {a,b} twice).
    std::size_t non_manifold_edges = 0;
    /// Welded vertices whose incident non-degenerate faces form more than one fan, where two faces
    /// around v are in the same fan when they share an edge incident to v (any number of faces on that
    /// edge). Example: two cubes sharing one corner, or a bow-tie.
    std::size_t non_manifold_vertices = 0;
    /// Faces whose welded corners repeat (combinatorially degenerate) or whose three positions are
    /// exactly collinear (zero area, exact test).
    std::size_t degenerate_faces = 0;
    /// Of these, the faces with a repeated welded vertex (e.g. made degenerate by welding).
    std::size_t collapsed_faces = 0;
    /// Non-collapsed faces with the same welded vertex set as an earlier face, in any order or
    /// orientation: the extra copies (a face present 3 times counts 2).
    std::size_t duplicate_faces = 0;
    /// Edges used by exactly two faces that traverse it in the same direction (a flipped face
    /// inside a mesh gives 3).
    std::size_t inconsistent_edges = 0;

    bool closed = false;    ///< faces > 0 and boundary_edges == 0
    bool manifold = false;  ///< no non-manifold edges and no non-manifold vertices
    bool oriented = false;  ///< inconsistent_edges == 0 (edges with > 2 faces are not judged)

    /// V - E + F with V = referenced_vertices, E = edges, F = faces (2 - 2g per closed component
    /// for a clean manifold; 2 - 2g - b for an orientable surface with b boundary loops).
    long euler_characteristic = 0;
    /// Total area of all faces, in squared world units.
    double area = 0.0;
    /// Signed enclosed volume by the divergence theorem, sum of det(a-o, b-o, c-o)/6 over faces with
    /// o = the bounding-box centre; positive for an outward-oriented closed mesh. For open meshes it
    /// depends on o and is only indicative.
    double volume = 0.0;
    /// Bounding box of all positions (referenced or not).
    Box3d bbox;
    /// One line per kind of defect found, e.g. "12 boundary edges (mesh is open)".
    std::vector<std::string> warnings;
};

/// Measures m (see MeshReport for the exact definitions).
/// Method: exact welding by sorting positions; edges grouped by sorting 64-bit keys (no maps);
/// union-find for components and for fans around vertices. Degeneracy is an exact collinearity test.
/// \throw InvalidInput if a face index is out of range or a position is not finite.
/// Cost: O(V log V + F log F) time, O(V + F) memory, single-threaded; about 30 ms for 170k faces.
MeshReport mesh_report(const Mesh& m);

/// Merges positions with identical coordinates (+0 == -0). The result keeps the first occurrence of
/// each point, in the original order, and remaps the faces (no face is removed, so faces may become
/// degenerate). If old_to_new is given it receives the new index of every old position. The result has
/// no attributes (normals, colours and texture coordinates are dropped).
/// \throw InvalidInput if a face index is out of range or a position is not finite.
Mesh weld_exact(const Mesh& m, std::vector<std::uint32_t>* old_to_new = nullptr);

/// True if the three points are exactly collinear (zero-area triangle). Exact for all inputs whose
/// coordinate differences are representable in double (always, unless the coordinates of one
/// triangle differ by a factor of more than 2^29); otherwise a long double test.
bool exactly_collinear(const Vec3f& a, const Vec3f& b, const Vec3f& c);

}  // namespace normalflow
