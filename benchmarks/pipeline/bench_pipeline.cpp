// nf_bench_pipeline: end-to-end scan conversion benchmark (issue 3), through the shipped pipeline
// (pipeline/ smooth_mesh with smoothing off: repair, scan conversion, extraction).
//   nf_bench_pipeline [mesh] [target_triangles] [resolution] [--no-sweep]
// 1. Subdivides a mesh (1-to-4 midpoint) to about target_triangles (default 1M), repairs and voxelizes
//    it at the resolution (default 512) and extracts it again: time per stage, band voxels, peak memory.
// 2. The same model (not subdivided) at resolutions 128, 256, 512, 1024: band voxels, volume bytes
//    and their ratio per doubling (about 4 for a sparse band, 8 for a dense grid).
// Prints Markdown tables. Peak memory is the process's maximum resident set (getrusage), so the
// 1024 row includes everything before it.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>

#include "core/mesh.h"
#include "io/io.h"
#include "pipeline/pipeline.h"

using namespace normalflow;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

double peak_mib() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

Mesh subdivide(const Mesh& m) {
    Mesh out;
    out.positions = m.positions;
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
        const auto key = std::minmax(a, b);
        auto [it, fresh] = mid.try_emplace(key, std::uint32_t(out.positions.size()));
        if (fresh) out.positions.push_back((m.positions[a] + m.positions[b]) * 0.5f);
        return it->second;
    };
    out.triangles.reserve(4 * m.triangles.size());
    for (const Tri& t : m.triangles) {
        const std::uint32_t a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
        out.triangles.push_back({t[0], a, c});
        out.triangles.push_back({t[1], b, a});
        out.triangles.push_back({t[2], c, b});
        out.triangles.push_back({a, b, c});
    }
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string path = argc > 1 ? argv[1] : std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf/fandisk_gt.ply";
    const std::size_t target = argc > 2 ? std::size_t(std::atoll(argv[2])) : 1000000;
    const int res = argc > 3 ? std::atoi(argv[3]) : 512;
    const bool sweep = !(argc > 4 && std::string(argv[4]) == "--no-sweep");
    try {
        const Mesh base = read_mesh(path);
        Mesh m = base;
        double t0 = now();
        while (m.triangles.size() * 4 <= target * 2) m = subdivide(m);  // nearest power of 4 to target
        const double t_sub = now() - t0;

        std::printf("## End to end: %s subdivided to %zu triangles, resolution %d\n\n", path.c_str(),
                    m.triangles.size(), res);
        // The shipped pipeline (smooth_mesh without the smoothing stage): repair, scan conversion
        // with the default distance query, extraction.
        PipelineOptions po;
        po.smoothing = false;
        po.scan.resolution = res;
        const PipelineResult out_result = smooth_mesh(m, po);
        const PipelineReport& rep = out_result.report;
        const Mesh& out = out_result.mesh;
        const ScanConvertReport& sr = rep.scan;
        std::printf("| stage | seconds |\n|---|---|\n");
        std::printf("| subdivide (not counted) | %.2f |\n", t_sub);
        std::printf("| repair | %.2f |\n", rep.seconds.repair);
        std::printf("| scan_convert: candidates + distances + block signs | %.2f |\n", sr.seconds_distance);
        std::printf("| scan_convert: winding-number tree + tile signs | %.2f |\n", sr.seconds_sign);
        std::printf("| voxelize total (memory check, %s query build, scan_convert) | %.2f |\n", to_string(rep.distance),
                    rep.seconds.voxelize);
        std::printf("| extract_surface | %.2f |\n", rep.seconds.extract);
        std::printf("| **end to end (repair + voxelize + extract)** | **%.2f** |\n\n", rep.seconds.total);
        std::printf(
            "grid %d x %d x %d, h = %.4g; band voxels %zu; blocks %zu (of %zu candidates); winding evaluations %zu; "
            "uncertain signs %zu; volume %.1f MiB; output %zu vertices, %zu triangles; peak RSS %.0f MiB\n\n",
            sr.grid.dims[0], sr.grid.dims[1], sr.grid.dims[2], sr.grid.voxel_size, sr.band_voxels, sr.blocks,
            sr.candidate_blocks, sr.winding_evaluations, sr.uncertain_sign, double(sr.memory_bytes) / 1048576.0,
            rep.extract.vertices, rep.extract.triangles, peak_mib());
        (void)out;

        if (!sweep) return 0;
        std::printf("## Resolution sweep: %s (%zu triangles)\n\n", path.c_str(), base.triangles.size());
        std::printf(
            "| resolution | band voxels | ratio | volume MiB | ratio | dense grid MiB | voxelize s | extract s | peak "
            "RSS MiB |\n");
        std::printf("|---|---|---|---|---|---|---|---|---|\n");
        std::size_t prev_band = 0, prev_mem = 0;
        for (int r : {128, 256, 512, 1024}) {
            PipelineOptions ob;
            ob.smoothing = false;
            ob.scan.resolution = r;
            const PipelineResult eb_result = smooth_mesh(base, ob);
            const PipelineReport& pb = eb_result.report;
            const Mesh& eb = eb_result.mesh;
            const ScanConvertReport& rb = pb.scan;
            const double ts = pb.seconds.voxelize, te = pb.seconds.extract;
            const double dense = double(rb.grid.sample_count()) * 4.0 / 1048576.0;
            if (prev_band)
                std::printf("| %d | %zu | %.2f | %.1f | %.2f | %.0f | %.2f | %.2f | %.0f |\n", r, rb.band_voxels,
                            double(rb.band_voxels) / double(prev_band), double(rb.memory_bytes) / 1048576.0,
                            double(rb.memory_bytes) / double(prev_mem), dense, ts, te, peak_mib());
            else
                std::printf("| %d | %zu | - | %.1f | - | %.0f | %.2f | %.2f | %.0f |\n", r, rb.band_voxels,
                            double(rb.memory_bytes) / 1048576.0, dense, ts, te, peak_mib());
            std::fflush(stdout);
            prev_band = rb.band_voxels;
            prev_mem = rb.memory_bytes;
            (void)eb;
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nf_bench_pipeline: %s\n", e.what());
        return 1;
    }
    return 0;
}
