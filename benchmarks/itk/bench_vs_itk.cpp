// nf_bench_vs_itk: the original authors' implementation in ITK against normalflow's engine, on the
// very same signed distance volume (issue 4).
//
//   nf_bench_vs_itk [--resolution 256] [--iterations 2] [--refit 100] [--itk-threads 2]
//                   [--nf-threads 1,2] [--modes isotropic,anisotropic,default] [--mu 0.1] [--samples 100000]
//                   [--no-itk] [mesh ...]          (default mesh: shared/data/pairs_gnf/fandisk_n0.3.ply)
//
// 1. mesh_to_volume (pipeline/, the shipped pipeline's first half: repair, scan conversion with the
//    engine BVH, band 3 voxels) at the resolution; the same φ, in voxel units and clamped to ±3
//    outside the band, is written into a dense itk::Image<float, 3> of spacing 1.
// 2. ITK: itk::IsotropicFourthOrderLevelSetImageFilter / AnisotropicFourthOrderLevelSetImageFilter.
// 3. normalflow: smooth_volume on a copy of the Volume, 1 and 2 threads (the engine alone is timed
//    against ITK's filter, so this step calls smooth_volume itself). Mode "default": the default
//    smoothing's engine (engine_options of the default PipelineOptions on this grid: bilateral, its
//    filter sized from the mesh's length scale and noise) for the same number of main iterations, against
//    ITK's anisotropic filter (the paper's iteration; run once for both where both modes are asked).
// Prints Markdown tables: seconds per main iteration (wall and process CPU; and wall with the set-up
// before the first main iteration left out: ITK's copy of the image and construction of its layers,
// timed up to its first InitializeIteration, and normalflow's initial band move and
// reinitialisation, outside SmoothReport::seconds_per_iteration), peak memory (rise of
// the process's peak RSS during the run, reset through /proc/self/clear_refs), the ITK / normalflow
// ratio, and the distance between the two results' zero level sets (lib/metrics surface_distance).
//
// What one "main iteration" is on each side (Tasdizen et al. 2003, Sec. 4: normal loop, then refit):
//   ITK: SparseFieldFourthOrderLevelSetImageFilter::InitializeIteration calls ProcessNormals (an
//        ImplicitManifoldNormalVectorFilter of MaxNormalIteration = 25 steps, dt = 0.5/3, on the band
//        |φ| <= CurvatureBandWidth + 3 = 6.5, then the target curvatures) at its first iteration and
//        again every MaxRefitIteration (default 100) level-set iterations, or earlier when the front
//        reaches the edge of the curvature band (or the RMS change falls below a trigger, default 0).
//        One ITK "filter iteration" (SetMaxFilterIteration, default 1000) is ONE refit step of the
//        sparse-field solver φ_t = |∇φ| (κ_target − κ), dt = min(1/6, (1/6) / max|κ_target − κ|).
//        So N main iterations = SetMaxRefitIteration(R), SetMaxFilterIteration(N · R); we count the
//        ProcessNormals calls (a subclass watches the target image change) to confirm N.
//   normalflow: SmoothOptions::iterations = N, normal_steps = 25, normal_dt = 1/6, refit_dt = 1/6,
//        refit_max_steps = R, refit_tolerance = 0 (refit until D = Σ(|∇φ| − ∇φ·N) stops decreasing,
//        at most R steps), plus the band move and reinitialisation (ITK's sparse field keeps its
//        layers every step). Anisotropic: ITK's g = exp(−|∂_i N|² / K²) per face direction i against
//        normalflow's g = exp(−κ² / (2µ²)) of the total curvature: K = √2 µ (ITK adds 0.001 to K, which
//        we subtract), and conductance_presmooth_steps = 0 (the paper's g from the current normals).
// The two solvers differ in the discretisation (ITK: 2×2×2 "vertex" normals for the curvature, upwind
// sparse-field layers; normalflow: the paper's Appendix B staggered stencil, 8³ blocks), so the
// results agree to a fraction of a voxel, not bit for bit.
#include <itkAnisotropicFourthOrderLevelSetImageFilter.h>
#include <itkImage.h>
#include <itkIsotropicFourthOrderLevelSetImageFilter.h>
#include <itkMultiThreaderBase.h>

