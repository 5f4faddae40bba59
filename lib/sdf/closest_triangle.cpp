#include "sdf/closest_triangle.h"

#include <algorithm>
#include <cmath>

#include "sdf/triangle_bvh.h"

namespace normalflow {
namespace {

Vec3d closest_on_segment(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
    const Vec3d ab = b - a;
    const double l2 = squared_norm(ab);
    if (!(l2 > 0)) return a;
    const double t = std::clamp(dot(p - a, ab) / l2, 0.0, 1.0);
    return a + ab * t;
}

class BruteForceQuery final : public ClosestTriangleQuery {
public:
    explicit BruteForceQuery(const Mesh& m) : mesh_(m) { check_mesh(mesh_, "make_brute_force_query"); }

    ClosestHit closest(const Vec3d& p) const override {
        ClosestHit best;
        for (std::size_t f = 0; f < mesh_.triangles.size(); ++f) {
            const Tri& t = mesh_.triangles[f];
            const Vec3d q = closest_point_on_triangle(p, Vec3d(mesh_.positions[t[0]]), Vec3d(mesh_.positions[t[1]]),
                                                      Vec3d(mesh_.positions[t[2]]));
            const double d2 = squared_norm(q - p);
            if (d2 < best.squared_distance) best = {d2, std::uint32_t(f), q};
        }
        return best;
    }

private:
    Mesh mesh_;
};

class BvhQuery final : public ClosestTriangleQuery {
public:
    explicit BvhQuery(const Mesh& m) {
        check_mesh(m, "make_bvh_query");
        bvh_.build(m, 4);
        corners_.resize(bvh_.order.size() * 3);
        leaf_of_.resize(m.triangles.size());
        for (std::size_t i = 0; i < bvh_.order.size(); ++i) {
            const Tri& t = m.triangles[bvh_.order[i]];
            for (int c = 0; c < 3; ++c) corners_[3 * i + std::size_t(c)] = Vec3d(m.positions[t[c]]);
            leaf_of_[bvh_.order[i]] = std::uint32_t(i);
        }
    }

    ClosestHit closest(const Vec3d& p) const override {
        return closest_within(p, std::numeric_limits<double>::infinity(), ClosestHit::kNone);
    }

    ClosestHit closest_within(const Vec3d& p, double max_sq, std::uint32_t hint) const override {
        ClosestHit best;
        best.squared_distance = max_sq;
        if (bvh_.nodes.empty()) return ClosestHit{};
        if (hint < leaf_of_.size()) test(p, leaf_of_[hint], best);
        std::uint32_t stack[128];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const detail::BvhNode& nd = bvh_.nodes[stack[--top]];
            if (!(detail::box_squared_distance(p, nd.lo, nd.hi) < best.squared_distance)) continue;
            if (nd.count > 0) {
                for (std::uint32_t i = nd.first; i < nd.first + nd.count; ++i) test(p, i, best);
                continue;
            }
            const std::uint32_t l = std::uint32_t(&nd - bvh_.nodes.data()) + 1, r = nd.first;
            const double dl = detail::box_squared_distance(p, bvh_.nodes[l].lo, bvh_.nodes[l].hi);
            const double dr = detail::box_squared_distance(p, bvh_.nodes[r].lo, bvh_.nodes[r].hi);
            // Push the farther child first so the nearer one is visited first.
            if (dl < dr) {
                if (dr < best.squared_distance) stack[top++] = r;
                if (dl < best.squared_distance) stack[top++] = l;
            } else {
                if (dl < best.squared_distance) stack[top++] = l;
                if (dr < best.squared_distance) stack[top++] = r;
            }
        }
        if (best.triangle == ClosestHit::kNone) return ClosestHit{};
        return best;
    }

private:
    void test(const Vec3d& p, std::uint32_t i, ClosestHit& best) const {
        const Vec3d* c = &corners_[3 * std::size_t(i)];
        const Vec3d q = closest_point_on_triangle(p, c[0], c[1], c[2]);
        const double d2 = squared_norm(q - p);
        const std::uint32_t id = bvh_.order[i];
        // Ties go to the smaller triangle index, so the answer does not depend on the visit order.
        if (d2 < best.squared_distance ||
            (d2 == best.squared_distance && best.triangle != ClosestHit::kNone && id < best.triangle)) {
            best = {d2, id, q};
        }
    }

    detail::TriangleBvh bvh_;
    std::vector<Vec3d> corners_;
    std::vector<std::uint32_t> leaf_of_;
};

}  // namespace

bool barycentric_coordinates(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c, double w[3]) {
    const Vec3d n = cross(b - a, c - a);
    const double nn = dot(n, n);
    if (!(nn > 0)) return false;
    w[1] = dot(cross(p - a, c - a), n) / nn;
    w[2] = dot(cross(b - a, p - a), n) / nn;
    w[0] = 1 - w[1] - w[2];
    return true;
}

Vec3d closest_point_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d ab = b - a, ac = c - a, ap = p - a;
    const Vec3d n = cross(ab, ac);
    const double n2 = squared_norm(n);
    const double scale = std::max(squared_norm(ab), squared_norm(ac));
    if (!(n2 > 1e-24 * scale * scale)) {  // zero-area (or nearly): closest point on the edges
        const Vec3d q0 = closest_on_segment(p, a, b), q1 = closest_on_segment(p, b, c),
                    q2 = closest_on_segment(p, c, a);
        const double d0 = squared_norm(q0 - p), d1 = squared_norm(q1 - p), d2 = squared_norm(q2 - p);
        return d0 <= d1 && d0 <= d2 ? q0 : (d1 <= d2 ? q1 : q2);
    }
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3d bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
    const Vec3d cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

std::unique_ptr<ClosestTriangleQuery> make_brute_force_query(const Mesh& m) {
    return std::make_unique<BruteForceQuery>(m);
}

std::unique_ptr<ClosestTriangleQuery> make_bvh_query(const Mesh& m) { return std::make_unique<BvhQuery>(m); }

}  // namespace normalflow
