// nf_bench_study [DATA_DIR] [--samples N] [--csv FILE]: the mesh-side baselines on the noisy/ground-truth
// pairs of shared/data/pairs_gnf (X_gt.ply and X_<noise>.ply). For each noisy mesh: Taubin at its best
// iteration count (the one with the lowest mean distance to the ground truth, an oracle choice in
// Taubin's favour), plain Laplacian (10 steps), bilateral normal filtering (defaults), and the noisy
// input itself. Prints a Markdown table: distance and normal-angle error vs ground truth, time.
// normalflow's own rows are added by the pipeline benchmark. Not part of the test suite.
#include <algorithm>
#include <cmath>
#include <utility>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "io/formats/atomic_file.h"
#include "io/io.h"
#include "io/openmesh/smoothing.h"
#include "metrics/compare.h"

namespace fs = std::filesystem;
using namespace normalflow;

namespace {

struct Row {
    std::string model, noisy, method, params;
    double ms = 0;
    MeshComparison c;
};

/// Torus about z (major R, minor r), nu × nv quads; grade > 0 clusters the u samples (same shape,
/// another triangulation).
Mesh torus(double R, double r, int nu, int nv, double grade) {
    Mesh m;
    const double pi = 3.14159265358979323846;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double t = double(i) / nu;
            const double u = 2 * pi * (t + grade * std::sin(2 * pi * t) / (2 * pi));
            const double v = 2 * pi * j / nv;
            m.positions.push_back(Vec3f(Vec3d((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                                              r * std::sin(v))));
        }
    auto id = [&](int i, int j) { return std::uint32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return m;
}

/// Largest and RMS distance of the vertices of m from the exact torus.
std::pair<double, double> torus_error(const Mesh& m, double R, double r) {
    double mx = 0, s2 = 0;
    for (const Vec3f& pf : m.positions) {
        const Vec3d p(pf);
        const double d = std::abs(std::hypot(std::hypot(p.x, p.y) - R, p.z) - r);
        mx = std::max(mx, d);
        s2 += d * d;
    }
    return {mx, std::sqrt(s2 / double(m.positions.size()))};
}

double now_ms() {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
    std::string data = std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf";
    std::string csv_path;
    CompareOptions co;
    co.sampling.samples = 50000;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--samples" && i + 1 < argc) co.sampling.samples = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--csv" && i + 1 < argc) csv_path = argv[++i];
        else data = a;
    }
    if (!fs::is_directory(data)) {
        std::fprintf(stderr, "nf_bench_study: %s: no such folder\n", data.c_str());
        return 1;
    }
    std::vector<fs::path> noisy_files;
    for (const auto& e : fs::directory_iterator(data)) {
        const std::string n = e.path().filename().string();
        if (e.path().extension() == ".ply" && n.find("_gt") == std::string::npos && n.find("result") == std::string::npos)
            noisy_files.push_back(e.path());
    }
    std::sort(noisy_files.begin(), noisy_files.end());