#include <malloc.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"
#include "extract/extract_surface.h"
#include "io/io.h"
#include "metrics/noise.h"
#include "metrics/surface_distance.h"
#include "normals/smooth.h"
#include "pipeline/pipeline.h"

using namespace normalflow;

namespace {

using Image = itk::Image<float, 3>;

double wall_now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

double cpu_now() {  // CPU seconds of the whole process (all threads)
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// kB of a field of /proc/self/status ("VmHWM", "VmRSS"); 0 where unavailable.
long status_kb(const std::string& field) {
    std::ifstream f("/proc/self/status");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind(field + ":", 0) == 0) return std::atol(line.c_str() + field.size() + 1);
    return 0;
}

/// Measures one run: wall and CPU seconds, and the rise of the peak RSS above the RSS at the start
/// (Linux >= 4.0: writing 5 to /proc/self/clear_refs resets the peak; -1 where that fails).
struct Measured {
    double wall = 0, cpu = 0, peak_mib = -1;
};

Measured measure(const std::function<void()>& run) {
    malloc_trim(0);  // give freed memory back, so that the RSS at the start is a fair baseline
    bool reset = false;
    {
        std::ofstream f("/proc/self/clear_refs");
        if (f) {
            f << "5";
            f.flush();
            reset = bool(f);
        }
    }
    const long rss0 = status_kb("VmRSS");
    Measured m;
    const double w0 = wall_now(), c0 = cpu_now();
    run();
    m.wall = wall_now() - w0;
    m.cpu = cpu_now() - c0;
    if (reset) m.peak_mib = double(status_kb("VmHWM") - rss0) / 1024.0;
    return m;
}

/// The ITK filter of the given kind, with a hook that counts and times its normal processes:
/// ProcessNormals installs a new sparse target image in the level-set function, so a change of
/// that pointer across InitializeIteration means one main iteration began.
template <class Base>
class TimedFourthOrder : public Base {
public:
    using Self = TimedFourthOrder;
    using Pointer = itk::SmartPointer<Self>;
    itkNewMacro(Self)

