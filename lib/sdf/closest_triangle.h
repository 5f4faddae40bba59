#pragma once
/// \file closest_triangle.h
/// What scan conversion needs from a mesh to measure distances: the closest point on any triangle.
/// As OpenVDB's MeshToVolume documents its mesh adapter, scan_convert states its needs as this tiny
/// interface. lib/ supplies a brute-force version (for tests) and a bounding volume hierarchy
/// (make_bvh_query); io/cgal/aabb_distance.h supplies a CGAL AABB-tree version, so the three can be
/// cross-checked for free.

#include <cstdint>
#include <limits>
#include <memory>

#include "core/mesh.h"
#include "core/vec.h"

namespace normalflow {

/// The closest point of a mesh to a query point.
struct ClosestHit {
    double squared_distance = std::numeric_limits<double>::infinity();  ///< world units squared
    std::uint32_t triangle = kNone;  ///< index into Mesh::triangles; kNone if nothing was found
    Vec3d point;                     ///< closest point on that triangle, world units

    static constexpr std::uint32_t kNone = 0xffffffffu;
    bool found() const { return triangle != kNone; }
};

/// Closest-triangle queries on a fixed mesh. Implementations keep a reference or copy of the mesh
/// made at construction; const queries must be thread-safe (scan_convert calls them from TBB workers).
class ClosestTriangleQuery {
public:
    virtual ~ClosestTriangleQuery() = default;

    /// The closest point on any triangle to p (exact up to rounding). Zero-area triangles count as
    /// segments or points. Returns a hit with triangle == kNone only for a mesh without triangles.
    virtual ClosestHit closest(const Vec3d& p) const = 0;

    /// The closest point among those strictly closer than sqrt(max_squared_distance); a hit with
    /// triangle == kNone if there is none. hint (a triangle index or kNone, e.g. the previous
    /// answer for a neighbouring point) may speed the search up but never changes the distance.
    /// The default calls closest(p); implementations override it to prune their search.
    virtual ClosestHit closest_within(const Vec3d& p, double max_squared_distance,
                                      std::uint32_t hint = ClosestHit::kNone) const {
        (void)hint;
        ClosestHit h = closest(p);
        if (!(h.squared_distance < max_squared_distance)) return ClosestHit{};
        return h;
    }
};

/// Closest point to p on triangle (a, b, c) (Ericson, Real-Time Collision Detection, §5.1.5), robust
/// for zero-area triangles (falls back to the closest point on the three edges).
Vec3d closest_point_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c);

/// Barycentric coordinates w (of a, b, c) of a point p in the plane of triangle (a, b, c), such as the
/// point closest_point_on_triangle returns: p = w[0] a + w[1] b + w[2] c. false (w untouched) for a
/// zero-area triangle.
bool barycentric_coordinates(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c, double w[3]);

/// Brute force: O(#F) per query, for tests and cross-checks. Copies the mesh.
std::unique_ptr<ClosestTriangleQuery> make_brute_force_query(const Mesh& m);

/// A bounding volume hierarchy over the triangles (median split along the longest axis, 4
/// triangles per leaf), nearest-child-first traversal. O(#F log #F) to build (TBB tasks), about
/// O(log #F) per query. Copies what it needs from the mesh.
/// \throw InvalidInput if a triangle index is out of range.
std::unique_ptr<ClosestTriangleQuery> make_bvh_query(const Mesh& m);

}  // namespace normalflow
