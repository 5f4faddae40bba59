#pragma once
/// \file repair.h
/// Polygon-soup repair and self-intersection counting with CGAL 5.5 (GPL-3.0-or-later).
/// All CGAL code is in repair.cpp; no CGAL type appears here.

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh.h"

namespace normalflow {

/// Number of pairs of faces that intersect, ignoring pairs that only touch through a shared vertex or
/// a shared edge, after exact welding (as in shared/data/SOURCES.md and Thingi10K).
///
/// Method: CGAL::box_self_intersection_d over the face bounding boxes, then the pair test of
/// CGAL::Polygon_mesh_processing::self_intersections (CGAL 5.5 has it only for face graphs, so it is
/// re-applied to the welded soup here), with exact predicates (Epick):
///  - no shared vertex: the triangles intersect (CGAL::do_intersect);
///  - one shared vertex v: the edge opposite v of one face meets the other face;
///  - a shared edge: the two other corners are coplanar with it and on the same side (fold-over);
///  - three shared vertices (duplicate faces, any orientation): always counted.
/// Faces with a repeated welded vertex or collinear corners are skipped (CGAL reports those as (f,f)).
/// Coordinates are the float positions of m, so the count can differ from one made on the double
/// coordinates of a text file: on Thingi10K 96582.stl (16 significant digits) floats give 114 pairs,
/// doubles 52, because rounding turns touching contacts into crossings.
/// \throw InvalidInput if a face index is out of range or a position is not finite.
/// Cost: O(F log F + K) for K candidate pairs, single-threaded; about 60 ms for 21k faces.
std::size_t count_self_intersections(const Mesh& m);

/// The pairs counted by count_self_intersections, as face indices of m (smaller first), sorted; with `only` (one
/// flag per face), just the pairs with a flagged face (a local change checked without the cost of the whole mesh's
/// candidate pairs). weld = false: m's vertex indices are its connectivity, as a reader of the written file sees
/// them, so two faces that touch at distinct vertices with the same position count (a surface that pinches itself
/// where a processing step made two vertices meet); this is the check of a result normalflow writes.
std::vector<std::pair<std::uint32_t, std::uint32_t>> self_intersecting_pairs(const Mesh& m,
                                                                             const std::vector<char>* only = nullptr,
                                                                             bool weld = true);

/// count_self_intersections without welding (self_intersecting_pairs with weld = false): the count an independent
/// evaluator reading the written file finds (CGAL's self_intersections on the mesh as it is).
std::size_t count_self_intersections_as_written(const Mesh& m);

/// Which repairs repair_mesh performs, in this order.
struct RepairOptions {
    bool merge_points = true;       ///< merge positions with identical coordinates (exact welding)
    bool remove_degenerate = true;  ///< remove faces with a repeated vertex or exactly collinear corners
                                    ///< (removing a zero-area "cap" can leave a crack: its long edge
                                    ///< becomes a boundary edge)
    bool remove_duplicates = true;  ///< keep one face of each set of faces on the same three vertices
                                    ///< (any order or orientation)
    bool orient = true;             ///< orient faces consistently (CGAL orient_polygon_soup), then turn
                                    ///< each closed patch outward (positive volume)
};

/// What repair_mesh did.
struct RepairReport {
    std::size_t points_merged = 0;       ///< positions removed by merging
    std::size_t degenerate_removed = 0;  ///< faces removed as degenerate
    std::size_t duplicates_removed = 0;  ///< faces removed as duplicates
    std::size_t faces_reversed = 0;      ///< faces whose orientation differs from the input at the end
    /// False when orient_polygon_soup could not orient every edge consistently without splitting
    /// non-manifold vertices/edges (or the surface is non-orientable). The faces are then oriented
    /// consistently within each manifold patch and the vertices are NOT split (the mesh keeps its
    /// indexing). True when orientation was not requested.
    bool orientable = true;
    std::size_t patches_inverted = 0;   ///< closed patches turned outward (their faces reversed)
    std::size_t open_patches = 0;       ///< patches not closed: their outward side is not defined
    std::vector<std::string> warnings;  ///< e.g. "3 open patches: outward orientation not defined"
};

/// Repairs a polygon soup, modified in place: merges duplicate points, removes degenerate and
/// duplicate faces, orients faces consistently and makes closed patches outward.
/// Method: CGAL::Polygon_mesh_processing::merge_duplicate_points_in_polygon_soup,
/// merge_duplicate_polygons_in_polygon_soup and orient_polygon_soup (the steps of repair_polygon_soup,
/// which returns nothing in 5.5, run one by one so that each can be counted and switched off).
/// A "patch" is a set of faces connected through edges with exactly two faces; it is closed if all of
/// its edges have two faces; a closed patch with negative signed volume is reversed.
/// Point order: merged points keep their first occurrence, in input order; unreferenced points are kept.
/// Face order: the surviving faces keep their input order. Running it twice changes nothing the second time.
/// Attributes: merging points renumbers them, so normals, colours and texture coordinates are dropped
/// (with a warning in the report when m had any).
/// \throw InvalidInput if a face index is out of range or a position is not finite.
/// Cost: O((V + F) log(V + F)), single-threaded; about 0.2 s for 170k faces.
RepairReport repair_mesh(Mesh& m, const RepairOptions& opt = {});

}  // namespace normalflow