        int normal_processes = 0;            ///< ProcessNormals calls (= main iterations)
    int refit_steps = 0;                     ///< level-set iterations (= refit steps)
    double normal_wall = 0, normal_cpu = 0;  ///< seconds inside ProcessNormals
    double first_iteration_wall = -1;        ///< wall time at the first InitializeIteration (end of set-up)

protected:
    TimedFourthOrder() = default;
    /// The curvature target that the last ProcessNormals installed in the level-set function.
    const void* target_image() const {
        using Function = typename Base::Superclass::LevelSetFunctionType;  // LevelSetFunctionWithRefitTerm
        const auto* f = dynamic_cast<const Function*>(this->GetDifferenceFunction().GetPointer());
        return f ? static_cast<const void*>(f->GetSparseTargetImage()) : nullptr;
    }
    void InitializeIteration() override {
        if (first_iteration_wall < 0) first_iteration_wall = wall_now();
        const void* before = target_image();
        const double w0 = wall_now(), c0 = cpu_now();
        Base::InitializeIteration();
        if (target_image() != before) {
            ++normal_processes;
            normal_wall += wall_now() - w0;
            normal_cpu += cpu_now() - c0;
        }
        ++refit_steps;
    }
};

using ItkIso = TimedFourthOrder<itk::IsotropicFourthOrderLevelSetImageFilter<Image, Image>>;
using ItkAniso = TimedFourthOrder<itk::AnisotropicFourthOrderLevelSetImageFilter<Image, Image>>;

/// φ of v in voxel units as a dense ITK image of spacing 1 (index (i, j, k) = grid sample (i, j, k));
/// samples outside the band get ±background (clamped to the band).
Image::Pointer to_itk(const Volume& v) {
    Image::Pointer img = Image::New();
    Image::RegionType region;
    Image::SizeType size;
    for (int a = 0; a < 3; ++a) size[a] = itk::SizeValueType(v.grid.dims[a]);
    region.SetSize(size);
    img->SetRegions(region);
    img->Allocate();
    float* out = img->GetBufferPointer();
    const float inv_h = float(1.0 / v.grid.voxel_size);
    std::size_t n = 0;
    for (int k = 0; k < v.grid.dims[2]; ++k)
        for (int j = 0; j < v.grid.dims[1]; ++j)
            for (int i = 0; i < v.grid.dims[0]; ++i) out[n++] = v.value(i, j, k) * inv_h;
    return img;
}

/// An ITK result (voxel units, dense) as a Volume on grid g, so that the same extractor runs on it:
/// blocks with a sample inside (−band, band) are allocated, the others tiled with their sign.
Volume from_itk(const Image* img, const Grid& g, float band) {
    Volume v(g, band);
    const float* in = img->GetBufferPointer();
    const float h = float(g.voxel_size);
    const auto at = [&](int i, int j, int k) {
        return in[(std::size_t(k) * std::size_t(g.dims[1]) + std::size_t(j)) * std::size_t(g.dims[0]) + std::size_t(i)];
    };
    for (int bk = 0; bk < v.block_dims[2]; ++bk)
        for (int bj = 0; bj < v.block_dims[1]; ++bj)
            for (int bi = 0; bi < v.block_dims[0]; ++bi) {
                bool near = false, inside = false;
                for (int k = bk * kBlockDim; k < std::min(g.dims[2], (bk + 1) * kBlockDim); ++k)
                    for (int j = bj * kBlockDim; j < std::min(g.dims[1], (bj + 1) * kBlockDim); ++j)
                        for (int i = bi * kBlockDim; i < std::min(g.dims[0], (bi + 1) * kBlockDim); ++i) {
                            const float x = at(i, j, k);
                            near = near || std::abs(x) < band;
                            inside = x < 0;
                        }
                if (!near) {
                    if (inside) v.block_table[v.table_index(bi, bj, bk)] = kBlockInside;
                    continue;
                }
                for (int k = bk * kBlockDim; k < std::min(g.dims[2], (bk + 1) * kBlockDim); ++k)
                    for (int j = bj * kBlockDim; j < std::min(g.dims[1], (bj + 1) * kBlockDim); ++j)
                        for (int i = bi * kBlockDim; i < std::min(g.dims[0], (bi + 1) * kBlockDim); ++i)
                            v.set(i, j, k, std::clamp(at(i, j, k), -band, band) * h);
            }
    return v;
}

struct Row {
    std::string name;
    int threads = 0;
    int iterations = 0;
    std::string steps;  ///< normal / refit steps per main iteration
    Measured m;
    double loop_wall = 0;  ///< wall seconds of the main iterations alone (set-up before them excluded)
    bool itk = false;
};

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string t; std::getline(ss, t, ',');)
        if (!t.empty()) out.push_back(t);
    return out;
}

std::string mib(double x) {
    if (x < 0) return "n/a";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.0f", x);
    return buf;
}

}  // namespace

