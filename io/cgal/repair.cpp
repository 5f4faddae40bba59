// All CGAL code of repair.h lives in this one translation unit.
#include "io/cgal/repair.h"

#include "core/union_find.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <string>

#include "core/errors.h"
#include "core/mesh_report.h"

namespace normalflow {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Poly = std::array<std::size_t, 3>;

template <class T>
bool collapsed(const T& t) {
    return t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
}

/// Undirected edges of the non-collapsed faces: (min, max, face, reversed), sorted by edge then face.
struct Edge {
    std::size_t a, b, face;
    bool reversed;
};
std::vector<Edge> sorted_edges(const std::vector<Poly>& polys) {
    std::vector<Edge> e;
    e.reserve(3 * polys.size());
    for (std::size_t f = 0; f < polys.size(); ++f) {
        if (collapsed(polys[f])) continue;
        for (int k = 0; k < 3; ++k) {
            const std::size_t a = polys[f][k], b = polys[f][(k + 1) % 3];
            e.push_back({std::min(a, b), std::max(a, b), f, a > b});
        }
    }
    std::sort(e.begin(), e.end(), [](const Edge& x, const Edge& y) {
        return x.a != y.a ? x.a < y.a : (x.b != y.b ? x.b < y.b : x.face < y.face);
    });
    return e;
}

/// Records which polygons orient_polygon_soup reverses (the visitor is copied, so it holds a pointer).
struct ReverseRecorder : PMP::Default_orientation_visitor {
    std::vector<char>* flips = nullptr;
    void polygon_orientation_reversed(std::size_t id) { (*flips)[id] ^= 1; }
};

}  // namespace

std::size_t count_self_intersections(const Mesh& mesh) { return self_intersecting_pairs(mesh).size(); }

