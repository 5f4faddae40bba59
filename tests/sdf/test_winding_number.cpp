// Tests for lib/sdf/winding_number.h.
#include "sdf/winding_number.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "core/errors.h"
#include "sdf_test_meshes.h"

namespace normalflow {
namespace {

TEST(SolidAngle, OctantTriangleIsAnEighthOfTheSphere) {
    // Seen from the origin, the triangle (e1, e2, e3) covers one octant: 4π / 8, positive (its normal points away).
    EXPECT_NEAR(solid_angle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}), std::numbers::pi / 2, 1e-12);
    EXPECT_NEAR(solid_angle({0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}), -std::numbers::pi / 2, 1e-12);
    EXPECT_EQ(solid_angle({0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}), 0.0);
}

TEST(WindingNumber, OneInsideZeroOutsideClosedIcosphere) {
    const Mesh m = test::icosphere(1.0, 4);  // 5120 faces
    const WindingNumber w(m);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    double max_err = 0;
    for (int s = 0; s < 500; ++s) {
        Vec3d dir = normalized(Vec3d{u(rng), u(rng), u(rng)});
        const double r = 0.05 + 1.9 * (s % 100) / 100.0;  // 0.05 .. 1.95
        if (std::abs(r - 1.0) < 0.02) continue;           // skip the chord-error shell
        const Vec3d p = dir * r;
        const double expect = r < 1 ? 1.0 : 0.0;
        EXPECT_NEAR(w.exact(p), expect, 1e-9);
        max_err = std::max(max_err, std::abs(w(p) - expect));
    }
    EXPECT_LT(max_err, 0.02);  // fast approximation (beta = 2)
    EXPECT_NEAR(w({50, 0, 0}), 0.0, 1e-6);
    EXPECT_NEAR(WindingNumber(test::flipped(m))({0, 0, 0}), -1.0, 0.02);
}

TEST(WindingNumber, FastApproximationIsCloseToExactNearTheSurface) {
    const Mesh m = test::torus_mesh(1.0, 0.4, 96, 48);
    const WindingNumber w(m);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    double max_err = 0;
    for (int s = 0; s < 400; ++s) {
        const Vec3d p{u(rng), u(rng), u(rng) * 0.4};
        max_err = std::max(max_err, std::abs(w(p) - w.exact(p)));
    }
    EXPECT_LT(max_err, 0.02);
}

TEST(WindingNumber, HalfAtAHole) {
    // Remove the faces around the +z pole: on the hole, w is about 1/2 (half of all directions are
    // covered); deep inside it stays near 1.
    Mesh m = test::icosphere(1.0, 3);
    std::vector<Tri> kept;
    for (const Tri& t : m.triangles) {
        const double z = (m.positions[t[0]].z + m.positions[t[1]].z + m.positions[t[2]].z) / 3.0;
        if (z < 0.9) kept.push_back(t);
    }
    ASSERT_LT(kept.size(), m.triangles.size());
    m.triangles = kept;
    const WindingNumber w(m);
    EXPECT_NEAR(w({0, 0, 0.97}), 0.5, 0.1);
    EXPECT_GT(w({0, 0, -0.5}), 0.9);
    EXPECT_LT(w({0, 0, 1.5}), 0.1);
}

TEST(WindingNumber, NestedAndDuplicatedShells) {
    const Mesh outer = test::icosphere(2.0, 3), inner = test::icosphere(1.0, 3);
    const WindingNumber hollow(test::concat(outer, test::flipped(inner)));
    EXPECT_NEAR(hollow({1.5, 0, 0}), 1.0, 0.02);
    EXPECT_NEAR(hollow({0.2, 0, 0}), 0.0, 0.02);
    const WindingNumber doubled(test::concat(outer, outer));
    EXPECT_NEAR(doubled({0.5, 0, 0}), 2.0, 0.04);
    EXPECT_NEAR(doubled({3, 0, 0}), 0.0, 0.02);
}

}  // namespace
}  // namespace normalflow

namespace normalflow {
namespace {

// Barill et al. 2018: the far field is expanded to the second derivative of the kernel, so the
// truncation error of a node seen at distance beta·r falls like beta^-3. A first-order-only
// expansion (falls like beta^-2) was the cause of a 0.06 error at the centre of a sphere.
TEST(WindingNumber, ErrorFallsAtLeastCubicallyWithBeta) {
    const Mesh m = test::icosphere(1.0, 4);
    auto max_error = [&](double beta) {
        const WindingNumber w(m, beta);
        std::mt19937 rng(7);
        std::uniform_real_distribution<double> u(-1, 1);
        double e = 0;
        for (int s = 0; s < 300; ++s) {
            const Vec3d p = normalized(Vec3d{u(rng), u(rng), u(rng)}) * (0.05 + 1.9 * (s % 100) / 100.0);
            e = std::max(e, std::abs(w(p) - w.exact(p)));
        }
        return e;
    };
    const double e2 = max_error(2.0), e4 = max_error(4.0);
    std::printf("max |fast - exact|: beta 2: %.3g, beta 4: %.3g\n", e2, e4);
    EXPECT_LT(e2, 5e-3);
    EXPECT_LT(e4, e2 / 6.0);  // 8x for a clean third-order truncation
}

TEST(WindingNumber, BadInput) {
    const Mesh m = test::icosphere(1.0, 1);
    EXPECT_THROW(WindingNumber(m, 0.5), InvalidInput);
    Mesh bad = m;
    bad.triangles.push_back({0, 1, 9999});
    EXPECT_THROW(WindingNumber{bad}, InvalidInput);
    const WindingNumber empty(Mesh{});
    EXPECT_EQ(empty({0, 0, 0}), 0.0);
}

}  // namespace
}  // namespace normalflow