    std::vector<Row> rows;
    try {
        for (const fs::path& np : noisy_files) {
            const std::string stem = np.stem().string();
            const std::string model = stem.substr(0, stem.find('_'));
            const fs::path gp = np.parent_path() / (model + "_gt.ply");
            if (!fs::exists(gp)) continue;
            const Mesh gt = read_mesh(gp.string());
            const Mesh noisy = read_mesh(np.string());
            auto add = [&](const std::string& method, const std::string& params, double ms, const Mesh& m) {
                rows.push_back({model, stem, method, params, ms, compare_meshes(m, gt, co)});
                const Row& r = rows.back();
                std::fprintf(stderr, "%s %s %s: mean/diag %.3e, normal %.2f deg, %.1f ms\n", stem.c_str(), method.c_str(),
                             params.c_str(), r.c.mean_relative, r.c.distance.mean_normal_angle_deg, ms);
            };
            add("noisy input", "", 0, noisy);

            // Taubin: best iteration count by mean distance to the ground truth.
            Row best;
            bool have = false;
            for (int k : {1, 2, 3, 5, 8, 12, 20, 30, 50}) {
                Mesh m = noisy;
                TaubinOptions o;
                o.iterations = k;
                const double t0 = now_ms();
                taubin_smooth(m, o);
                const double ms = now_ms() - t0;
                MeshComparison c = compare_meshes(m, gt, co);
                if (!have || c.distance.mean < best.c.distance.mean) {
                    best = {model, stem, "Taubin λ|μ (best K)", "K=" + std::to_string(k), ms, c};
                    have = true;
                }
            }
            rows.push_back(best);

            Mesh lap = noisy;
            double t0 = now_ms();
            laplacian_smooth(lap, {});
            add("Laplacian", "λ=0.5, 10 steps", now_ms() - t0, lap);

            Mesh bil = noisy;
            t0 = now_ms();
            bilateral_normal_filter(bil, {});
            add("bilateral normal", "20+10 it., σr=0.35", now_ms() - t0, bil);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nf_bench_study: %s\n", e.what());
        return 1;
    }

    std::string md =
        "| noisy mesh | method | parameters | ms | mean dist / diag | RMS / diag | Hausdorff / diag | normal angle ° | "
        "volume Δ | crease kept |\n|---|---|---|---|---|---|---|---|---|---|\n";
    std::string csv = "noisy,method,parameters,ms,mean_relative,rms_relative,hausdorff_relative,mean_normal_angle_deg,"
                      "volume_change,crease_preservation\n";
    for (const Row& r : rows) {
        char buf[512];
        std::snprintf(buf, sizeof buf, "| %s | %s | %s | %.1f | %.3e | %.3e | %.3e | %.2f | %+.2f%% | %.1f%% |\n",
                      r.noisy.c_str(), r.method.c_str(), r.params.c_str(), r.ms, r.c.mean_relative, r.c.rms_relative,
                      r.c.hausdorff_relative, r.c.distance.mean_normal_angle_deg, 100 * r.c.volume_change,
                      100 * r.c.crease.fraction);
        md += buf;
        std::snprintf(buf, sizeof buf, "%s,\"%s\",\"%s\",%.3f,%.6e,%.6e,%.6e,%.4f,%.6f,%.4f\n", r.noisy.c_str(),
                      r.method.c_str(), r.params.c_str(), r.ms, r.c.mean_relative, r.c.rms_relative, r.c.hausdorff_relative,
                      r.c.distance.mean_normal_angle_deg, r.c.volume_change, r.c.crease.fraction);
        csv += buf;
    }
    std::printf("%s", md.c_str());

    // The same shape meshed two ways: Taubin (uniform weights) depends on the triangulation. A torus
    // (R = 1, r = 0.4) sampled uniformly and with graded u spacing; both smoothed with Taubin K = 20.
    {
        const double R = 1.0, r = 0.4;
        const Mesh a0 = torus(R, r, 96, 48, 0.0), b0 = torus(R, r, 96, 48, 0.6);
        Mesh a = a0, b = b0;
        TaubinOptions o;
        o.iterations = 20;
        taubin_smooth(a, o);
        taubin_smooth(b, o);
        const auto ea = torus_error(a, R, r), eb = torus_error(b, R, r);
        const MeshComparison ab = compare_meshes(b, a, co);
        std::printf("\nTriangulation dependence (torus R=1, r=0.4, 96x48, Taubin K=20, uniform weights):\n\n"
                    "| triangulation | max vertex distance to the torus | RMS |\n|---|---|---|\n"
                    "| uniform | %.3e | %.3e |\n| graded (u clustered) | %.3e | %.3e |\n\n"
                    "Hausdorff between the two results: %.3e (%.3e of the diagonal)\n",
                    ea.first, ea.second, eb.first, eb.second, ab.distance.hausdorff, ab.hausdorff_relative);
    }
    if (!csv_path.empty()) {
        AtomicFile f(csv_path, "nf_bench_study");
        f.write(csv);
        f.commit();
    }
    return 0;
}
