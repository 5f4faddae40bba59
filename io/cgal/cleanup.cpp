// All CGAL code of cleanup.h lives in this one translation unit.
#include "io/cgal/cleanup.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_filter.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "io/cgal/repair.h"
#include "sdf/closest_triangle.h"

namespace normalflow::cgal {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
namespace SMS = CGAL::Surface_mesh_simplification;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using SM = CGAL::Surface_mesh<Point>;
using face_descriptor = SM::Face_index;

void check_options(const CleanupOptions& o) {
    auto bad = [](const std::string& what) { throw InvalidInput("cleanup_mesh: " + what); };
    if (!(o.needle_threshold > 1.0)) bad("needle_threshold must be > 1");
    if (!(o.cap_threshold > -1.0 && o.cap_threshold < 0.0)) bad("cap_threshold must be in (-1, 0)");
    if (!(o.min_component_fraction >= 0.0 && o.min_component_fraction < 1.0))
        bad("min_component_fraction must be in [0, 1)");
    if (o.distance_samples_per_face < 0) bad("distance_samples_per_face must be >= 0");
    switch (o.reduction) {
        case CleanupReduction::None: break;
        case CleanupReduction::FaceCount:
            if (o.target_faces < 4) bad("target_faces must be >= 4, got " + std::to_string(o.target_faces));
            break;
        case CleanupReduction::ErrorBound:
            if (!(o.max_error > 0.0) || !std::isfinite(o.max_error)) bad("max_error must be > 0");
            break;
        case CleanupReduction::Remesh:
            if (!(o.target_edge_length > 0.0) || !std::isfinite(o.target_edge_length))
                bad("target_edge_length must be > 0");
            if (o.remesh_iterations < 1) bad("remesh_iterations must be >= 1");
            break;
    }
}

/// Welded, non-collapsed soup -> Surface_mesh (orient_polygon_soup splits non-manifold vertices).
SM to_surface_mesh(const Mesh& in, std::vector<std::string>& warnings) {
    const Mesh w = weld_exact(in);
    std::vector<Point> pts;
    pts.reserve(w.positions.size());
    for (const auto& p : w.positions) pts.emplace_back(p[0], p[1], p[2]);
    std::vector<std::array<std::size_t, 3>> polys;
    polys.reserve(w.triangles.size());
    for (const auto& t : w.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        polys.push_back({t[0], t[1], t[2]});
    }
    const std::size_t npts = pts.size();
    if (!PMP::orient_polygon_soup(pts, polys))
        warnings.push_back("input is not an orientable manifold: " + std::to_string(pts.size() - npts) +
                           " vertices duplicated to make it one");
    SM sm;
    PMP::polygon_soup_to_polygon_mesh(pts, polys, sm);
    return sm;
}

Mesh to_mesh(const SM& sm) {
    Mesh m;
    std::vector<std::uint32_t> index(sm.number_of_vertices() + sm.number_of_removed_vertices(), 0);
    m.positions.reserve(sm.number_of_vertices());
    for (auto v : sm.vertices()) {
        index[v.idx()] = static_cast<std::uint32_t>(m.positions.size());
        const Point& p = sm.point(v);
        m.positions.push_back(Vec3f{static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
    }
    m.triangles.reserve(sm.number_of_faces());
    for (auto f : sm.faces()) {
        Tri t{};
        int k = 0;
        for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
            if (k < 3) t[k] = index[v.idx()];
            ++k;
        }
        if (k == 3) m.triangles.push_back(t);
    }
    return m;
}

/// Edge-connected components below min_faces are removed; returns {components, faces} removed.
std::pair<std::size_t, std::size_t> remove_small_components(SM& sm, std::size_t min_faces) {
    auto fcc = sm.add_property_map<face_descriptor, std::size_t>("f:nf_cc", 0).first;
    const std::size_t n = PMP::connected_components(sm, fcc);
    std::vector<std::size_t> size(n, 0);
    for (auto f : sm.faces()) ++size[fcc[f]];
    std::vector<std::size_t> drop;
    std::size_t faces = 0;
    for (std::size_t c = 0; c < n; ++c)
        if (size[c] < min_faces) {
            drop.push_back(c);
            faces += size[c];
        }
    if (!drop.empty()) PMP::remove_connected_components(sm, drop, fcc);
    sm.remove_property_map(fcc);
    sm.collect_garbage();
    return {drop.size(), faces};
}

/// Signed volume (about the origin of the first vertex) per edge-connected component.
std::vector<double> component_volumes(const SM& sm, const SM::Property_map<face_descriptor, std::size_t>& fcc,
                                      std::size_t n) {
    std::vector<double> vol(n, 0.0);
    for (auto f : sm.faces()) {
        std::array<Point, 3> p;
        int k = 0;
        for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm))
            if (k < 3) p[k++] = sm.point(v);
        const auto a = p[0] - CGAL::ORIGIN, b = p[1] - CGAL::ORIGIN, c = p[2] - CGAL::ORIGIN;
        vol[fcc[f]] += CGAL::scalar_product(a, CGAL::cross_product(b, c)) / 6.0;
    }
    return vol;
}

