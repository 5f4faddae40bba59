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
