// nf_bench_quality: quality of the normal-map engine on real noisy / ground-truth pairs.
//
// For every pair NAME_<noise>.ply / NAME_gt.ply in shared/data/pairs_gnf and pairs_gcn: run the
// shipped pipeline (pipeline/ smooth_mesh: repair, scan conversion at resolution R along the
// longest side, isotropic and anisotropic smoothing, extraction) on the noisy mesh, and report the distance and the mean normal-angle error to
// the ground truth (surface_distance: points sampled uniformly by area on the result, angle between
// the result's face normal there and the ground truth's face normal at the closest point), next to
// the noisy input. Distances are in voxels of the grid (h = longest side / R).
//
// usage: nf_bench_quality [--data DIR] [--resolution R] [--iterations K] [--mu MU] [--mu-robust C] [--presmooth S]
//                         [--normal-dt DT] [--normal-steps N] [--samples S] [--only SUBSTRING]...
//                         [--modes iso,aniso,floor] [--out DIR] [--threads T]
// (floor: the ground truth scan-converted and extracted without smoothing, the error floor of the grid)
// Prints one table row per pair and mode on stdout (and, with --out DIR, writes the meshes there).

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "io/io.h"
#include "metrics/surface_distance.h"
#include "pipeline/pipeline.h"
#include "study_pairs.h"

namespace fs = std::filesystem;
using namespace normalflow;

namespace {

struct Pair {
    std::string name;  // e.g. pairs_gnf/fandisk_n0.3
    fs::path noisy, truth;
};

std::vector<Pair> find_pairs(const fs::path& data) {
    std::vector<Pair> pairs;
    for (const char* set : {"pairs_gnf", "pairs_gcn"}) {
        const fs::path dir = data / set;
        if (!fs::is_directory(dir)) continue;
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const auto& f : files) {
            const std::string stem = f.stem().string();
            if (f.extension() != ".ply" || stem.ends_with("_gt") || stem.find("result") != std::string::npos) continue;
            const auto us = stem.rfind('_');
            if (us == std::string::npos) continue;
            const fs::path gt = dir / (stem.substr(0, us) + "_gt.ply");
            if (fs::exists(gt)) pairs.push_back({std::string(set) + "/" + stem, f, gt});
        }
    }
    return pairs;
}

}  // namespace

int main(int argc, char** argv) {
    // shared/data beside the checkout (this file is <repo>/benchmarks/pipeline/nf_bench_quality.cpp)
    fs::path data = fs::path(__FILE__).parent_path() / "../../../shared/data";
    int resolution = 256;
    SmoothOptions base;
    SurfaceSamplingOptions sampling;
    sampling.samples = 100000;
    std::vector<std::string> only;
    std::string modes = "iso,aniso";
    fs::path out;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "nf_bench_quality: %s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--data")
            data = next();
        else if (a == "--resolution")
            resolution = std::stoi(next());
        else if (a == "--iterations")
            base.iterations = std::stoi(next());
        else if (a == "--mu")
            base.mu = std::stof(next());
        else if (a == "--mu-robust")
            base.mu_robust = std::stof(next());
        else if (a == "--presmooth")
            base.conductance_presmooth_steps = std::stoi(next());
        else if (a == "--normal-dt")
            base.normal_dt = std::stof(next());
        else if (a == "--normal-steps")
            base.normal_steps = std::stoi(next());
        else if (a == "--samples")
            sampling.samples = std::stoul(next());
        else if (a == "--only")
            only.push_back(next());
        else if (a == "--modes")
            modes = next();
        else if (a == "--out")
            out = next();
        else if (a == "--threads")
            base.threads = std::stoi(next());
        else {
            std::fprintf(stderr, "nf_bench_quality: unknown argument %s\n", a.c_str());
            return 2;
        }
    }
    auto selected = [&](const std::string& key) {
        return ("," + modes + ",").find("," + key + ",") != std::string::npos;
    };
    const std::vector<Pair> pairs = find_pairs(data);
    if (pairs.empty()) {
        std::fprintf(stderr, "nf_bench_quality: no pairs under %s (pairs_gnf, pairs_gcn)\n", data.string().c_str());
        return 1;
    }
    std::printf(
        "resolution %d, iterations %d (0: the mode's default), normal_steps %d, normal_dt %g, mu %g, presmooth %d, "
        "samples %zu\n",
        resolution, base.iterations, base.normal_steps, double(base.normal_dt), double(base.mu),
        base.conductance_presmooth_steps, sampling.samples);
    std::printf("%-28s %-11s %10s %10s %10s %9s %9s\n", "pair", "result", "mean(vox)", "rms(vox)", "haus(vox)",
                "angle(deg)", "seconds");
    std::fflush(stdout);
    int failures = 0;
    for (const Pair& p : pairs) {
        if (!bench::selected(only, p.name)) continue;
        try {
            const Mesh noisy = read_mesh(p.noisy.string());
            const Mesh truth = read_mesh(p.truth.string());
            // The shipped pipeline (pipeline/ smooth_mesh): repair, scan conversion with the default
            // distance query and the band rule, smoothing, extraction.
            PipelineOptions po;
            po.scan.resolution = resolution;
            po.scan.threads = base.threads;
            po.smooth = base;
            PipelineReport pv;
            (void)mesh_to_volume(noisy, po, &pv);
            const double t_vox = pv.seconds.repair + pv.seconds.voxelize;
            const double h = pv.scan.grid.voxel_size;
            auto row = [&](const char* what, const Mesh& m, double secs) {
                const SurfaceDistance d = surface_distance(m, truth, sampling);
                std::printf("%-28s %-11s %10.4f %10.4f %10.3f %9.2f %9.2f\n", p.name.c_str(), what, d.mean / h,
                            d.rms / h, d.hausdorff / h, d.mean_normal_angle_deg, secs);
                std::fflush(stdout);
            };
            row("noisy", noisy, t_vox);
            if (selected("floor")) {  // the ground truth through scan conversion and extraction only
                PipelineOptions pf = po;
                pf.smoothing = false;
                row("gt-voxel", smooth_mesh(truth, pf).mesh, 0.0);
            }
            for (const auto& [key, mode] :
                 {std::pair{"iso", SmoothMode::Isotropic}, std::pair{"aniso", SmoothMode::Anisotropic}}) {
                if (!selected(key)) continue;
                PipelineOptions pm = po;
                pm.smooth.mode = mode;
                const PipelineResult m_result = smooth_mesh(noisy, pm);
                const PipelineReport& pr = m_result.report;
                const Mesh& m = m_result.mesh;
                const double secs = pr.seconds.smooth + pr.seconds.extract;
                const SmoothReport& rep = pr.smooth;
                row(to_string(mode), m, secs);
                if (!out.empty()) {
                    fs::create_directories(out);
                    write_mesh((out / (p.noisy.stem().string() + "_" + key + ".ply")).string(), m);
                }
                if (mode == SmoothMode::Anisotropic) {
                    std::printf("%-28s %-11s mu per iteration:", p.name.c_str(), "");
                    for (const SmoothIteration& it : rep.iterations) std::printf(" %.3f", double(it.mu));
                    std::printf("\n");
                }
            }
        } catch (const std::exception& e) {
            std::fprintf(stderr, "%s: %s\n", p.name.c_str(), e.what());
            ++failures;
        }
    }
    return failures ? 1 : 0;
}
