// nf_ab_engine: two builds of the engine (libnormalflow_core.so) timed against each other in one
// process, their runs interleaved (A B B A A B ...), on the same volume.
//
//   nf_ab_engine LIB_A LIB_B [--mesh PATH] [--resolution 256] [--runs 8] [--threads 1]
//                [--mode paper25|isotropic|anisotropic|highboost|mcf|second_order] [--iterations 1]
//
// The modes are the variants of engine_variants.h; together they take every path of the engine, so
// a refactoring that must not change the results is checked with each (use --iterations 2: paper25
// stops after its first main iteration by design).
//
// On shared machines the speed drifts by ±15 % between runs minutes apart, more than most changes
// to a kernel gain; runs interleaved within one process see the same drift, and the minimum and the
// median over several runs resolve differences of a few per cent. Each library is dlopen'ed with
// RTLD_LOCAL (copy the old build's library aside first, e.g. cp B/lib/libnormalflow_core.so /tmp/old.so)
// and its smooth_volume is called on a copy of one scan-converted volume. Prints the minimum and the
// median of the wall seconds of the normal loop, the refit, the band moves and reinitialisations and
// the main iteration, B / A, and whether the two builds returned the same φ bit for bit (else the
// largest difference, in voxels).
// Needs the engine built as a shared library (the default build here).
#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"
#include "engine_variants.h"
#include "io/io.h"
#include "normals/smooth.h"
#include "sdf/scan_convert.h"
#include "sdf/triangle_bvh.h"

using namespace normalflow;

namespace {

using SmoothFn = decltype(&smooth_volume);  // the signature of this tree's smooth_volume

SmoothFn load(const char* path) {
    void* h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        std::fprintf(stderr, "nf_ab_engine: %s: %s\n", path, dlerror());
        std::exit(1);
    }
    // normalflow::smooth_volume(Volume&, SmoothOptions const&, Progress*, NormalMap*, SmoothCheckpoint const*):
    // a library built before that signature (the normal map and the checkpoint came in December) has none.
    void* f = dlsym(h,
                    "_ZN10normalflow13smooth_volumeERNS_6VolumeERKNS_13SmoothOptionsEPNS_8ProgressEPSt5arrayIS0_Lm3EEP"
                    "KSt8functionIFbRKS0_EE");
    if (!f) {
        std::fprintf(stderr, "nf_ab_engine: %s: no normalflow::smooth_volume of this signature\n", path);
        std::exit(1);
    }
    return reinterpret_cast<SmoothFn>(f);
}

double median(std::vector<double> x) {
    std::sort(x.begin(), x.end());
    return x[x.size() / 2];
}
double minimum(const std::vector<double>& x) { return *std::min_element(x.begin(), x.end()); }

}  // namespace

int main(int argc, char** argv) {
    std::string mesh_path = std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf/fandisk_n0.3.ply";
    std::string mode = "paper25";
    int resolution = 256, runs = 8, threads = 1, iterations = 1;
    std::vector<const char*> libs;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        const auto next = [&]() -> const char* {
            if (a + 1 >= argc) {
                std::fprintf(stderr, "nf_ab_engine: %s needs a value\n", arg.c_str());
                std::exit(2);
            }
            return argv[++a];
        };
        if (arg == "--mesh")
            mesh_path = next();
        else if (arg == "--resolution")
            resolution = std::atoi(next());
        else if (arg == "--runs")
            runs = std::atoi(next());
        else if (arg == "--threads")
            threads = std::atoi(next());
        else if (arg == "--iterations")
            iterations = std::atoi(next());
        else if (arg == "--mode")
            mode = next();
        else if (!arg.empty() && arg[0] == '-') {
            std::fprintf(stderr, "nf_ab_engine: unknown option %s (see the comment at the top of ab_engine.cpp)\n",
                         arg.c_str());
            return 2;
        } else
            libs.push_back(argv[a]);
    }
    if (libs.size() != 2 || resolution < 8 || runs < 1 || threads < 0 || iterations < 1 || !bench::is_variant(mode)) {
        std::fprintf(stderr,
                     "usage: nf_ab_engine LIB_A LIB_B [--mesh PATH] [--resolution N] [--runs N] "
                     "[--threads N] [--mode paper25|isotropic|anisotropic|highboost|mcf|second_order] "
                     "[--iterations N]\n");
        return 2;
    }
    const SmoothFn fn[2] = {load(libs[0]), load(libs[1])};
    try {
        const Mesh mesh = read_mesh(mesh_path);
        const auto query = make_bvh_query(mesh);
        ScanConvertOptions so;
        so.resolution = resolution;
        const Volume input = scan_convert(mesh, *query, so, nullptr);
        SmoothOptions o = bench::options_for(mode);
        o.iterations = iterations;
        o.threads = threads;
        std::vector<double> normals[2], refit[2], reinit[2], per_iteration[2];
        Volume result[2];
        for (int r = 0; r < runs; ++r)
            for (int e = 0; e < 2; ++e) {
                const int w = (r % 2) ? 1 - e : e;  // A B, B A, A B, ...
                Volume v = input;
                const SmoothReport rep = fn[w](v, o, nullptr, nullptr, nullptr);
                double total = 0;
                for (const SmoothIteration& it : rep.iterations) total += it.seconds;
                normals[w].push_back(rep.seconds_normals / iterations);
                refit[w].push_back(rep.seconds_refit / iterations);
                reinit[w].push_back(rep.seconds_reinit / iterations);
                per_iteration[w].push_back(total / iterations);
                if (r == 0) result[w] = std::move(v);
            }
        std::printf("%s, resolution %d, %s, %d thread(s), %d run(s) each, interleaved\n\n", mesh_path.c_str(),
                    resolution, mode.c_str(), threads, runs);
        std::printf(
            "Wall seconds per main iteration, min / median; the band moves and reinitialisations include the "
            "one before the first iteration.\n\n");
        std::printf(
            "| build | normal loop | refit | band move + reinitialisation | main iteration |\n|---|---|---|---|---|\n");
        const std::vector<double>* cols[4] = {normals, refit, reinit, per_iteration};
        for (int e = 0; e < 2; ++e) {
            std::printf("| %s %s", e ? "B" : "A", libs[e]);
            for (const auto* c : cols) std::printf(" | %.3f / %.3f", minimum(c[e]), median(c[e]));
            std::printf(" |\n");
        }
        std::printf("| B / A");
        for (const auto* c : cols)
            std::printf(" | %.3f / %.3f", minimum(c[1]) / std::max(minimum(c[0]), 1e-9),
                        median(c[1]) / std::max(median(c[0]), 1e-9));
        std::printf(" |\n\n");
        const auto& va = result[0].values;
        const auto& vb = result[1].values;
        if (va.size() != vb.size() || result[0].block_coords != result[1].block_coords) {
            std::printf("results: different bands\n");
        } else if (std::memcmp(va.data(), vb.data(), va.size() * sizeof(float)) == 0) {
            std::printf("results: identical bit for bit\n");
        } else {
            double worst = 0;
            for (std::size_t i = 0; i < va.size(); ++i) worst = std::max(worst, double(std::abs(va[i] - vb[i])));
            std::printf("results: differ, max |Δφ| = %.3g voxel\n", worst / result[0].grid.voxel_size);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nf_ab_engine: %s\n", e.what());
        return 1;
    }
    return 0;
}