std::size_t orient_outward(SM& sm, std::vector<std::string>& warnings) {
    if (!CGAL::is_closed(sm)) {
        warnings.push_back("mesh is not closed: outward orientation not defined, left as is");
        return 0;
    }
    auto fcc = sm.add_property_map<face_descriptor, std::size_t>("f:nf_cc", 0).first;
    const std::size_t n = PMP::connected_components(sm, fcc);
    const auto before = component_volumes(sm, fcc, n);
    PMP::orient_to_bound_a_volume(sm);
    const auto after = component_volumes(sm, fcc, n);
    sm.remove_property_map(fcc);
    std::size_t flipped = 0;
    for (std::size_t c = 0; c < n; ++c)
        if ((before[c] < 0) != (after[c] < 0)) ++flipped;
    return flipped;
}

/// Edge-collapse filter for ErrorBound: a collapse is allowed only if every face around the new
/// point stays within max_error of the reference surface at sample points (the new point, and the
/// barycentric points of kFilterBary on each new face, which include the points sampled_hausdorff
/// measures). Distances are exact point-to-triangle distances through the reference's BVH, with the
/// previous answer as hint. Wraps Bounded_normal_change_filter (no face flips).
class SampledDistanceFilter {
public:
    SampledDistanceFilter(const ClosestTriangleQuery& reference, double max_error)
        : ref_(&reference), max_sq_(max_error * max_error) {}

    template <typename Profile>
    boost::optional<typename Profile::Point> operator()(const Profile& profile,
                                                        boost::optional<typename Profile::Point> op) const {
        op = base_(profile, op);
        if (!op) return op;
        const Vec3d p{op->x(), op->y(), op->z()};
        std::uint32_t hint = ClosestHit::kNone;
        if (!near(p, hint)) return boost::none;
        const auto& link = profile.link();
        const auto vpm = profile.vertex_point_map();
        auto pos = [&](auto v) {
            const auto& q = get(vpm, v);
            return Vec3d{q.x(), q.y(), q.z()};
        };
        // The faces after the collapse are (p, link[i-1], link[i]) around the closed link.
        Vec3d a = pos(link.back());
        for (std::size_t i = 0; i < link.size(); ++i) {
            const Vec3d b = pos(link[i]);
            for (const auto& w : kFilterBary) {
                const Vec3d x{w[0] * p[0] + w[1] * a[0] + w[2] * b[0], w[0] * p[1] + w[1] * a[1] + w[2] * b[1],
                              w[0] * p[2] + w[1] * a[2] + w[2] * b[2]};
                if (!near(x, hint)) return boost::none;
            }
            a = b;
        }
        return op;
    }

private:
    // Centroid first (the point most likely to be far), the points sampled_hausdorff uses, then the
    // rest of a step-1/4 barycentric grid (corners excluded; the other two corners are old points).
    static constexpr double kFilterBary[][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3},
                                                {0.6, 0.2, 0.2},
                                                {0.2, 0.6, 0.2},
                                                {0.2, 0.2, 0.6},
                                                {0.5, 0.5, 0.0},
                                                {0.0, 0.5, 0.5},
                                                {0.5, 0.0, 0.5},
                                                {0.5, 0.25, 0.25},
                                                {0.25, 0.5, 0.25},
                                                {0.25, 0.25, 0.5},
                                                {0.75, 0.25, 0.0},
                                                {0.25, 0.75, 0.0},
                                                {0.0, 0.75, 0.25},
                                                {0.0, 0.25, 0.75},
                                                {0.75, 0.0, 0.25},
                                                {0.25, 0.0, 0.75}};
    bool near(const Vec3d& x, std::uint32_t& hint) const {
        const ClosestHit h = ref_->closest_within(x, max_sq_, hint);
        if (!h.found()) return false;
        hint = h.triangle;
        return true;
    }
    const ClosestTriangleQuery* ref_;
    double max_sq_;
    SMS::Bounded_normal_change_filter<> base_;
};

