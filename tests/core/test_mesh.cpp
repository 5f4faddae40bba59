// Tests for lib/core/mesh.h: check_mesh, the one mesh validation every stage calls.
#include "core/mesh.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "core/errors.h"

namespace normalflow {
namespace {

Mesh triangle() {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    return m;
}

std::string message(const Mesh& m) {
    try {
        check_mesh(m, "who");
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "";
}

// Angle weighting: a cube corner's normal is the diagonal however its three faces are split, and a vertex in no
// face of positive area gets a zero normal.
TEST(VertexNormals, CubeCornersAreTheDiagonalWhateverTheSplit) {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {5, 5, 5}};
    m.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                   {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
    compute_vertex_normals(m);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (std::size_t v = 0; v < 8; ++v) {
        const Vec3d outward = normalized(Vec3d(m.positions[v]) - Vec3d{0.5, 0.5, 0.5});
        EXPECT_NEAR(dot(Vec3d(m.normals[v]), outward), 1.0, 1e-6) << "corner " << v;
    }
    EXPECT_EQ(m.normals[8], (Vec3f{0, 0, 0}));  // in no triangle
    m.triangles.push_back({8, 8, 0});           // a degenerate face adds nothing
    compute_vertex_normals(m);
    EXPECT_EQ(m.normals[8], (Vec3f{0, 0, 0}));
    check_mesh(m, "test");
}

TEST(CheckMesh, ValidAndEmptyMeshesPass) {
    EXPECT_EQ(message(triangle()), "");
    EXPECT_EQ(message(Mesh{}), "");  // nothing to check; stages that need triangles say so themselves
    Mesh points = triangle();
    points.triangles.clear();
    EXPECT_EQ(message(points), "");
}

TEST(CheckMesh, IndexOutOfRange) {
    Mesh m = triangle();
    m.triangles.push_back({0, 2, 3});
    EXPECT_EQ(message(m), "who: triangle 1 has vertex index 3, expected < 3");
    m.positions.clear();
    EXPECT_EQ(message(m), "who: triangle 0 has vertex index 0, expected < 0");
}

TEST(CheckMesh, NonFinitePositionEvenIfUnreferenced) {
    Mesh m = triangle();
    m.positions[1].y = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(message(m), "who: vertex 1 has a non-finite coordinate");
    m = triangle();
    m.positions.push_back({0, 0, std::numeric_limits<float>::infinity()});  // not used by any triangle
    EXPECT_EQ(message(m), "who: vertex 3 has a non-finite coordinate");
}

TEST(CheckMesh, IndicesAreCheckedBeforePositions) {
    Mesh m = triangle();
    m.positions[0].x = std::numeric_limits<float>::quiet_NaN();
    m.triangles[0][2] = 9;
    EXPECT_EQ(message(m), "who: triangle 0 has vertex index 9, expected < 3");
}

}  // namespace
}  // namespace normalflow
