// normalflow's scan conversion against OpenVDB's (issue 3: "use OpenVDB's tree unless a benchmark
// shows a better way"). Same mesh, same voxel size, same band half-width (3 voxels):
//   normalflow: scan_convert (engine BVH distances, generalized winding number sign) into the
//               8³-block Volume;
//   OpenVDB:    tools::meshToLevelSet into a FloatGrid (its own distances, sign by flood fill).
// Prints wall time, active voxels and the bytes each structure holds, as a Markdown table.
// Usage: nf_bench_vs_openvdb [mesh] [resolution...]   (default: shared/data fandisk, 256 512 1024)
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "io/io.h"
#include "sdf/closest_triangle.h"
#include "sdf/scan_convert.h"

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
    using namespace normalflow;
    const std::string path = argc > 1 ? argv[1] : std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf/fandisk_gt.ply";
    std::vector<int> resolutions;
    for (int i = 2; i < argc; ++i) resolutions.push_back(std::atoi(argv[i]));
    if (resolutions.empty()) resolutions = {256, 512, 1024};
    openvdb::initialize();
    const Mesh m = read_mesh(path);
    const Box3d box = bounding_box(m);
    const Vec3d size = box.max - box.min;
    const double longest = std::max({size.x, size.y, size.z});

    std::vector<openvdb::Vec3s> points;
    for (const Vec3f& p : m.positions) points.emplace_back(p.x, p.y, p.z);
    std::vector<openvdb::Vec3I> tris;
    for (const Tri& t : m.triangles) tris.emplace_back(t[0], t[1], t[2]);

    std::printf("## Scan conversion: normalflow vs OpenVDB meshToLevelSet, %s (%zu triangles), band 3 voxels\n\n",
                path.c_str(), m.triangles.size());
    std::printf(
        "| resolution | normalflow s | OpenVDB s | normalflow band voxels | OpenVDB active voxels | "
        "normalflow MiB | OpenVDB MiB |\n|---|---|---|---|---|---|---|\n");
    for (int res : resolutions) {
        const double h = longest / res;
        auto t0 = std::chrono::steady_clock::now();
        const auto q = make_bvh_query(m);
        ScanConvertOptions opt;
        opt.voxel_size = h;
        opt.half_width = 3;
        ScanConvertReport rep;
        const Volume v = scan_convert(m, *q, opt, &rep);
        const double t_nf = seconds_since(t0);

        t0 = std::chrono::steady_clock::now();
        const auto xform = openvdb::math::Transform::createLinearTransform(h);
        const auto grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, points, tris, 3.0f);
        const double t_vdb = seconds_since(t0);
        std::printf("| %d | %.2f | %.2f | %zu | %llu | %.1f | %.1f |\n", res, t_nf, t_vdb, rep.band_voxels,
                    static_cast<unsigned long long>(grid->activeVoxelCount()), v.memory_bytes() / 1048576.0,
                    grid->memUsage() / 1048576.0);
        std::fflush(stdout);
    }
    return 0;
}
