// Sharp features on the extraction (issue 22): the clean CAD models scanned at a resolution and extracted, then
// their vertices moved onto the features of a reference surface (sharpen_mesh), against the true model.
//   nf_bench_sharpen [resolution=256] [models...]
// Columns: mean normal angle and Hausdorff distance (voxels) to the true model, triangles, self-intersecting
// pairs, degenerate faces, seconds.
#include <cstdio>
#include <string>
#include <vector>

#include "core/mesh_report.h"
#include "core/stopwatch.h"
#include "io/cgal/repair.h"
#include "io/io.h"
#include "metrics/compare.h"
#include "pipeline/pipeline.h"
#include "remesh/sharpen.h"
#include "sdf/closest_triangle.h"

using namespace normalflow;

namespace {

void row(const char* model, const char* what, const Mesh& m, const Mesh& gt, double h, double seconds) {
    CompareOptions co;
    const MeshComparison c = compare_meshes(m, gt, co);
    const MeshReport r = mesh_report(m);
    std::printf("| %s | %s | %.3f° | %.3f | %zu | %zu | %zu | %s | %.2f |\n", model, what,
                c.distance.mean_normal_angle_deg, c.distance.hausdorff / h, m.triangles.size(),
                count_self_intersections(m), r.degenerate_faces, r.closed && r.manifold ? "yes" : "no", seconds);
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
    const int resolution = argc > 1 ? std::stoi(argv[1]) : 256;
    std::vector<std::string> models;
    for (int i = 2; i < argc; ++i) models.push_back(argv[i]);
    if (models.empty()) models = {"fandisk", "block", "twelve", "trimstar", "sharpsphere"};
    std::printf(
        "| model | surface | mean normal angle | Hausdorff (voxels) | triangles | self-intersecting pairs | "
        "degenerate faces | closed, manifold | seconds |\n|---|---|---|---|---|---|---|---|---|\n");
    // the clean CAD models re-meshed as `normalflow remesh` does (smooth_mesh without smoothing)
    for (const std::string& name : models) {
        const Mesh gt = read_mesh(std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf/" + name + "_gt.ply");
        for (const bool decimated : {false, true})
            for (const bool sharpen : {false, true}) {
                PipelineOptions o;
                o.smoothing = false;
                o.connectivity = Connectivity::Remesh;
                o.scan.resolution = resolution;
                o.sharpen = sharpen;
                const double h0 = mesh_to_volume(gt,
                                                 [&] {
                                                     PipelineOptions p = o;
                                                     p.sharpen = false;
                                                     p.scan.half_width = 1;
                                                     return p;
                                                 }())
                                      .grid.voxel_size;
                if (decimated) o.max_error = 0.03 * h0;
                Stopwatch clock;
                const PipelineResult r = smooth_mesh(gt, o);
                const std::string what =
                    std::string(sharpen ? "remesh" : "remesh --no-sharpen") +
                    (decimated ? " --max-error 0.03 voxel" : "") +
                    (sharpen ? " (restored " + std::to_string(r.report.sharpen_restored) + ")" : "");
                row(name.c_str(), what.c_str(), r.mesh, gt, h0, clock.seconds());
            }
    }
    // the smoothed noisy pairs: sharpened to the smoothed volume (its gradient, or the engine's filtered normal map)
    for (const char* pair : {"fandisk_n0.3", "block_n0.4"}) {
        const std::string name(pair);
        const Mesh gt =
            read_mesh(std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf/" + name.substr(0, name.find('_')) + "_gt.ply");
        const Mesh noisy = read_mesh(std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf/" + name + ".ply");
        PipelineOptions o;
        o.connectivity = Connectivity::Remesh;
        PipelineReport r;
        Volume v = mesh_to_volume(noisy, o, &r);
        NormalMap map;
        smooth_volume_stage(v, o, noisy, &r, nullptr, &map);
        const double h = v.grid.voxel_size;
        Stopwatch clock;
        const Mesh e = volume_to_mesh(v, o);
        row(pair, "smoothed (default), re-meshed", e, gt, h, clock.lap());
        for (int with_map = 0; with_map < 2; ++with_map) {
            Mesh s = e;
            SharpenOptions so;
            so.max_move = h;
            clock.lap();
            sharpen_mesh(s, volume_probe(v, with_map ? &map : nullptr), so);
            row(pair, with_map ? "sharpened to the volume, filtered normal map" : "sharpened to the volume, grad phi",
                s, gt, h, clock.lap());
        }
    }
}
