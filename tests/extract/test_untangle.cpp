// Tests of lib/fit/untangle.h: faces folded over along the surface are unfolded by moving their vertices along it.
// Analytic cases (a sphere folded by tangential moves comes back unfolded and on the sphere), then properties (what
// has no fold does not move, open borders stay, thread count), then bad input.
#include "fit/untangle.h"

#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>

#include "core/errors.h"
#include "extract/surface_attributes.h"
#include "normals/volume_fixtures.h"
#include "sdf/sdf_test_meshes.h"

namespace normalflow {
namespace {

const Vec3d kCentre(1.6, 1.6, 1.6);

std::size_t folded(const Mesh& m, const Volume& v) {
    const std::vector<char> a = faces_against_volume(m, v);
    return std::size_t(std::count(a.begin(), a.end(), char(1)));
}

/// An icosphere whose every `every`-th vertex moved along the sphere by `edges` edge lengths (then back onto it):
/// far enough past its neighbours to fold faces over.
Mesh folded_sphere(int every, double edges) {
    Mesh m = test::icosphere(1.0, 4, kCentre);
    const double edge = norm(Vec3d(m.positions[m.triangles[0][1]]) - Vec3d(m.positions[m.triangles[0][0]]));
    for (std::size_t i = 0; i < m.positions.size(); i += std::size_t(every)) {
        const Vec3d r = normalized(Vec3d(m.positions[i]) - kCentre);
        Vec3d t = cross(r, Vec3d(0.3, 1.0, 0.2));
        if (norm(t) < 1e-6) continue;
        t = normalized(t);
        m.positions[i] = Vec3f(kCentre + normalized(r + t * (edges * edge)));
    }
    return m;
}

TEST(Untangle, AFoldedSphereUnfoldsAndStaysOnTheSphere) {
    const Volume v = test::make_volume(64, 0.05, test::sphere_sdf(kCentre, 1.0));
    const Mesh before = folded_sphere(41, 1.6);
    const std::size_t folds = folded(before, v);
    ASSERT_GT(folds, 20u);
    Mesh m = before;
    const UntangleReport r = untangle(m, v, 1.0);
    EXPECT_EQ(r.folded_before, folds);
    EXPECT_EQ(r.folded_after, 0u);
    EXPECT_EQ(folded(m, v), 0u);
    EXPECT_GT(r.passes, 0);
    EXPECT_EQ(m.triangles, before.triangles);
    // along the surface: every vertex within a hundredth of the radius of the sphere (the plane across the gradient
    // leaves it by the square of a move over the diameter)
    for (const Vec3f& p : m.positions) EXPECT_NEAR(norm(Vec3d(p) - kCentre), 1.0, 0.01);
    // along the surface: the moves lie in the planes across the radius (the volume's gradient), not across them
    double along = 0, across = 0;
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        const Vec3d d = Vec3d(m.positions[i]) - Vec3d(before.positions[i]);
        const double radial = std::abs(dot(d, normalized(Vec3d(before.positions[i]) - kCentre)));
        across += radial;
        along += norm(d - normalized(Vec3d(before.positions[i]) - kCentre) *
                              dot(d, normalized(Vec3d(before.positions[i]) - kCentre)));
    }
    EXPECT_LT(across, 0.02 * along) << across << " across, " << along << " along";
    // only around the folds: most vertices where they were
    std::size_t moved = 0;
    for (std::size_t i = 0; i < m.positions.size(); ++i) moved += m.positions[i] != before.positions[i];
    EXPECT_EQ(moved, r.moved);
    EXPECT_LT(moved, m.positions.size() / 2) << r.passes << " passes";
    // the same on one thread and two
    Mesh one = before, two = before;
    tbb::task_arena(1).execute([&] { untangle(one, v, 1.0); });
    tbb::task_arena(2).execute([&] { untangle(two, v, 1.0); });
    EXPECT_EQ(one.positions, two.positions);
    EXPECT_EQ(one.positions, m.positions);
}

TEST(Untangle, AMeshWithoutFoldsIsLeftAsItIs) {
    const Volume v = test::make_volume(64, 0.05, test::sphere_sdf(kCentre, 1.0));
    const Mesh before = test::icosphere(1.0, 4, kCentre);
    Mesh m = before;
    const UntangleReport r = untangle(m, v, 1.0);
    EXPECT_EQ(r.folded_before, 0u);
    EXPECT_EQ(r.passes, 0);
    EXPECT_EQ(r.moved, 0u);
    EXPECT_EQ(m.positions, before.positions);
    // no passes allowed: nothing moves, the folds are counted
    Mesh f = folded_sphere(7, 1.6);
    const Mesh g = f;
    const UntangleReport none = untangle(f, v, 1.0, 0);
    EXPECT_GT(none.folded_before, 0u);
    EXPECT_EQ(none.folded_after, none.folded_before);
    EXPECT_EQ(f.positions, g.positions);
}

TEST(Untangle, FoldsThatDoNotUnfoldStopThePassesAndAreLeftAsTheyWere) {
    // a sphere turned inside out: every face folded against the volume, and no move along the surface turns one
    // back; the passes stop once kUntanglePatience of them in a row unfolded nothing with each of the rings of
    // neighbours, and every vertex goes back
    const Volume v = test::make_volume(64, 0.05, test::sphere_sdf(kCentre, 1.0));
    Mesh inside_out = folded_sphere(41, 1.6);
    for (Tri& t : inside_out.triangles) std::swap(t[1], t[2]);
    const Mesh before = inside_out;
    const UntangleReport r = untangle(inside_out, v, 1.0);
    EXPECT_GT(r.folded_before, before.triangles.size() * 9 / 10);
    EXPECT_EQ(r.folded_after, r.folded_before);
    EXPECT_TRUE(r.undone);
    EXPECT_LE(r.passes, kUntanglePatience * (kUntangleRings + 1) + 1);
    EXPECT_EQ(inside_out.positions, before.positions);
}

TEST(Untangle, OpenBordersStay) {
    const Volume v = test::make_volume(64, 0.05, test::sphere_sdf(kCentre, 1.0));
    Mesh open = folded_sphere(5, 1.6);
    // the faces below the equator's band removed: an open cap with folds along its border too
    std::vector<Tri> kept;
    for (const Tri& t : open.triangles) {
        double z = 0;
        for (const std::uint32_t a : t) z += open.positions[a].z - kCentre.z;
        if (z / 3 > -0.2) kept.push_back(t);
    }
    open.triangles = kept;
    std::vector<char> border(open.positions.size(), 0);
    {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
        for (const Tri& t : open.triangles)
            for (int e = 0; e < 3; ++e)
                edges.emplace_back(std::min(t[std::size_t(e)], t[std::size_t((e + 1) % 3)]),
                                   std::max(t[std::size_t(e)], t[std::size_t((e + 1) % 3)]));
        std::sort(edges.begin(), edges.end());
        for (std::size_t i = 0; i < edges.size(); ++i)
            if ((i == 0 || edges[i] != edges[i - 1]) && (i + 1 == edges.size() || edges[i] != edges[i + 1]))
                border[edges[i].first] = border[edges[i].second] = 1;
    }
    ASSERT_GT(std::count(border.begin(), border.end(), char(1)), 20);
    const Mesh before = open;
    const UntangleReport r = untangle(open, v, 1.0);
    EXPECT_GT(r.folded_before, 0u);
    EXPECT_LT(r.folded_after, r.folded_before);
    for (std::size_t i = 0; i < open.positions.size(); ++i) {
        if (!border[i]) continue;
        EXPECT_EQ(open.positions[i], before.positions[i]) << i;
    }
}

TEST(Untangle, BadInputIsRefused) {
    const Volume v = test::make_volume(16, 0.2, test::sphere_sdf(kCentre, 1.0));
    Mesh m = test::icosphere(1.0, 2, kCentre);
    EXPECT_THROW(untangle(m, v, 1.0, -1), InvalidInput);
    Mesh broken = m;
    broken.triangles.push_back({0, 1, std::uint32_t(m.positions.size())});  // an index past the positions
    EXPECT_THROW(untangle(broken, v, 1.0), InvalidInput);
    EXPECT_THROW(untangle(m, Volume{}, 1.0), InvalidInput);
}

}  // namespace
}  // namespace normalflow
