#pragma once
/// \file aabb_distance.h
/// Closest-triangle queries backed by CGAL's AABB tree (GPL-3.0-or-later), for scan_convert.

#include <memory>

#include "core/mesh.h"
#include "sdf/closest_triangle.h"

namespace normalflow {

/// A ClosestTriangleQuery on a copy of m's triangles, using CGAL::AABB_tree (Epick kernel) with
/// accelerated distance queries built up front, so const queries are thread-safe. Zero-area
/// triangles are kept (CGAL treats them as segments/points). The hint of closest_within seeds the
/// search with that triangle's closest point.
/// \throw InvalidInput for an empty mesh, an out-of-range index or a non-finite position.
/// Cost: O(#F log #F) to build; O(log #F) per query (compare make_bvh_query, lib/sdf).
std::unique_ptr<ClosestTriangleQuery> make_aabb_query(const Mesh& m);

}  // namespace normalflow
