// nf_bench_decimate: decimation of extracted surfaces, meshoptimizer against CGAL, in one run (issue 22).
//
// For each model: scan-convert at resolution R and extract (pipeline/ smooth_mesh without the
// smoothing stage), then decimate the same extraction to N faces three ways, alternating:
//   quadric  lib/remesh decimate_mesh_qem alone (normalflow's quadric edge collapse),
//   meshopt  io/meshopt decimate_mesh alone (meshoptimizer's simplifier),
//   auto     pipeline/ decimate_mesh with Decimator::Auto (what --target-faces runs: the quadric
//            collapse, the checks and the distances, CGAL where a check fails),
//   cgal     pipeline/ decimate_mesh with Decimator::Cgal (CGAL's edge collapse, the previous default).
// Each row gives the faces, the decimation's seconds (the call's own, checks and distances excluded
// except for "auto", whose checks are part of it), the sampled Hausdorff distance to the extraction in
// voxels (vertices + 3 points per face, both ways), closed, manifold and self-intersecting pairs.
//
// Models (shared/data): pairs_gnf/fandisk_gt.ply (CAD), organic/armadillo.ply, medical/brainmesh_icbm152_lh.ply.
//
// usage: nf_bench_decimate [--data DIR] [--resolution R] [--target-faces N] [--only SUBSTRING]
// Prints a Markdown table.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/mesh_report.h"
#include "io/cgal/repair.h"
#include "io/io.h"
#include "io/meshopt/decimate.h"
#include "metrics/surface_distance.h"
#include "pipeline/pipeline.h"
#include "remesh/decimate.h"

namespace fs = std::filesystem;
using namespace normalflow;

namespace {

double since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Result {
    std::size_t faces = 0, self_intersections = 0;
    double seconds = 0, hausdorff = 0;
    bool closed = false, manifold = false;
    std::string note;
};

Result measure(const Mesh& ext, const Mesh& dec, double seconds) {
    Result r;
    r.faces = dec.triangles.size();
    r.seconds = seconds;
    r.hausdorff = sampled_hausdorff(dec, ext, 3).hausdorff;
    const MeshReport mr = mesh_report(dec);
    r.closed = mr.closed;
    r.manifold = mr.manifold;
    r.self_intersections = count_self_intersections(dec);
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    fs::path data = NORMALFLOW_TEST_DATA;
    int resolution = 256;
    std::size_t target_faces = 20000;
    std::vector<std::string> only;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "nf_bench_decimate: %s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--data")
            data = next();
        else if (a == "--resolution")
            resolution = std::stoi(next());
        else if (a == "--target-faces")
            target_faces = std::stoul(next());
        else if (a == "--only")
            only.push_back(next());
        else {
            std::fprintf(stderr, "nf_bench_decimate: unknown argument %s\n", a.c_str());
            return 2;
        }
    }
    const std::vector<std::string> models = {"pairs_gnf/fandisk_gt.ply", "organic/armadillo.ply",
                                             "medical/brainmesh_icbm152_lh.ply"};
    std::printf("resolution %d, --target-faces %zu; Hausdorff in voxels h (sampled, both ways); 2 cores\n\n",
                resolution, target_faces);
    std::printf(
        "| model | extracted faces | decimator | faces | seconds | Hausdorff (h) | closed, manifold | "
        "self-intersecting pairs | note |\n|---|---|---|---|---|---|---|---|---|\n");
    int failures = 0;
    for (const auto& name : models) {
        bool skip = !only.empty();
        for (const auto& s : only) skip = skip && name.find(s) == std::string::npos;
        if (skip) continue;
        const fs::path in = data / name;
        if (!fs::exists(in)) {
            std::fprintf(stderr, "nf_bench_decimate: %s missing\n", in.string().c_str());
            ++failures;
            continue;
        }
        try {
            PipelineOptions po;
            po.scan.resolution = resolution;
            po.smoothing = false;
            po.connectivity = Connectivity::Remesh;
            const PipelineResult pr = smooth_mesh(read_mesh(in.string()), po);
            const Mesh& ext = pr.mesh;
            const double h = pr.report.scan.grid.voxel_size;

            Mesh q = ext;
            auto t0 = std::chrono::steady_clock::now();
            decimate_mesh_qem(q, {.target_faces = target_faces});
            const Result rq = measure(ext, q, since(t0));

            Mesh a = ext;
            t0 = std::chrono::steady_clock::now();
            meshopt::decimate_mesh(a, {.target_faces = target_faces});
            const Result rm = measure(ext, a, since(t0));

            Mesh b = ext;
            t0 = std::chrono::steady_clock::now();
            const DecimationReport db = decimate_mesh(b, target_faces, Decimator::Auto);
            Result ra = measure(ext, b, since(t0));
            ra.note = db.decimator + (db.fallback.empty() ? "" : " (" + db.fallback + ")") +
                      "; checks and distances included";

            Mesh c = ext;
            const DecimationReport dc = decimate_mesh(c, target_faces, Decimator::Cgal);
            Result rc = measure(ext, c, dc.seconds_decimate);
            rc.note = "cleanup_mesh FaceCount (repairs, edge collapse, self-intersection repair)";

            const std::pair<const char*, const Result*> rows[4] = {
                {"quadric", &rq}, {"meshopt", &rm}, {"auto", &ra}, {"cgal", &rc}};
            for (const auto& [label, r] : rows)
                std::printf("| %s | %zu | %s | %zu | %.2f | %.3f | %s, %s | %zu | %s |\n", name.c_str(),
                            ext.triangles.size(), label, r->faces, r->seconds, r->hausdorff / h,
                            r->closed ? "yes" : "NO", r->manifold ? "yes" : "NO", r->self_intersections,
                            r->note.c_str());
            std::fflush(stdout);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "nf_bench_decimate: %s: %s\n", name.c_str(), e.what());
            ++failures;
        }
    }
    return failures ? 1 : 0;
}
