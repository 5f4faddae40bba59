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

namespace normalflow {
namespace {

/// A closed tetrahedron scaled by s about c, its vertices appended to m.
void add_tetrahedron(Mesh& m, double s, Vec3d c) {
    const auto b = std::uint32_t(m.positions.size());
    for (const Vec3d p : {Vec3d{1, 1, 1}, Vec3d{1, -1, -1}, Vec3d{-1, 1, -1}, Vec3d{-1, -1, 1}})
        m.positions.push_back(Vec3f(c + p * s));
    for (const Tri t : {Tri{0, 1, 2}, Tri{0, 3, 1}, Tri{0, 2, 3}, Tri{1, 3, 2}})
        m.triangles.push_back({b + t[0], b + t[1], b + t[2]});
}

// Components numbered in the order of their first face; with `only`, a part split where faces are left out.
TEST(FaceComponents, NumberedByFirstFaceAndOnlyTheChosenFacesJoin) {
    Mesh m;
    add_tetrahedron(m, 1.0, {0, 0, 0});
    add_tetrahedron(m, 1.0, {5, 0, 0});
    std::swap(m.triangles[0], m.triangles[5]);  // the second tetrahedron's face comes first
    std::size_t n = 0;
    const std::vector<std::uint32_t> c = face_components(m, nullptr, &n);
    EXPECT_EQ(n, 2u);
    EXPECT_EQ(c, (std::vector<std::uint32_t>{0, 1, 1, 1, 0, 1, 0, 0}));
    // faces 1 and 5 of the first tetrahedron (they share its edge 0-1) and face 4 of the second
    const std::vector<char> only = {0, 1, 0, 0, 1, 1, 0, 0};
    const std::vector<std::uint32_t> d = face_components(m, &only, &n);
    EXPECT_EQ(n, 2u);
    EXPECT_EQ(
        d, (std::vector<std::uint32_t>{kNoComponent, 0, kNoComponent, kNoComponent, 1, 0, kNoComponent, kNoComponent}));
}

// Two parts allowed: the smallest of four goes when it is under the area fraction, the second smallest only when it
// is too; a part as large as the fraction stays (the caller warns of it). Attributes follow the vertices.
TEST(RemoveExtraComponents, SmallestBeyondTheAllowedGoWhileUnderTheFraction) {
    Mesh m;
    add_tetrahedron(m, 1.0, {0, 0, 0});
    add_tetrahedron(m, 0.01, {5, 0, 0});  // area 1e-4 of the first
    add_tetrahedron(m, 1.0, {10, 0, 0});
    add_tetrahedron(m, 0.3, {20, 0, 0});  // area 0.09 of the first, 0.04 of the total
    for (std::size_t i = 0; i < m.positions.size(); ++i) m.normals.push_back(Vec3f(Vec3d{double(i), 0, 0}));
    Mesh a = m;
    ComponentsRemoved r = remove_extra_components(a, 2, 0.01);
    EXPECT_EQ(r.components, 4u);
    EXPECT_EQ(r.removed, 1u);  // the speck; the 0.3 tetrahedron is 4% of the area
    EXPECT_EQ(r.faces, 4u);
    EXPECT_EQ(a.triangles.size(), 12u);
    EXPECT_EQ(a.positions.size(), 12u);
    EXPECT_EQ(a.normals[4].x, 8.0f);  // the third tetrahedron's first vertex, moved down with its normal
    Mesh b = m;
    r = remove_extra_components(b, 2, 0.05);
    EXPECT_EQ(r.removed, 2u);
    EXPECT_EQ(b.triangles.size(), 8u);
    EXPECT_NEAR(r.largest_area_fraction, 0.09 / 2.0901, 1e-3);
    Mesh c = m;
    EXPECT_EQ(remove_extra_components(c, 4, 1.0).removed, 0u);  // as many parts as allowed: nothing goes
    EXPECT_EQ(c.triangles.size(), m.triangles.size());
}

}  // namespace
}  // namespace normalflow
