// bench_normals: seconds per main iteration of the normal-map engine (smooth_volume: 25 normal
// steps + refit + band move/reinitialisation) and its peak memory against the band size.
//
// Cases: fandisk and bunny (shared/data/pairs_gnf, ground truth) scan-converted at resolution 256,
// and a 221×221×161 volume as in Tasdizen et al. 2003 (a noisy sphere of radius 70 voxels, analytic,
// so it runs without the test data), each with 1 and 2 threads, isotropic, anisotropic (the
// defaults) and paper25 (anisotropic, 25 normal steps, no conductance pre-smoothing: the issue's
// definition of a main iteration).
// Counters: s_per_iter (wall seconds of the main iteration, from SmoothReport), band_voxels
// (samples processed), allocated_voxels, peak_MiB (rise of the process's peak RSS during the run,
// Linux: reset through /proc/self/clear_refs) and bytes_per_band_voxel.
// The comparison with ITK's implementation of the same paper (AnisotropicFourthOrderLevelSetImageFilter)
// is benchmarks/itk/nf_bench_vs_itk, built with -DNORMALFLOW_WITH_ITK=ON where ITK is installed (libinsighttoolkit5-dev).
//
// usage: bench_normals [--benchmark_filter=...]   e.g. --benchmark_filter='anisotropic|paper25'    (the models are skipped if shared/data is missing)

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>

#include "core/mesh.h"
#include "core/volume.h"
#include "engine_variants.h"
#include "io/io.h"
#include "normals/smooth.h"
#include "sdf/scan_convert.h"
#include "sdf/triangle_bvh.h"

namespace fs = std::filesystem;
using namespace normalflow;

namespace {

fs::path data_dir() { return fs::path(__FILE__).parent_path() / "../../../shared/data"; }

/// kB of a field of /proc/self/status ("VmHWM", "VmRSS"); 0 where unavailable.
long status_kb(const std::string& field) {
    std::ifstream f("/proc/self/status");
    std::string key;
    while (f >> key) {
        if (key == field + ":") {
            long kb = 0;
            f >> kb;
            return kb;
        }
        std::string rest;
        std::getline(f, rest);
    }
    return 0;
}

/// Resets the peak RSS to the current RSS (Linux >= 4.0); false where not possible.
bool reset_peak_rss() {
    std::ofstream f("/proc/self/clear_refs");
    if (!f) return false;
    f << "5";
    return bool(f);
}

/// A noisy sphere of radius 70 voxels in a 221×221×161 grid (h = 1), band of 3 voxels.
Volume paper_volume() {
    Grid g;
    g.dims = {221, 221, 161};
    Volume v(g, 3.0f);
    const double cx = 110.3, cy = 110.6, cz = 80.2, r = 70.0;
    for (int bk = 0; bk < v.block_dims[2]; ++bk)
        for (int bj = 0; bj < v.block_dims[1]; ++bj)
            for (int bi = 0; bi < v.block_dims[0]; ++bi) {
                const double dx = bi * 8 + 3.5 - cx, dy = bj * 8 + 3.5 - cy, dz = bk * 8 + 3.5 - cz;
                const double d = std::sqrt(dx * dx + dy * dy + dz * dz) - r;
                if (std::abs(d) > 3.0 + 7.0) {
                    v.block_table[v.table_index(bi, bj, bk)] = d < 0 ? kBlockInside : kBlockOutside;
                    continue;
                }
                for (int z = 0; z < 8; ++z)
                    for (int y = 0; y < 8; ++y)
                        for (int x = 0; x < 8; ++x) {
                            const int i = bi * 8 + x, j = bj * 8 + y, k = bk * 8 + z;
                            if (!g.contains(i, j, k)) continue;
                            std::uint32_t hsh = std::uint32_t(i) * 73856093u ^ std::uint32_t(j) * 19349663u ^
                                                std::uint32_t(k) * 83492791u;
                            hsh = (hsh ^ (hsh >> 13)) * 0x5bd1e995u;
                            const double noise = 0.3 * (double(hsh & 0xFFFF) / 65535.0 * 2.0 - 1.0);
                            const double px = i - cx, py = j - cy, pz = k - cz;
                            const double s = std::sqrt(px * px + py * py + pz * pz) - r + noise;
                            v.set(i, j, k, float(std::clamp(s, -3.0, 3.0)));
                        }
            }
    return v;
}

/// Volumes by name, built once ("" when the model is missing).
const Volume* volume(const std::string& name) {
    static std::map<std::string, std::unique_ptr<Volume>> cache;
    auto it = cache.find(name);
    if (it != cache.end()) return it->second.get();
    std::unique_ptr<Volume> v;
    if (name == "paper221x221x161") {
        v = std::make_unique<Volume>(paper_volume());
    } else {
        const fs::path p = data_dir() / "pairs_gnf" / (name + "_gt.ply");
        if (fs::exists(p)) {
            const Mesh m = read_mesh(p.string());
            ScanConvertOptions so;
            so.resolution = 256;
            so.half_width = 3.0f;
            v = std::make_unique<Volume>(scan_convert(m, *make_bvh_query(m), so));
        }
    }
    return (cache[name] = std::move(v)).get();
}

using bench::options_for;

void BM_MainIteration(benchmark::State& state, const std::string& name, const std::string& variant) {
    const Volume* src = volume(name);
    if (!src) {
        state.SkipWithError(("missing model " + name + " (shared/data/pairs_gnf)").c_str());
        return;
    }
    SmoothOptions o = options_for(variant);
    o.iterations = 1;
    o.threads = int(state.range(0));
    SmoothReport rep;
    double peak_mib = 0;
    for (auto _ : state) {
        Volume v = *src;
        const long rss0 = status_kb("VmRSS");
        const bool peak_ok = reset_peak_rss();
        rep = smooth_volume(v, o);
        if (peak_ok) peak_mib = double(status_kb("VmHWM") - rss0) / 1024.0;
        state.SetIterationTime(rep.iterations.at(0).seconds);
        benchmark::DoNotOptimize(v.values.data());
    }
    const double band = double(rep.iterations.at(0).band_voxels);
    state.counters["s_per_iter"] = rep.iterations.at(0).seconds;
    state.counters["s_normals"] = rep.seconds_normals;
    state.counters["s_refit"] = rep.seconds_refit;
    state.counters["s_reinit"] = rep.seconds_reinit;
    state.counters["refit_steps"] = rep.iterations.at(0).refit_steps;
    state.counters["band_voxels"] = band;
    state.counters["allocated_voxels"] = double(rep.iterations.at(0).allocated_voxels);
    state.counters["peak_MiB"] = peak_mib;
    state.counters["bytes_per_band_voxel"] = peak_mib * 1024.0 * 1024.0 / band;
}

void register_all() {
    for (const char* name : {"fandisk", "bunny", "paper221x221x161"})
        for (const char* variant : {"isotropic", "anisotropic", "paper25"})
            benchmark::RegisterBenchmark(
                (std::string("MainIteration/") + name + "/" + variant).c_str(),
                [n = std::string(name), m = std::string(variant)](benchmark::State& s) { BM_MainIteration(s, n, m); })
                ->ArgName("threads")
                ->Arg(1)
                ->Arg(2)
                ->Iterations(1)
                ->UseManualTime()
                ->Unit(benchmark::kSecond);
}

}  // namespace

int main(int argc, char** argv) {
    register_all();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
