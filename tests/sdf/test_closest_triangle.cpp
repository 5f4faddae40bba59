// Tests for lib/sdf/closest_triangle.h (and io/cgal/aabb_distance.h when built with CGAL).
#include "sdf/closest_triangle.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "core/errors.h"
#include "sdf_test_meshes.h"
#ifdef NORMALFLOW_TEST_HAS_CGAL
#include "io/cgal/aabb_distance.h"
#endif

namespace normalflow {
namespace {

Mesh dirty_soup() {
    // A random soup with degenerate (zero-area, collinear, point) and duplicate triangles.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    Mesh m;
    for (int f = 0; f < 300; ++f) {
        const auto base = std::uint32_t(m.positions.size());
        const Vec3f c(u(rng), u(rng), u(rng));
        for (int k = 0; k < 3; ++k) m.positions.push_back(c + Vec3f(u(rng), u(rng), u(rng)) * 0.2f);
        m.triangles.push_back({base, base + 1, base + 2});
    }
    m.triangles.push_back({0, 0, 0});  // a point
    m.triangles.push_back({3, 4, 3});  // a segment
    m.positions.push_back(Vec3f(2, 2, 2));
    m.positions.push_back(Vec3f(3, 3, 3));
    m.positions.push_back(Vec3f(4, 4, 4));
    const auto n = std::uint32_t(m.positions.size());
    m.triangles.push_back({n - 3, n - 2, n - 1});  // collinear
    m.triangles.push_back(m.triangles[5]);         // duplicate
    return m;
}

TEST(ClosestPointOnTriangle, RegionsOfAUnitTriangle) {
    const Vec3d a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    auto near = [](Vec3d x, Vec3d y) { return norm(x - y) < 1e-12; };
    EXPECT_TRUE(near(closest_point_on_triangle({0.2, 0.2, 5}, a, b, c), {0.2, 0.2, 0}));  // face
    EXPECT_TRUE(near(closest_point_on_triangle({-1, -1, 1}, a, b, c), a));                // vertex
    EXPECT_TRUE(near(closest_point_on_triangle({0.5, -2, 0}, a, b, c), {0.5, 0, 0}));     // edge ab
    EXPECT_TRUE(near(closest_point_on_triangle({1, 1, 0}, a, b, c), {0.5, 0.5, 0}));      // edge bc
    EXPECT_TRUE(near(closest_point_on_triangle({3, 0, 0}, a, a, b), b));                  // degenerate
    EXPECT_TRUE(near(closest_point_on_triangle({3, 1, 0}, a, a, a), a));
}

void expect_agree(const Mesh& m, const ClosestTriangleQuery& ref, const ClosestTriangleQuery& q, double spread) {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-spread, spread);
    std::uint32_t hint = ClosestHit::kNone;
    for (int s = 0; s < 2000; ++s) {
        const Vec3d p{u(rng), u(rng), u(rng)};
        const ClosestHit a = ref.closest(p), b = q.closest(p);
        ASSERT_TRUE(b.found());
        EXPECT_NEAR(a.squared_distance, b.squared_distance, 1e-9 * (1 + a.squared_distance));
        const Tri& t = m.triangles[b.triangle];
        const Vec3d onb =
            closest_point_on_triangle(p, Vec3d(m.positions[t[0]]), Vec3d(m.positions[t[1]]), Vec3d(m.positions[t[2]]));
        EXPECT_NEAR(squared_norm(onb - p), b.squared_distance, 1e-9 * (1 + a.squared_distance));
        // Bounded search with a hint: the same distance when inside the bound, nothing outside.
        const double bound = 0.25;
        const ClosestHit c = q.closest_within(p, bound, hint);
        if (a.squared_distance < bound * 0.999) {
            ASSERT_TRUE(c.found());
            EXPECT_NEAR(c.squared_distance, a.squared_distance, 1e-9 * (1 + a.squared_distance));
            hint = c.triangle;
        } else if (a.squared_distance > bound * 1.001) {
            EXPECT_FALSE(c.found());
        }
    }
}

TEST(ClosestTriangleQuery, BvhAgreesWithBruteForceOnSphere) {
    const Mesh m = test::icosphere(1.0, 3);
    const auto ref = make_brute_force_query(m);
    const auto bvh = make_bvh_query(m);
    expect_agree(m, *ref, *bvh, 1.5);
}

TEST(ClosestTriangleQuery, BvhAgreesWithBruteForceOnDirtySoup) {
    const Mesh m = dirty_soup();
    const auto ref = make_brute_force_query(m);
    const auto bvh = make_bvh_query(m);
    expect_agree(m, *ref, *bvh, 2.0);
}

#ifdef NORMALFLOW_TEST_HAS_CGAL
TEST(ClosestTriangleQuery, AabbAgreesWithBruteForce) {
    for (const Mesh& m : {test::icosphere(1.0, 3), dirty_soup()}) {
        const auto ref = make_brute_force_query(m);
        const auto aabb = make_aabb_query(m);
        expect_agree(m, *ref, *aabb, 1.8);
    }
}

TEST(ClosestTriangleQuery, AabbRejectsBadInput) {
    Mesh m = test::icosphere(1.0, 0);
    m.triangles[3][1] = 999;
    EXPECT_THROW(make_aabb_query(m), InvalidInput);
    EXPECT_THROW(make_aabb_query(Mesh{}), InvalidInput);
}
#endif

TEST(ClosestTriangleQuery, BadInput) {
    Mesh m = test::icosphere(1.0, 0);
    m.triangles[3][1] = 999;
    try {
        make_bvh_query(m);
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("triangle 3 has vertex index 999"), std::string::npos) << e.what();
    }
    Mesh n = test::icosphere(1.0, 0);
    n.positions[2].x = std::nanf("");
    EXPECT_THROW(make_brute_force_query(n), InvalidInput);
    // An empty mesh is a valid query object that finds nothing.
    EXPECT_FALSE(make_bvh_query(Mesh{})->closest({0, 0, 0}).found());
}

}  // namespace
}  // namespace normalflow