double mean_edge_length(const SM& sm) {
    double s = 0.0;
    std::size_t n = 0;
    for (auto e : sm.edges()) {
        s +=
            std::sqrt(CGAL::squared_distance(sm.point(sm.source(sm.halfedge(e))), sm.point(sm.target(sm.halfedge(e)))));
        ++n;
    }
    return n ? s / static_cast<double>(n) : 0.0;
}

}  // namespace

CleanupReport cleanup_mesh(Mesh& m, const CleanupOptions& opt) {
    const auto t0 = std::chrono::steady_clock::now();
    check_mesh(m, "cleanup_mesh");
    check_options(opt);
    CleanupReport rep;
    rep.faces_before = m.triangles.size();
    rep.vertices_before = m.positions.size();
    if (m.triangles.empty()) throw InvalidInput("cleanup_mesh: mesh has no faces");

    SM sm = to_surface_mesh(m, rep.warnings);

    // 1. Small components (first, so that the reference surface for the distance is the kept part).
    if (opt.min_component_fraction > 0.0) {
        const auto min_faces =
            static_cast<std::size_t>(std::ceil(opt.min_component_fraction * static_cast<double>(sm.number_of_faces())));
        const auto [comps, faces] = remove_small_components(sm, min_faces);
        rep.components_removed = comps;
        rep.faces_in_removed_components = faces;
    }
    const Mesh reference = to_mesh(sm);
    if (reference.triangles.empty()) throw InvalidInput("cleanup_mesh: no face left after removing small components");

    // 2. Degenerate faces, needles and caps.
    if (opt.remove_degenerate) {
        const std::size_t f0 = sm.number_of_faces();
        PMP::remove_degenerate_faces(sm);
        sm.collect_garbage();
        // Collapse only edges shorter than the mean edge length, so the surface barely moves. Not for
        // ErrorBound: on creases it moves the surface by up to a mean edge length (0.007 on fandisk at
        // 128), which no later step could undo; the bounded collapse removes needles within the bound.
        if (opt.reduction != CleanupReduction::ErrorBound) {
            PMP::experimental::remove_almost_degenerate_faces(sm, opt.cap_threshold, opt.needle_threshold,
                                                              mean_edge_length(sm));
            sm.collect_garbage();
        }
        rep.degenerate_removed = f0 - sm.number_of_faces();
    }

    // 3. Outward orientation.
    if (opt.orient_outward) rep.components_reversed = orient_outward(sm, rep.warnings);

    // 4. Reduction.
    switch (opt.reduction) {
        case CleanupReduction::None: break;
        case CleanupReduction::FaceCount: {
            // Count_stop_predicate counts edges: a closed triangle mesh has 3F/2 of them.
            const std::size_t edges = opt.target_faces * 3 / 2;
            if (sm.number_of_edges() > edges) {
                SMS::Count_stop_predicate<SM> stop(edges);
                SMS::Bounded_normal_change_filter<> filter;
                SMS::edge_collapse(sm, stop, CGAL::parameters::filter(filter));
                sm.collect_garbage();
            }
            break;
        }
        case CleanupReduction::ErrorBound: {
            SMS::Count_stop_predicate<SM> stop(0);
            const auto query = make_bvh_query(reference);
            SampledDistanceFilter filter(*query, opt.max_error);
            SMS::edge_collapse(sm, stop, CGAL::parameters::filter(filter));
            sm.collect_garbage();
            break;
        }
        case CleanupReduction::Remesh:
            PMP::isotropic_remeshing(
                faces(sm), opt.target_edge_length, sm,
                CGAL::parameters::number_of_iterations(static_cast<unsigned>(opt.remesh_iterations)));
            sm.collect_garbage();
            break;
    }

    Mesh result = to_mesh(sm);
    if (result.triangles.empty()) throw InvalidInput("cleanup_mesh: no face left");

    // 5. Self-intersections (decimation can fold thin parts through each other): repair locally and keep
    // the repair only if the result stays as closed and manifold as before and has fewer pairs.
    if (opt.repair_self_intersections) {
        const std::size_t before = count_self_intersections(result);
        rep.self_intersections_found = before;
        if (before > 0) {
            SM fixed = sm;
            for (auto v : fixed.vertices()) {  // repair the float positions that will be written
                const Point& q = fixed.point(v);
                fixed.point(v) = Point(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
            }
            bool ok = false;
            try {
                PMP::experimental::remove_self_intersections(fixed, CGAL::parameters::preserve_genus(true));
                fixed.collect_garbage();
                ok = true;
            } catch (const std::exception&) {  // CGAL precondition or hole-filling failure: keep the input
            }
            if (ok) {
                Mesh candidate = to_mesh(fixed);
                const MeshReport a = mesh_report(result), b = mesh_report(candidate);
                // ErrorBound is a promise: a repair that moves the surface beyond it is not kept.
                const bool within =
                    opt.reduction != CleanupReduction::ErrorBound ||
                    sampled_max_distance(candidate, reference, opt.distance_samples_per_face) <= opt.max_error;
                if (!candidate.triangles.empty() && (b.closed || !a.closed) && (b.manifold || !a.manifold) && within &&
                    count_self_intersections(candidate) < before)
                    result = std::move(candidate);
                else
                    rep.warnings.push_back(
                        within ? "self-intersection repair made the mesh worse; kept the unrepaired mesh"
                               : "self-intersection repair would exceed max_error; kept the "
                                 "unrepaired mesh");
            }
        }
    }

    // 6. Checks of the result.
    const MeshReport mr = mesh_report(result);
    rep.closed = mr.closed;
    rep.manifold = mr.manifold;
    if (!mr.closed)
        rep.warnings.push_back("result is not closed (" + std::to_string(mr.boundary_edges) + " boundary edges)");
    if (!mr.manifold)
        rep.warnings.push_back("result is not manifold (" + std::to_string(mr.non_manifold_edges) +
                               " non-manifold edges, " + std::to_string(mr.non_manifold_vertices) +
                               " non-manifold vertices)");
    rep.self_intersections = count_self_intersections(result);
    if (rep.self_intersections > 0)
        rep.warnings.push_back("result has " + std::to_string(rep.self_intersections) +
                               " pairs of self-intersecting faces");
    const SampledDistance d = sampled_hausdorff(result, reference, opt.distance_samples_per_face);
    rep.result_to_input = d.a_to_b;
    rep.input_to_result = d.b_to_a;
    rep.hausdorff = d.hausdorff;

    rep.faces_after = result.triangles.size();
    rep.vertices_after = result.positions.size();
    m = std::move(result);
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return rep;
}

}  // namespace normalflow::cgal
