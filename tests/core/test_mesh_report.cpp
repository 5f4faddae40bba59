// Tests for lib/core/mesh_report.h: analytic cases with known answers, then properties, then bad input.
// The real-data table (every mesh in shared/data against SOURCES.md) is tests/io/test_shared_data.cpp.
#include "core/mesh_report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/errors.h"

namespace nf = normalflow;
using nf::Mesh;
using nf::Tri;
using nf::Vec3f;

namespace {

// Unit right tetrahedron, outward (counter-clockwise seen from outside). Volume 1/6.
Mesh tetrahedron() {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    return m;
}

// Axis-aligned cube [o, o+s]^3, 12 outward triangles. Volume s^3, area 6 s^2.
Mesh cube(Vec3f o = {0, 0, 0}, float s = 1.0f) {
    Mesh m;
    for (int i = 0; i < 8; ++i)
        m.positions.push_back({o.x + s * float(i & 1), o.y + s * float((i >> 1) & 1), o.z + s * float((i >> 2) & 1)});
    m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                   {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return m;
}

Mesh concat(const Mesh& a, const Mesh& b) {
    Mesh m = a;
    const auto off = static_cast<std::uint32_t>(a.positions.size());
    m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
    for (Tri t : b.triangles) m.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
    return m;
}

// Every triangle gets its own three copies of its corners (as in an STL file).
Mesh explode(const Mesh& in) {
    Mesh m;
    for (const Tri& t : in.triangles) {
        const auto n = static_cast<std::uint32_t>(m.positions.size());
        for (auto v : t) m.positions.push_back(in.positions[v]);
        m.triangles.push_back({n, n + 1, n + 2});
    }
    return m;
}

void expect_clean_closed(const nf::MeshReport& r) {
    EXPECT_TRUE(r.closed);
    EXPECT_TRUE(r.manifold);
    EXPECT_TRUE(r.oriented);
    EXPECT_EQ(r.boundary_edges, 0u);
    EXPECT_EQ(r.non_manifold_edges, 0u);
    EXPECT_EQ(r.non_manifold_vertices, 0u);
    EXPECT_EQ(r.degenerate_faces, 0u);
    EXPECT_EQ(r.duplicate_faces, 0u);
    EXPECT_EQ(r.inconsistent_edges, 0u);
}

}  // namespace

TEST(MeshReport, Tetrahedron) {
    const auto r = nf::mesh_report(tetrahedron());
    EXPECT_EQ(r.vertices, 4u);
    EXPECT_EQ(r.input_vertices, 4u);
    EXPECT_EQ(r.referenced_vertices, 4u);
    EXPECT_EQ(r.faces, 4u);
    EXPECT_EQ(r.edges, 6u);
    EXPECT_EQ(r.components, 1u);
    EXPECT_EQ(r.euler_characteristic, 2);
    expect_clean_closed(r);
    EXPECT_NEAR(r.volume, 1.0 / 6.0, 1e-12);
    EXPECT_NEAR(r.area, 1.5 + std::sqrt(3.0) / 2.0, 1e-12);
    EXPECT_DOUBLE_EQ(r.bbox.min.x, 0.0);
    EXPECT_DOUBLE_EQ(r.bbox.max.z, 1.0);
    EXPECT_TRUE(r.warnings.empty());
}

TEST(MeshReport, CubeVolumeAreaAndChi) {
    const auto r = nf::mesh_report(cube({10, -3, 2}, 2.0f));
    expect_clean_closed(r);
    EXPECT_EQ(r.vertices, 8u);
    EXPECT_EQ(r.edges, 18u);
    EXPECT_EQ(r.euler_characteristic, 2);
    EXPECT_NEAR(r.volume, 8.0, 1e-12);
    EXPECT_NEAR(r.area, 24.0, 1e-12);
}

TEST(MeshReport, InsideOutCubeHasNegativeVolumeAndWarns) {
    Mesh m = cube();
    for (Tri& t : m.triangles) std::swap(t[1], t[2]);
    const auto r = nf::mesh_report(m);
    EXPECT_TRUE(r.oriented);
    EXPECT_NEAR(r.volume, -1.0, 1e-12);
    EXPECT_FALSE(r.warnings.empty());
}

TEST(MeshReport, CubeWithOneFaceRemovedHasFourBoundaryEdges) {
    Mesh m = cube();
    m.triangles.erase(m.triangles.begin(), m.triangles.begin() + 2);  // the z = 0 square
    const auto r = nf::mesh_report(m);
    EXPECT_EQ(r.boundary_edges, 4u);
    EXPECT_EQ(r.boundary_loops, 1u);
    EXPECT_FALSE(r.closed);
    EXPECT_TRUE(r.manifold);
    EXPECT_TRUE(r.oriented);
    EXPECT_EQ(r.euler_characteristic, 1);  // disc
}

TEST(MeshReport, BoundaryLoopsCountHolesNotEdges) {
    // a cube without its bottom and top squares: a tube with two loops of 4 edges
    Mesh m = cube();
    std::vector<Tri> kept;
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
        if (f >= 4) kept.push_back(m.triangles[f]);  // faces 0..3: the z = 0 and z = 1 squares
    m.triangles = kept;
    const auto r = nf::mesh_report(m);
    EXPECT_EQ(r.boundary_edges, 8u);
    EXPECT_EQ(r.boundary_loops, 2u);
    EXPECT_EQ(nf::mesh_report(cube()).boundary_loops, 0u);
    // two separate open cubes: two loops
    Mesh one = cube();
    one.triangles.erase(one.triangles.begin(), one.triangles.begin() + 2);
    EXPECT_EQ(nf::mesh_report(concat(one,
                                     [&] {
                                         Mesh o = one;
                                         for (Vec3f& p : o.positions) p.x += 3;
                                         return o;
                                     }()))
                  .boundary_loops,
              2u);
}

TEST(MeshReport, TwoTetsSharingAnEdgeGiveOneNonManifoldEdge) {
    Mesh m = tetrahedron();
    m.positions.push_back({1, 1, -1});      // 4
    m.positions.push_back({0.5f, -1, -1});  // 5
    // A second closed tet on vertices {0, 1, 4, 5}; edge {0,1} now has 4 faces.
    const Mesh t2{{}, {{0, 1, 4}, {0, 5, 1}, {0, 4, 5}, {1, 5, 4}}};
    for (Tri t : t2.triangles) m.triangles.push_back(t);
    const auto r = nf::mesh_report(m);
    EXPECT_EQ(r.non_manifold_edges, 1u);
    EXPECT_EQ(r.boundary_edges, 0u);
    EXPECT_EQ(r.non_manifold_vertices, 0u);  // the faces around 0 and 1 are joined through edge {0,1}
    EXPECT_EQ(r.components, 1u);
    EXPECT_FALSE(r.manifold);
    EXPECT_EQ(r.euler_characteristic, 6 - 11 + 8);
}

TEST(MeshReport, TwoCubesSharingAVertexGiveOneNonManifoldVertexAndOneComponent) {
    // Second cube has its corner 0 at the first cube's corner 7 = (1,1,1); exact welding joins them.
    const Mesh m = concat(cube(), cube({1, 1, 1}));
    const auto r = nf::mesh_report(m);
    EXPECT_EQ(r.input_vertices, 16u);
    EXPECT_EQ(r.vertices, 15u);
    EXPECT_EQ(r.non_manifold_vertices, 1u);
    EXPECT_EQ(r.non_manifold_edges, 0u);
    EXPECT_EQ(r.components, 1u);  // vertex-connectivity (see MeshReport::components)
    EXPECT_TRUE(r.closed);
    EXPECT_FALSE(r.manifold);
    EXPECT_EQ(r.euler_characteristic, 15 - 36 + 24);
    EXPECT_NEAR(r.volume, 2.0, 1e-12);
}

TEST(MeshReport, DisjointPiecesAreSeparateComponents) {
    const auto r = nf::mesh_report(concat(cube(), concat(cube({3, 0, 0}), cube({5, 0, 0}))));
    EXPECT_EQ(r.components, 3u);
    EXPECT_EQ(r.euler_characteristic, 6);
}

TEST(MeshReport, FlippedFaceGivesThreeInconsistentEdges) {
    Mesh m = tetrahedron();
    std::swap(m.triangles[3][1], m.triangles[3][2]);
    const auto r = nf::mesh_report(m);
    EXPECT_EQ(r.inconsistent_edges, 3u);
    EXPECT_FALSE(r.oriented);
    EXPECT_TRUE(r.closed);
    EXPECT_TRUE(r.manifold);
}

TEST(MeshReport, DuplicateFacesCountExtraCopiesInAnyOrder) {
    Mesh m = tetrahedron();
    m.triangles.push_back({0, 1, 2});  // face 0 = (0,2,1) with the opposite orientation
    m.triangles.push_back({2, 1, 0});  // face 0 rotated
    const auto r = nf::mesh_report(m);
    EXPECT_EQ(r.duplicate_faces, 2u);
    EXPECT_EQ(r.non_manifold_edges, 3u);  // the three edges of that face now have 4 faces
    EXPECT_EQ(r.boundary_edges, 0u);
}

TEST(MeshReport, DegenerateFaces) {
    Mesh m = tetrahedron();
    m.positions.push_back({2, 0, 0});  // 4: collinear with 0 and 1
    m.positions.push_back({0, 0, 0});  // 5: exact copy of 0
    m.triangles.push_back({0, 1, 4});  // zero area
    m.triangles.push_back({5, 0, 3});  // collapses after welding
    const auto r = nf::mesh_report(m);
    EXPECT_EQ(r.degenerate_faces, 2u);
    EXPECT_EQ(r.collapsed_faces, 1u);
    EXPECT_EQ(r.vertices, 5u);
}

TEST(MeshReport, CollapsedFaceContributesItsEdgeTwice) {
    // A face (a,b,a) uses edge {a,b} in both directions (this is what makes 73342.stl's 12 edges
    // non-manifold in SOURCES.md).
    Mesh m = tetrahedron();
    m.triangles.push_back({0, 1, 0});
    const auto r = nf::mesh_report(m);
    EXPECT_EQ(r.non_manifold_edges, 1u);
    EXPECT_EQ(r.collapsed_faces, 1u);
    EXPECT_EQ(r.duplicate_faces, 0u);
    EXPECT_EQ(r.non_manifold_vertices, 0u);
}

TEST(MeshReport, SoupIsWeldedExactly) {
    const Mesh soup = explode(cube());
    const auto r = nf::mesh_report(soup);
    EXPECT_EQ(r.input_vertices, 36u);
    EXPECT_EQ(r.vertices, 8u);
    expect_clean_closed(r);
    EXPECT_EQ(r.euler_characteristic, 2);
    EXPECT_NEAR(r.volume, 1.0, 1e-12);
}

TEST(MeshReport, NearbyButDifferentPositionsAreNotWelded) {
    Mesh soup = explode(tetrahedron());
    soup.positions[0].x = std::nextafter(0.0f, 1.0f);
    const auto r = nf::mesh_report(soup);
    EXPECT_EQ(r.vertices, 5u);
    EXPECT_EQ(r.boundary_edges, 4u);  // the split corner opens two edges on each side
}

TEST(MeshReport, NegativeZeroWeldsWithPositiveZero) {
    Mesh soup = explode(tetrahedron());
    for (auto& p : soup.positions)
        if (p.x == 0.0f) p.x = -0.0f;
    soup.positions[0].x = 0.0f;
    EXPECT_EQ(nf::mesh_report(soup).vertices, 4u);
}

TEST(MeshReport, UnreferencedVerticesAreCountedButAreNoComponent) {
    Mesh m = tetrahedron();
    m.positions.push_back({7, 7, 7});
    const auto r = nf::mesh_report(m);
    EXPECT_EQ(r.vertices, 5u);
    EXPECT_EQ(r.referenced_vertices, 4u);
    EXPECT_EQ(r.components, 1u);
    EXPECT_EQ(r.euler_characteristic, 2);
    EXPECT_DOUBLE_EQ(r.bbox.max.x, 7.0);
}

TEST(MeshReport, EmptyMesh) {
    const auto r = nf::mesh_report(Mesh{});
    EXPECT_EQ(r.faces, 0u);
    EXPECT_EQ(r.components, 0u);
    EXPECT_FALSE(r.closed);
    EXPECT_TRUE(r.bbox.empty());
}

TEST(MeshReport, InvariantUnderFaceOrderVertexOrderAndCornerRotation) {
    // Property: relabelling vertices, shuffling faces and rotating corners changes no count.
    const Mesh base = concat(concat(cube(), cube({1, 1, 1})), tetrahedron());  // touches, overlaps
    Mesh m = base;
    m.triangles.push_back(m.triangles[3]);            // a duplicate
    std::swap(m.triangles[5][0], m.triangles[5][1]);  // a flip
    const auto ref = nf::mesh_report(m);
    std::mt19937 rng(7);
    for (int trial = 0; trial < 5; ++trial) {
        Mesh p = m;
        std::vector<std::uint32_t> perm(p.positions.size());
        for (std::uint32_t i = 0; i < perm.size(); ++i) perm[i] = i;
        std::shuffle(perm.begin(), perm.end(), rng);
        for (std::size_t i = 0; i < perm.size(); ++i) p.positions[perm[i]] = m.positions[i];
        for (Tri& t : p.triangles) {
            t = {perm[t[0]], perm[t[1]], perm[t[2]]};
            std::rotate(t.begin(), t.begin() + (rng() % 3), t.end());
        }
        std::shuffle(p.triangles.begin(), p.triangles.end(), rng);
        const auto r = nf::mesh_report(p);
        EXPECT_EQ(r.vertices, ref.vertices);
        EXPECT_EQ(r.edges, ref.edges);
        EXPECT_EQ(r.components, ref.components);
        EXPECT_EQ(r.boundary_edges, ref.boundary_edges);
        EXPECT_EQ(r.non_manifold_edges, ref.non_manifold_edges);
        EXPECT_EQ(r.non_manifold_vertices, ref.non_manifold_vertices);
        EXPECT_EQ(r.duplicate_faces, ref.duplicate_faces);
        EXPECT_EQ(r.inconsistent_edges, ref.inconsistent_edges);
        EXPECT_EQ(r.degenerate_faces, ref.degenerate_faces);
        EXPECT_NEAR(r.volume, ref.volume, 1e-9);
    }
}

TEST(WeldExact, KeepsFirstOccurrencesInOrder) {
    Mesh m;
    m.positions = {{1, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}};
    m.triangles = {{2, 4, 3}, {0, 1, 3}};
    std::vector<std::uint32_t> map;
    const Mesh w = nf::weld_exact(m, &map);
    ASSERT_EQ(w.positions.size(), 3u);
    EXPECT_EQ(w.positions[0], (Vec3f{1, 0, 0}));
    EXPECT_EQ(w.positions[1], (Vec3f{0, 0, 0}));
    EXPECT_EQ(w.positions[2], (Vec3f{0, 1, 0}));
    EXPECT_EQ(map, (std::vector<std::uint32_t>{0, 1, 0, 2, 1}));
    EXPECT_EQ(w.triangles[0], (Tri{0, 1, 2}));
    EXPECT_EQ(w.triangles[1], (Tri{0, 1, 2}));
}

TEST(ExactlyCollinear, ExactAnswers) {
    EXPECT_TRUE(nf::exactly_collinear({0, 0, 0}, {1, 1, 1}, {3, 3, 3}));
    EXPECT_TRUE(nf::exactly_collinear({1, 2, 3}, {1, 2, 3}, {4, 5, 6}));  // repeated point
    EXPECT_FALSE(nf::exactly_collinear({0, 0, 0}, {1, 0, 0}, {0, 1, 0}));
    // One ulp off the line.
    const float x = 3.0f, y = std::nextafter(3.0f, 4.0f);
    EXPECT_FALSE(nf::exactly_collinear({0.1f, 0.1f, 0.1f}, {x, x, x}, {x, y, x}));
    EXPECT_TRUE(nf::exactly_collinear({1e7f, 1e7f, 0}, {1e7f + 2, 1e7f + 2, 0}, {1e7f + 4, 1e7f + 4, 0}));
    EXPECT_FALSE(nf::exactly_collinear({1e7f, 1e7f, 0}, {1e7f + 2, 1e7f + 2, 0}, {1e7f + 4, 1e7f + 6, 0}));
}

TEST(MeshReport, BadInputThrows) {
    Mesh m = tetrahedron();
    m.triangles.push_back({0, 1, 9});
    EXPECT_THROW(nf::mesh_report(m), nf::InvalidInput);
    Mesh n = tetrahedron();
    n.positions[2].y = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(nf::mesh_report(n), nf::InvalidInput);
    EXPECT_THROW(nf::weld_exact(n), nf::InvalidInput);
}
