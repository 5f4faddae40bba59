// The decimation dispatcher of the pipeline (decimate_mesh, pipeline.h): the quadric edge collapse, its result
// checked, CGAL's local repair or edge collapse where a guarantee breaks; meshoptimizer and CGAL on request.
#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "core/stopwatch.h"
#include "metrics/surface_distance.h"
#include "pipeline/pipeline.h"
#include "remesh/decimate.h"
#ifdef NORMALFLOW_HAS_CGAL
#include "io/cgal/repair.h"
#endif
#ifdef NORMALFLOW_HAS_MESHOPT
#include "io/meshopt/decimate.h"
#endif

namespace normalflow {

const char* to_string(Decimator d) {
    switch (d) {
        case Decimator::Auto: return "auto";
        case Decimator::Quadric: return "quadric";
        case Decimator::Meshoptimizer: return "meshoptimizer";
        case Decimator::Cgal: return "cgal";
    }
    return "?";
}

namespace {

/// The first guarantee of `before` that `after` breaks ("" when none): closed, manifold, and
/// (self_intersections >= 0) free of self-intersections.
std::string broken_guarantee(const MeshReport& before, const MeshReport& after, long long self_intersections) {
    if (before.closed && !after.closed)
        return "not closed (" + std::to_string(after.boundary_edges) + " boundary edges)";
    if (before.manifold && !after.manifold)
        return "not manifold (" + std::to_string(after.non_manifold_edges) + " non-manifold edges, " +
               std::to_string(after.non_manifold_vertices) + " non-manifold vertices)";
    if (self_intersections > 0) return std::to_string(self_intersections) + " pairs of self-intersecting faces";
    return "";
}

/// Pairs of intersecting faces as the result is written; -1 in a build without CGAL.
long long pairs_as_written([[maybe_unused]] const Mesh& m) {
#ifdef NORMALFLOW_HAS_CGAL
    return static_cast<long long>(count_self_intersections_as_written(m));
#else
    return -1;
#endif
}

template <class T>
std::string str(T v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g", double(v));
    return buf;
}

}  // namespace

SampledDistance decimation_distance(const Mesh& result, const Mesh& input) {
    // From the input (dense: an extraction has vertices a fraction of a voxel apart) its vertices
    // suffice, from the result 3 more points per face.
    SampledDistance d;
    d.a_to_b = sampled_max_distance(result, input, 3);
    d.b_to_a = sampled_max_distance(input, result, 0);
    d.hausdorff = std::max(d.a_to_b, d.b_to_a);
    return d;
}

DecimationReport decimate_mesh(Mesh& m, std::size_t target_faces, Decimator decimator) {
    if (target_faces < 4) throw InvalidInput("decimate_mesh: target_faces must be >= 4, got " + str(target_faces));
    return decimate_mesh(m, {.target_faces = target_faces, .decimator = decimator});
}

DecimationReport decimate_mesh(Mesh& m, const DecimationOptions& options) {
    Stopwatch clock;
    const std::size_t target_faces = options.target_faces;
    const Decimator decimator = options.decimator;
    check_mesh(m, "decimate_mesh");
    if (m.triangles.empty()) throw InvalidInput("decimate_mesh: empty mesh (no triangles)");
    if (!(options.max_error >= 0) || !std::isfinite(options.max_error))
        throw InvalidInput("decimate_mesh: max_error must be finite and >= 0, got " + str(options.max_error));
    if (target_faces < 4 && !(target_faces == 0 && options.max_error > 0))
        throw InvalidInput("decimate_mesh: target_faces must be >= 4 (or 0 with max_error > 0), got " +
                           str(target_faces));
    if (options.max_error > 0 && decimator == Decimator::Meshoptimizer)
        throw InvalidInput("decimate_mesh: decimator meshoptimizer decimates to a face count only, not to max_error");
#ifndef NORMALFLOW_HAS_MESHOPT
    if (decimator == Decimator::Meshoptimizer)
        throw InvalidInput("decimate_mesh: decimator meshoptimizer: needs a build with meshoptimizer");
#endif
#ifndef NORMALFLOW_HAS_CGAL
    if (decimator == Decimator::Cgal)
        throw InvalidInput("decimate_mesh: decimator cgal: CGAL's edge collapse needs a build with CGAL");
#endif
    DecimationReport rep;
    rep.faces_before = m.triangles.size();
    rep.vertices_before = m.positions.size();
    const MeshReport input = options.input_report ? *options.input_report : mesh_report(m);
    Mesh result;
    bool done = false;
    std::optional<MeshReport> known;  // result's mesh_report where it was measured and the result kept since
    if (decimator == Decimator::Auto || decimator == Decimator::Quadric) {
        Stopwatch t;
        result = m;
        decimate_mesh_qem(result, {.target_faces = target_faces,
                                   .max_error = options.max_error,
                                   .tangent_planes = options.tangent_planes && m.normals.size() == m.positions.size(),
                                   .max_normal_deviation_deg =
                                       m.normals.size() == m.positions.size() ? options.max_normal_deviation_deg : 0});
        rep.seconds_decimate += t.lap();
        rep.decimator = "quadric";
        rep.self_intersections = pairs_as_written(result);
        MeshReport after = mesh_report(result);
#ifdef NORMALFLOW_HAS_CGAL
        // A few pairs of faces decimated through each other (deep folds, thin parts): CGAL's local
        // repair first (cleanup_mesh's self-intersection step alone), kept only if it clears them all
        // and keeps the mesh as closed and manifold as it was.
        if ((decimator == Decimator::Auto || options.local_repair) && rep.self_intersections > 0 &&
            broken_guarantee(input, after, -1).empty()) {
            Mesh repaired = result;
            cgal::CleanupOptions co;
            co.remove_degenerate = false;
            co.orient_outward = false;
            const cgal::CleanupReport cr = cgal::cleanup_mesh(repaired, co);
            const MeshReport ra = mesh_report(repaired);
            if (cr.self_intersections == 0 && broken_guarantee(input, ra, 0).empty()) {
                rep.repaired_self_intersections = std::size_t(rep.self_intersections);
                rep.self_intersections = 0;
                result = std::move(repaired);
                after = ra;
            }
            rep.seconds_decimate += t.lap();
        }
#endif
        known = after;
        const std::string why = broken_guarantee(input, after, rep.self_intersections);
        done = why.empty() || decimator == Decimator::Quadric;
#ifndef NORMALFLOW_HAS_CGAL
        done = true;  // nothing to fall back to: the result is reported as it is
#endif
        if (!done)
            rep.fallback =
                "the quadric decimation's result was " + why + "; decimated with CGAL's edge collapse instead";
    }
#ifdef NORMALFLOW_HAS_MESHOPT
    if (decimator == Decimator::Meshoptimizer) {
        Stopwatch t;
        result = m;
        meshopt::decimate_mesh(result, {.target_faces = target_faces});
        rep.seconds_decimate += t.lap();
        rep.decimator = "meshoptimizer";
        rep.self_intersections = pairs_as_written(result);
        done = true;
    }
#endif
#ifdef NORMALFLOW_HAS_CGAL
    if (!done) {
        Stopwatch t;
        Mesh other = m;
        cgal::CleanupOptions co;
        if (target_faces > 0) {
            co.reduction = cgal::CleanupReduction::FaceCount;
            co.target_faces = target_faces;
        } else {
            co.reduction = cgal::CleanupReduction::ErrorBound;
            co.max_error = options.max_error;
        }
        const cgal::CleanupReport cr = cgal::cleanup_mesh(other, co);
        rep.seconds_decimate += t.lap();
        const long long other_pairs = static_cast<long long>(cr.self_intersections);
        // CGAL's result, unless it breaks more than the quadric one did (at extreme ratios on folded
        // surfaces both can leave intersecting pairs): then the quadric one, with a warning below.
        const bool cgal_better =
            broken_guarantee(input, mesh_report(other), -1).empty() &&
            (other_pairs < rep.self_intersections || !broken_guarantee(input, mesh_report(result), -1).empty());
        if (cgal_better) {
            result = std::move(other);
            known.reset();
            rep.decimator = "cgal";
            rep.self_intersections = other_pairs;
            rep.warnings.insert(rep.warnings.end(), cr.warnings.begin(), cr.warnings.end());
            rep.warnings.push_back(rep.fallback);
        } else {
            rep.fallback = "CGAL's edge collapse left " + std::to_string(other_pairs) +
                           " pairs of self-intersecting faces; the quadric decimation's result is kept";
        }
    }
#endif
    const MeshReport out = known ? *known : mesh_report(result);
    rep.closed = out.closed;
    rep.manifold = out.manifold;
    if (rep.decimator != "cgal") {  // CGAL's cleanup reported its own problems
        const std::string why = broken_guarantee(input, out, rep.self_intersections);
        if (!why.empty()) rep.warnings.push_back("decimated result is " + why);
    }
    if (options.measure_distance) {
        const SampledDistance d = decimation_distance(result, m);
        rep.result_to_input = d.a_to_b;
        rep.input_to_result = d.b_to_a;
        rep.hausdorff = d.hausdorff;
    }
    rep.faces_after = result.triangles.size();
    rep.vertices_after = result.positions.size();
    m = std::move(result);
    rep.seconds = clock.lap();
    return rep;
}

}  // namespace normalflow
