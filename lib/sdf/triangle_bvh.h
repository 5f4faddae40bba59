#pragma once
/// \file triangle_bvh.h
/// Internal: a bounding volume hierarchy over triangles, shared by the closest-point query and the
/// fast winding number. Not part of the public API (namespace detail).

#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/vec.h"

namespace normalflow::detail {

/// One node: its box, and either a leaf range [first, first + count) into TriangleBvh::order
/// (count > 0) or an inner node (count == 0) whose children are (index + 1) and `first`.
struct BvhNode {
    Vec3d lo, hi;
    std::uint32_t first = 0;
    std::uint32_t count = 0;
};

/// Median-split BVH; node 0 is the root. Deterministic (independent of the thread count).
struct TriangleBvh {
    std::vector<BvhNode> nodes;
    std::vector<std::uint32_t> order;  ///< triangle indices in leaf order

    /// Builds over the triangles of m (all must have valid indices); leaf_size >= 1.
    void build(const Mesh& m, int leaf_size);
};

/// Squared distance from p to box [lo, hi].
inline double box_squared_distance(const Vec3d& p, const Vec3d& lo, const Vec3d& hi) {
    double s = 0;
    for (int a = 0; a < 3; ++a) {
        const double d = p[a] < lo[a] ? lo[a] - p[a] : (p[a] > hi[a] ? p[a] - hi[a] : 0.0);
        s += d * d;
    }
    return s;
}

}  // namespace normalflow::detail