int main(int argc, char** argv) {
    int resolution = 256, iterations = 2, refit = 100, itk_threads = 2;
    std::vector<int> nf_threads{1, 2};
    std::vector<std::string> modes{"isotropic", "anisotropic"};
    float mu = 0.1f;
    std::size_t samples = 100000;
    bool run_itk = true;
    std::vector<std::string> meshes;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        const auto next = [&]() -> std::string {
            if (a + 1 >= argc) {
                std::fprintf(stderr, "nf_bench_vs_itk: %s needs a value\n", arg.c_str());
                std::exit(2);
            }
            return argv[++a];
        };
        if (arg == "--resolution")
            resolution = std::atoi(next().c_str());
        else if (arg == "--iterations")
            iterations = std::atoi(next().c_str());
        else if (arg == "--refit")
            refit = std::atoi(next().c_str());
        else if (arg == "--itk-threads")
            itk_threads = std::atoi(next().c_str());
        else if (arg == "--mu")
            mu = float(std::atof(next().c_str()));
        else if (arg == "--samples")
            samples = std::size_t(std::atoll(next().c_str()));
        else if (arg == "--modes")
            modes = split(next());
        else if (arg == "--no-itk")
            run_itk = false;
        else if (arg == "--nf-threads") {
            nf_threads.clear();
            for (const auto& t : split(next())) nf_threads.push_back(std::atoi(t.c_str()));
        } else if (!arg.empty() && arg[0] == '-') {
            std::fprintf(stderr,
                         "nf_bench_vs_itk: unknown option %s (see the comment at the top of bench_vs_itk.cpp)\n",
                         arg.c_str());
            return 2;
        } else
            meshes.push_back(arg);
    }
    if (resolution < 8 || iterations < 1 || refit < 1 || itk_threads < 1 || mu <= 0 || samples < 1) {
        std::fprintf(stderr, "nf_bench_vs_itk: bad option value\n");
        return 2;
    }
    for (const auto& mode : modes)
        if (mode != "isotropic" && mode != "anisotropic" && mode != "default") {
            std::fprintf(stderr, "nf_bench_vs_itk: --modes takes isotropic, anisotropic and/or default, not %s\n",
                         mode.c_str());
            return 2;
        }
    if (meshes.empty()) meshes.push_back(std::string(NORMALFLOW_TEST_DATA) + "/pairs_gnf/fandisk_n0.3.ply");

    itk::MultiThreaderBase::SetGlobalMaximumNumberOfThreads(itk_threads);
    itk::MultiThreaderBase::SetGlobalDefaultNumberOfThreads(itk_threads);
    const float itk_conductance = std::sqrt(2.0f) * mu - 0.001f;

    try {
        for (const std::string& path : meshes) {
            const Mesh mesh = read_mesh(path);
            const double noise = estimate_noise(mesh, NoiseNormals::Steady).sigma;  // the default's filter scale
            // The shipped pipeline's first half (pipeline/ mesh_to_volume: repair, scan conversion
            // with the default distance query, the 3-voxel band of a smoothing run).
            PipelineOptions po;
            po.scan.resolution = resolution;
            PipelineReport pr;
            const Volume input = mesh_to_volume(mesh, po, &pr);
            const ScanConvertReport& sr = pr.scan;
            po.smoothing = false;
            const Mesh input_surface = volume_to_mesh(input, po);
            // pairs_gnf naming: NAME_<noise>.ply beside NAME_gt.ply; the ground truth, where present,
            // shows whether the two results smooth alike.
            Mesh truth;
            const std::size_t us = path.rfind('_');
            const std::string gt_path = us == std::string::npos ? std::string() : path.substr(0, us) + "_gt.ply";
            if (!gt_path.empty() && gt_path != path && std::ifstream(gt_path).good()) truth = read_mesh(gt_path);
            const double h = input.grid.voxel_size;
            std::printf(
                "## %s, resolution %d: grid %d x %d x %d, h = %.4g, %zu band voxels; %d main iterations "
                "(25 normal steps + at most %d refit steps each); ITK %s, %d thread(s)\n\n",
                path.c_str(), resolution, input.grid.dims[0], input.grid.dims[1], input.grid.dims[2], h, sr.band_voxels,
                iterations, refit, ITK_VERSION_STRING, itk_threads);
            std::fflush(stdout);

            std::printf(
                "| run | threads | main iterations | normal / refit steps per iteration | wall s per iteration "
                "| CPU s per iteration | wall s per iteration, set-up excluded | peak RSS rise MiB "
                "| ITK / this, wall | ITK / this, CPU | ITK / this, wall, set-up excluded |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|\n");
            std::fflush(stdout);
            Row itk_row;  // the last ITK run, for the ratios of the normalflow rows after it
            bool have_itk_row = false;
            const auto print_row = [&](const Row& r) {
                if (r.itk) {
                    itk_row = r;
                    have_itk_row = true;
                }
                const double n = std::max(r.iterations, 1);
                std::string ratio_w = "-", ratio_c = "-", ratio_l = "-";
                if (!r.itk && have_itk_row) {
                    const double ni = std::max(itk_row.iterations, 1);
                    char buf[32];
                    std::snprintf(buf, sizeof buf, "%.1f", (itk_row.m.wall / ni) / (r.m.wall / n));
                    ratio_w = buf;
                    std::snprintf(buf, sizeof buf, "%.1f", (itk_row.m.cpu / ni) / (r.m.cpu / n));
                    ratio_c = buf;
                    std::snprintf(buf, sizeof buf, "%.1f", (itk_row.loop_wall / ni) / (r.loop_wall / n));
                    ratio_l = buf;
                }
                std::printf("| %s | %d | %d | %s | %.2f | %.2f | %.2f | %s | %s | %s | %s |\n", r.name.c_str(),
                            r.threads, r.iterations, r.steps.c_str(), r.m.wall / n, r.m.cpu / n, r.loop_wall / n,
                            mib(r.m.peak_mib).c_str(), ratio_w.c_str(), ratio_c.c_str(), ratio_l.c_str());
                std::fflush(stdout);
            };
            std::vector<std::string> agreement;
            for (const std::string& mode : modes) {
                const bool default_engine = mode == "default";
                const bool aniso = mode == "anisotropic" || default_engine;  // ITK's side of the default: the paper's
                Volume itk_result;
                bool have_itk = false;
                const bool itk_aniso_done = have_itk_row && itk_row.name.find("Anisotropic") != std::string::npos;
                if (run_itk && !(default_engine && itk_aniso_done)) {
                    Image::Pointer img = to_itk(input);
                    Row r;
                    r.name = "ITK " + std::string(aniso ? "AnisotropicFourthOrderLevelSetImageFilter"
                                                        : "IsotropicFourthOrderLevelSetImageFilter");
                    r.threads = itk_threads;
                    r.itk = true;
                    Image::Pointer out;
                    double setup = 0, normal_wall = 0, normal_cpu = 0;
                    int processes = 0, steps = 0;
                    const auto run = [&](auto filter) {
                        filter->SetInput(img);
                        filter->SetMaxRefitIteration(unsigned(refit));
                        filter->SetMaxFilterIteration(unsigned(iterations * refit));
                        if constexpr (std::is_same_v<decltype(filter), ItkAniso::Pointer>)
                            filter->SetNormalProcessConductance(itk_conductance);
                        const double w0 = wall_now();
                        filter->Update();
                        out = filter->GetOutput();
                        out->DisconnectPipeline();
                        setup = filter->first_iteration_wall - w0;
                        normal_wall = filter->normal_wall;
                        normal_cpu = filter->normal_cpu;
                        processes = filter->normal_processes;
                        steps = filter->refit_steps;
                    };
                    r.m = measure([&] {
                        if (aniso)
                            run(ItkAniso::New());
                        else
                            run(ItkIso::New());
                    });
                    r.iterations = processes;
                    r.loop_wall = r.m.wall - setup;
                    r.steps = "25 / " + std::to_string(steps / std::max(processes, 1));
                    print_row(r);
                    char buf[384];
                    std::snprintf(buf, sizeof buf,
                                  "ITK %s: %d normal processes in %d level-set iterations; set-up (copy, layers) "
                                  "%.1f s wall; normal processes %.1f s wall, %.1f s CPU; set-up + refit %.1f s wall, "
                                  "%.1f s CPU",
                                  mode.c_str(), processes, steps, setup, normal_wall, normal_cpu,
                                  r.m.wall - normal_wall, r.m.cpu - normal_cpu);
                    agreement.push_back(buf);
                    img = nullptr;
                    itk_result = from_itk(out.GetPointer(), input.grid, 8.0f);
                    have_itk = true;
                }
                Volume nf_result;
                std::vector<float> first_values;
                bool identical = true;
                for (int t : nf_threads) {
                    SmoothOptions o;
                    if (default_engine) {
                        o = engine_options(PipelineOptions{}, h, model_length_scale(mesh), noise);
                        o.iterations = iterations;
                    } else {
                        o.mode = aniso ? SmoothMode::Anisotropic : SmoothMode::Isotropic;
                        o.iterations = iterations;
                        o.normal_steps = 25;
                        o.normal_dt = 1.0f / 6.0f;
                        o.refit_dt = 1.0f / 6.0f;
                        o.refit_max_steps = refit;
                        o.refit_tolerance = 0;
                        o.mu = mu;
                        o.conductance_presmooth_steps = 0;
                    }
                    o.threads = t;
                    Volume v = input;
                    SmoothReport rep;
                    Row r;
                    r.name = "normalflow smooth_volume " + mode;
                    r.threads = t;
                    r.m = measure([&] { rep = smooth_volume(v, o); });
                    r.iterations = rep.iterations_run();
                    for (const SmoothIteration& it : rep.iterations) r.loop_wall += it.seconds;
                    int refits = 0;
                    for (const SmoothIteration& it : rep.iterations) refits += it.refit_steps;
                    char buf[64];
                    std::snprintf(buf, sizeof buf, "%d / %.1f", o.normal_steps,
                                  double(refits) / std::max(rep.iterations_run(), 1));
                    r.steps = buf;
                    print_row(r);
                    if (first_values.empty())
                        first_values = v.values;
                    else
                        identical = identical && first_values == v.values;
                    nf_result = std::move(v);
                }
                if (nf_threads.size() > 1)
                    agreement.push_back("normalflow " + mode + ": results for all thread counts " +
                                        (identical ? "bit-identical" : "DIFFER"));
                // Agreement of the zero level sets, voxel units.
                const Mesh nf_surface = extract_surface(nf_result);
                SurfaceSamplingOptions sopt;
                sopt.samples = samples;
                const auto line = [&](const char* what, const Mesh& a, const Mesh& b) {
                    const SurfaceDistance d = surface_distance(a, b, sopt);
                    char buf[256];
                    std::snprintf(buf, sizeof buf,
                                  "%s: mean %.3f, rms %.3f, Hausdorff %.2f voxels, mean normal angle %.1f deg", what,
                                  d.mean / h, d.rms / h, d.hausdorff / h, d.mean_normal_angle_deg);
                    agreement.push_back(buf);
                };
                if (!truth.triangles.empty() && mode == modes.front())
                    line("input (scan-converted, unsmoothed) vs ground truth", input_surface, truth);
                line(("normalflow " + mode + " vs input").c_str(), nf_surface, input_surface);
                if (!truth.triangles.empty())
                    line(("normalflow " + mode + " vs ground truth").c_str(), nf_surface, truth);
                if (have_itk) {
                    const Mesh itk_surface = extract_surface(itk_result);
                    line(("ITK " + mode + " vs input").c_str(), itk_surface, input_surface);
                    if (!truth.triangles.empty())
                        line(("ITK " + mode + " vs ground truth").c_str(), itk_surface, truth);
                    line(("ITK " + mode + " vs normalflow " + mode).c_str(), itk_surface, nf_surface);
                }
            }

            std::printf("\nInput volume %.1f MiB (sparse), dense ITK image %.1f MiB.\n\n",
                        double(input.memory_bytes()) / 1048576.0, double(input.grid.sample_count()) * 4.0 / 1048576.0);
            for (const auto& s : agreement) std::printf("- %s\n", s.c_str());
            std::printf("\n");
            std::fflush(stdout);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nf_bench_vs_itk: %s\n", e.what());
        return 1;
    }
    return 0;
}
