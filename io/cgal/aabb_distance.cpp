#include "io/cgal/aabb_distance.h"

#include <string>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "core/errors.h"

namespace normalflow {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Triangle = K::Triangle_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, Iterator>;
using Traits = CGAL::AABB_traits<K, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;

class AabbQuery final : public ClosestTriangleQuery {
public:
    explicit AabbQuery(const Mesh& m) {
        if (m.empty()) throw InvalidInput("make_aabb_query: empty mesh (no triangles)");
        const std::size_t nv = m.positions.size();
        triangles_.reserve(m.triangles.size());
        for (std::size_t f = 0; f < m.triangles.size(); ++f) {
            Point p[3];
            for (int c = 0; c < 3; ++c) {
                const std::uint32_t v = m.triangles[f][std::size_t(c)];
                if (v >= nv)
                    throw InvalidInput("make_aabb_query: triangle " + std::to_string(f) + " has vertex index " +
                                       std::to_string(v) + ", expected < " + std::to_string(nv));
                if (!is_finite(m.positions[v]))
                    throw InvalidInput("make_aabb_query: vertex " + std::to_string(v) + " has a non-finite coordinate");
                p[c] = Point(m.positions[v].x, m.positions[v].y, m.positions[v].z);
            }
            triangles_.emplace_back(p[0], p[1], p[2]);
        }
        tree_.insert(triangles_.cbegin(), triangles_.cend());
        tree_.build();
        tree_.accelerate_distance_queries();
    }

    ClosestHit closest(const Vec3d& p) const override {
        return to_hit(tree_.closest_point_and_primitive(Point(p.x, p.y, p.z)), p);
    }

    ClosestHit closest_within(const Vec3d& p, double max_sq, std::uint32_t hint) const override {
        const Point q(p.x, p.y, p.z);
        ClosestHit h;
        if (hint < triangles_.size()) {
            const Iterator it = triangles_.cbegin() + std::ptrdiff_t(hint);
            const Point seed = K::Construct_projected_point_3()(*it, q);
            h = to_hit(tree_.closest_point_and_primitive(q, Tree::Point_and_primitive_id(seed, it)), p);
        } else {
            h = to_hit(tree_.closest_point_and_primitive(q), p);
        }
        if (!(h.squared_distance < max_sq)) return ClosestHit{};
        return h;
    }

private:
    ClosestHit to_hit(const Tree::Point_and_primitive_id& pp, const Vec3d& p) const {
        const Vec3d x(pp.first.x(), pp.first.y(), pp.first.z());
        return {squared_norm(x - p), std::uint32_t(pp.second - triangles_.cbegin()), x};
    }

    std::vector<Triangle> triangles_;
    Tree tree_;
};

}  // namespace

std::unique_ptr<ClosestTriangleQuery> make_aabb_query(const Mesh& m) { return std::make_unique<AabbQuery>(m); }

}  // namespace normalflow