std::size_t count_self_intersections_as_written(const Mesh& mesh) {
    return self_intersecting_pairs(mesh, nullptr, false).size();
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> self_intersecting_pairs(const Mesh& mesh,
                                                                             const std::vector<char>* only, bool weld) {
    check_mesh(mesh, "count_self_intersections");
    if (only && only->size() != mesh.triangles.size())
        throw InvalidInput("self_intersecting_pairs: one flag per face expected");
    Mesh welded;
    if (weld) welded = weld_exact(mesh);
    const Mesh& m = weld ? welded : mesh;
    std::vector<Point> pts;
    pts.reserve(m.positions.size());
    for (const auto& p : m.positions) pts.emplace_back(p.x, p.y, p.z);
    const auto& T = m.triangles;

    using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t,
                                                          CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;
    std::vector<Box> boxes;
    boxes.reserve(T.size());
    for (std::size_t f = 0; f < T.size(); ++f) {
        const Tri& t = T[f];
        if (collapsed(t) || CGAL::collinear(pts[t[0]], pts[t[1]], pts[t[2]])) continue;
        boxes.emplace_back(pts[t[0]].bbox() + pts[t[1]].bbox() + pts[t[2]].bbox(), f);
    }
    std::vector<const Box*> ptr, marked;
    ptr.reserve(boxes.size());
    for (const Box& b : boxes) {
        ptr.push_back(&b);
        if (only && (*only)[b.info()]) marked.push_back(&b);
    }

    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    auto test = [&](const Box* x, const Box* y) {
        const Tri& A = T[x->info()];
        const Tri& B = T[y->info()];
        const std::pair<std::uint32_t, std::uint32_t> pair(std::uint32_t(std::min(x->info(), y->info())),
                                                           std::uint32_t(std::max(x->info(), y->info())));
        int ia[3] = {0, 0, 0}, ib[3] = {0, 0, 0}, shared = 0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (A[i] == B[j]) {
                    ia[shared] = i;
                    ib[shared] = j;
                    ++shared;
                }
        if (shared == 3) {  // duplicate face (either orientation)
            pairs.push_back(pair);
            return;
        }
        if (shared == 2) {  // shared edge pq: a fold-over iff r and s are coplanar with it, on the same side
            const Point& p = pts[A[ia[0]]];
            const Point& q = pts[A[ia[1]]];
            const Point& r = pts[A[3 - ia[0] - ia[1]]];
            const Point& s = pts[B[3 - ib[0] - ib[1]]];
            if (CGAL::coplanar(p, q, r, s) && CGAL::coplanar_orientation(p, q, r, s) == CGAL::POSITIVE)
                pairs.push_back(pair);
            return;
        }
        const K::Triangle_3 ta(pts[A[0]], pts[A[1]], pts[A[2]]), tb(pts[B[0]], pts[B[1]], pts[B[2]]);
        if (shared == 1) {  // shared vertex: does the opposite edge of one face meet the other face?
            const K::Segment_3 sa(pts[A[(ia[0] + 1) % 3]], pts[A[(ia[0] + 2) % 3]]);
            const K::Segment_3 sb(pts[B[(ib[0] + 1) % 3]], pts[B[(ib[0] + 2) % 3]]);
            if (CGAL::do_intersect(ta, sb) || CGAL::do_intersect(tb, sa)) pairs.push_back(pair);
            return;
        }
        if (CGAL::do_intersect(ta, tb)) pairs.push_back(pair);
    };
    if (only) {  // the marked faces against all: each pair of two marked faces is found twice
        CGAL::box_intersection_d(
            marked.begin(), marked.end(), ptr.begin(), ptr.end(),
            [&](const Box* x, const Box* y) {
                if (x->info() == y->info()) return;
                if ((*only)[y->info()] && y->info() < x->info()) return;
                test(x, y);
            },
            std::ptrdiff_t(2000));
    } else {
        CGAL::box_self_intersection_d(ptr.begin(), ptr.end(), test, std::ptrdiff_t(2000));
    }
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

RepairReport repair_mesh(Mesh& m, const RepairOptions& opt) {
    check_mesh(m, "repair_mesh");
    RepairReport rep;
    if (m.has_attributes()) {
        m.clear_attributes();
        rep.warnings.push_back("normals, colours and texture coordinates dropped: repair renumbers the vertices");
    }

    std::vector<Point> pts;
    pts.reserve(m.positions.size());
    for (const auto& p : m.positions) pts.emplace_back(p.x, p.y, p.z);
    std::vector<Poly> polys;
    polys.reserve(m.triangles.size());
    for (const Tri& t : m.triangles) polys.push_back({t[0], t[1], t[2]});

    // 1. Exact welding (first occurrence kept, input order).
    if (opt.merge_points) rep.points_merged = PMP::merge_duplicate_points_in_polygon_soup(pts, polys);

    // 2. Degenerate faces: repeated vertex or exactly collinear corners.
    if (opt.remove_degenerate) {
        const auto end = std::remove_if(polys.begin(), polys.end(), [&](const Poly& t) {
            return collapsed(t) || CGAL::collinear(pts[t[0]], pts[t[1]], pts[t[2]]);
        });
        rep.degenerate_removed = static_cast<std::size_t>(polys.end() - end);
        polys.erase(end, polys.end());
    }

    // 3. Duplicate faces (same vertex set): keep the first, preserve the order of the others.
    if (opt.remove_duplicates) {
        std::vector<std::pair<Poly, std::size_t>> keys;
        keys.reserve(polys.size());
        for (std::size_t f = 0; f < polys.size(); ++f) {
            if (collapsed(polys[f])) continue;
            Poly s = polys[f];
            std::sort(s.begin(), s.end());
            keys.emplace_back(s, f);
        }
        std::sort(keys.begin(), keys.end());
        std::vector<char> drop(polys.size(), 0);
        for (std::size_t k = 1; k < keys.size(); ++k)
            if (keys[k].first == keys[k - 1].first) drop[keys[k].second] = 1;
        std::size_t out = 0;
        for (std::size_t f = 0; f < polys.size(); ++f)
            if (!drop[f]) polys[out++] = polys[f];
        rep.duplicates_removed = polys.size() - out;
        polys.resize(out);
    }

    std::vector<char> flipped(polys.size(), 0);
    if (opt.orient && !polys.empty()) {
        // 4. Consistent orientation. CGAL may split non-manifold points; we only take its reversal
        //    decisions and keep our indexing (collapsed faces are left out of the soup it sees).
        std::vector<std::size_t> sub;
        for (std::size_t f = 0; f < polys.size(); ++f)
            if (!collapsed(polys[f])) sub.push_back(f);
        std::vector<Point> opts = pts;
        std::vector<Poly> opolys;
        opolys.reserve(sub.size());
        for (auto f : sub) opolys.push_back(polys[f]);
        std::vector<char> sub_flips(sub.size(), 0);
        ReverseRecorder rec;
        rec.flips = &sub_flips;
        const bool no_split = PMP::orient_polygon_soup(opts, opolys, CGAL::parameters::visitor(rec));
        for (std::size_t i = 0; i < sub.size(); ++i)
            if (sub_flips[i]) {
                std::reverse(polys[sub[i]].begin(), polys[sub[i]].end());
                flipped[sub[i]] ^= 1;
            }
        if (!no_split)
            rep.warnings.push_back("orientation met " + std::to_string(opts.size() - pts.size()) +
                                   " non-manifold or non-orientable point occurrences (left unsplit)");

        // 5. Patches: faces joined across edges with exactly two faces. A closed patch (all of its
        //    edges have two faces) with negative volume is reversed.
        const std::vector<Edge> edges = sorted_edges(polys);
        detail::UnionFind<std::size_t> uf(polys.size());
        std::vector<char> open(polys.size(), 0);
        std::size_t inconsistent = 0;
        for (std::size_t i = 0; i < edges.size();) {
            std::size_t j = i;
            while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b) ++j;
            if (j - i == 2) {
                uf.unite(edges[i].face, edges[i + 1].face);
                if (edges[i].reversed == edges[i + 1].reversed) ++inconsistent;
            } else {
                for (std::size_t k = i; k < j; ++k) open[edges[k].face] = 1;
            }
            i = j;
        }
        rep.orientable = inconsistent == 0;
        if (inconsistent > 0)
            rep.warnings.push_back(std::to_string(inconsistent) +
                                   " edges could not be oriented consistently (non-orientable surface)");
        const Box3d box = bounding_box(m);
        const Vec3d o = box.empty() ? Vec3d{} : box.center();
        std::vector<double> vol(polys.size(), 0.0);
        std::vector<char> patch_open(polys.size(), 0), is_root(polys.size(), 0);
        for (std::size_t f = 0; f < polys.size(); ++f) {
            if (collapsed(polys[f])) continue;
            const std::size_t r = uf.find(f);
            is_root[r] = 1;
            if (open[f]) patch_open[r] = 1;
            const Vec3d a = Vec3d(pts[polys[f][0]].x(), pts[polys[f][0]].y(), pts[polys[f][0]].z()) - o;
            const Vec3d b = Vec3d(pts[polys[f][1]].x(), pts[polys[f][1]].y(), pts[polys[f][1]].z()) - o;
            const Vec3d c = Vec3d(pts[polys[f][2]].x(), pts[polys[f][2]].y(), pts[polys[f][2]].z()) - o;
            vol[r] += dot(a, cross(b, c));
        }
        for (std::size_t r = 0; r < polys.size(); ++r) {
            if (!is_root[r]) continue;
            if (patch_open[r])
                ++rep.open_patches;
            else if (vol[r] < 0)
                ++rep.patches_inverted;
        }
        for (std::size_t f = 0; f < polys.size(); ++f) {
            if (collapsed(polys[f])) continue;
            const std::size_t r = uf.find(f);
            if (!patch_open[r] && vol[r] < 0) {
                std::reverse(polys[f].begin(), polys[f].end());
                flipped[f] ^= 1;
            }
        }
        if (rep.open_patches > 0)
            rep.warnings.push_back(std::to_string(rep.open_patches) +
                                   " open patches: outward orientation not defined, left as oriented");
    }
    rep.faces_reversed = static_cast<std::size_t>(std::count(flipped.begin(), flipped.end(), 1));

    m.positions.resize(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i)
        m.positions[i] =
            Vec3f(static_cast<float>(pts[i].x()), static_cast<float>(pts[i].y()), static_cast<float>(pts[i].z()));
    m.triangles.resize(polys.size());
    for (std::size_t f = 0; f < polys.size(); ++f)
        m.triangles[f] = {static_cast<std::uint32_t>(polys[f][0]), static_cast<std::uint32_t>(polys[f][1]),
                          static_cast<std::uint32_t>(polys[f][2])};
    return rep;
}

}  // namespace normalflow
