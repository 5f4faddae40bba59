// nf_bench_study [DATA_DIR] [--samples N] [--resolution R] [--threads T] [--only SUBSTRING]...
//                [--no-normalflow] [--modes aniso,bilateral,default] (also: iso, guided, tv, keep, remesh, full) [--csv FILE] [--md FILE]
// The comparison study of issue 6 on every noisy/ground-truth pair of shared/data: pairs_gnf, pairs_gcn
// and pairs_nllr (DATA_DIR is shared/data). For each noisy mesh:
//   - the noisy input itself;
//   - Taubin λ|μ at its best iteration count (K from 1 to 200, the K with the lowest mean distance to
//     the ground truth: an oracle choice in Taubin's favour);
//   - plain Laplacian (10 steps, to show shrinkage) and bilateral normal filtering (defaults);
//   - normalflow isotropic and anisotropic (smooth_mesh, the shipped pipeline: repair, scan conversion
//     at resolution R, smooth_volume with the defaults, extraction; the time includes all of them);
//   - the published result of the method the pair comes from, where the folder has one
//     (X.nllr_result.ply: Li et al. 2018, NLLR; X.gcn_result.ply: Shen et al. 2022, GCN-Denoiser).
// Metrics (compare_meshes, no vertex correspondence): mean / RMS / Hausdorff distance relative to the
// ground truth's diagonal, mean normal angle (area-uniform samples on the result, its face normal
// against the ground truth's face normal at the closest point), volume change, crease preservation.
// Rows whose mesh kept the noisy mesh's vertices and triangles (the noisy input, Taubin, Laplacian, the
// bilateral normal filter, normalflow keep and default on an open input, published results), which the
// ground truth shares, also get the correspondence measures of the denoising papers (correspondence_errors):
// face-by-face normal angle (unweighted mean over faces) and mean vertex distance; "-" on the others.
// Prints a Markdown table (and writes it with --md, the rows as CSV with --csv after every pair).
// Then the triangulation experiment: one torus meshed two ways, smoothed by Taubin and by normalflow.
// Not part of the test suite (minutes to an hour; see benchmarks/README.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "io/io.h"
#include "io/openmesh/smoothing.h"
#include "io/util/atomic_file.h"
#include "metrics/compare.h"
#include "pipeline/pipeline.h"
#include "study_pairs.h"

namespace fs = std::filesystem;
using namespace normalflow;
using normalflow::bench::find_pairs;
using normalflow::bench::Pair;

namespace {

struct Row {
    std::string set, noisy, method, params;
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
            m.positions.push_back(Vec3f(
                Vec3d((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v))));
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

/// normalflow's whole pipeline on m, as the tool ships it (pipeline/ smooth_mesh: repair, scan
/// conversion at `resolution`, smooth_volume with the defaults, extraction).
Mesh normalflow_smooth(const Mesh& m, int resolution, SmoothMode mode, int threads) {
    PipelineOptions o;
    o.scan.resolution = resolution;  // 0: automatic (auto_resolution)
    o.scan.threads = threads;
    o.smooth.mode = mode;
    o.smooth.threads = threads;
    return smooth_mesh(m, o).mesh;
}

/// The correspondence columns of a row: the face-by-face angle (degrees) and the mean vertex distance
/// relative to the ground truth's diagonal, printed with f, or `none` when the row's mesh has other
/// connectivity than the ground truth.
std::string correspondence_cell(const MeshComparison& c, double CorrespondenceErrors::*field, const char* f,
                                const char* none) {
    if (!c.correspondence) return none;
    char buf[64];
    std::snprintf(buf, sizeof buf, f, (*c.correspondence).*field);
    return buf;
}
std::string face_angle(const MeshComparison& c, const char* f, const char* none) {
    return correspondence_cell(c, &CorrespondenceErrors::mean_face_angle_deg, f, none);
}
std::string vertex_distance(const MeshComparison& c, const char* f, const char* none) {
    return correspondence_cell(c, &CorrespondenceErrors::mean_vertex_distance_relative, f, none);
}

double now_ms() {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
    fs::path data = NORMALFLOW_TEST_DATA;
    std::string csv_path, md_path;
    std::vector<std::string> only;
    int resolution = 256, threads = 0;
    bool with_normalflow = true;
    // normalflow rows: iso, aniso, bilateral, guided at --resolution; default: the pipeline's defaults
    // (PipelineOptions{}: its mode and the automatic resolution), what `normalflow smooth IN OUT` runs
    std::string modes = "aniso,bilateral,default";
    // --decimation-sweep E1,E2,...: each re-meshed pipeline row again, decimated within E voxels (max_error)
    // voxels, and with E:DEGREES also no face turned more than DEGREES from the field's normals at its corners
    std::vector<std::pair<double, double>> sweep;
    CompareOptions co;
    co.sampling.samples = 50000;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has = i + 1 < argc;
        if (a == "--samples" && has)
            co.sampling.samples = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--csv" && has)
            csv_path = argv[++i];
        else if (a == "--md" && has)
            md_path = argv[++i];
        else if (a == "--resolution" && has)
            resolution = std::atoi(argv[++i]);
        else if (a == "--threads" && has)
            threads = std::atoi(argv[++i]);
        else if (a == "--only" && has)
            only.emplace_back(argv[++i]);
        else if (a == "--no-normalflow")
            with_normalflow = false;
        else if (a == "--modes" && has)
            modes = argv[++i];
        else if (a == "--decimation-sweep" && has) {
            for (std::string list = argv[++i]; !list.empty();) {
                const std::size_t comma = list.find(',');
                const std::string item = list.substr(0, comma);  // E or E:DEGREES
                const std::size_t colon = item.find(':');
                sweep.push_back({std::atof(item.substr(0, colon).c_str()),
                                 colon == std::string::npos ? 0.0 : std::atof(item.substr(colon + 1).c_str())});
                list = comma == std::string::npos ? "" : list.substr(comma + 1);
            }
        } else if (!a.starts_with("--"))
            data = a;
        else {
            std::fprintf(stderr, "nf_bench_study: unknown or incomplete argument %s\n", a.c_str());
            return 2;
        }
    }
    const std::vector<Pair> pairs = find_pairs(data);
    if (pairs.empty()) {
        std::fprintf(stderr, "nf_bench_study: %s: no pairs (pairs_gnf, pairs_gcn, pairs_nllr)\n",
                     data.string().c_str());
        return 1;
    }

    std::vector<Row> rows;
    std::string csv =
        "set,noisy,method,parameters,ms,mean_relative,rms_relative,hausdorff_relative,"
        "mean_normal_angle_deg,volume_change,crease_preservation,face_normal_angle_deg,"
        "mean_vertex_distance_relative\n";
    auto save_csv = [&] {
        if (csv_path.empty()) return;
        AtomicFile f(csv_path, "nf_bench_study");
        f.write(csv);
        f.commit();
    };
    int failures = 0;
    for (const Pair& p : pairs) {
        const std::string key = p.set + "/" + p.noisy_name;
        if (!bench::selected(only, key)) continue;
        try {
            const Mesh gt = read_mesh(p.truth.string());
            const Mesh noisy = read_mesh(p.noisy.string());
            auto add = [&](const std::string& method, const std::string& params, double ms, const Mesh& m) {
                CompareOptions o = co;
                o.correspondence = correspondence_mismatch(m, gt).empty();  // connectivity kept
                rows.push_back({p.set, p.noisy_name, method, params, ms, compare_meshes(m, gt, o)});
                const Row& r = rows.back();
                char buf[640];
                std::snprintf(buf, sizeof buf, "%s,%s,\"%s\",\"%s\",%.3f,%.6e,%.6e,%.6e,%.4f,%.6f,%.4f,%s,%s\n",
                              r.set.c_str(), r.noisy.c_str(), r.method.c_str(), r.params.c_str(), r.ms,
                              r.c.mean_relative, r.c.rms_relative, r.c.hausdorff_relative,
                              r.c.distance.mean_normal_angle_deg, r.c.volume_change, r.c.crease.fraction,
                              face_angle(r.c, "%.4f", "").c_str(), vertex_distance(r.c, "%.6e", "").c_str());
                csv += buf;
                std::fprintf(stderr, "%s %s %s: mean/diag %.3e, normal %.2f deg, face-by-face %s deg, %.1f ms\n",
                             key.c_str(), method.c_str(), params.c_str(), r.c.mean_relative,
                             r.c.distance.mean_normal_angle_deg, face_angle(r.c, "%.2f", "-").c_str(), ms);
            };
            add("noisy input", "", 0, noisy);

            // Taubin: best iteration count by mean distance to the ground truth.
            Mesh best_mesh;
            std::string best_params;
            double best_ms = 0, best_mean = 0;
            for (int k : {1, 2, 3, 5, 8, 12, 20, 30, 50, 80, 120, 200}) {
                Mesh m = noisy;
                TaubinOptions o;
                o.iterations = k;
                const double t0 = now_ms();
                taubin_smooth(m, o);
                const double ms = now_ms() - t0;
                const double mean = surface_distance(m, gt, co.sampling).mean;
                if (best_params.empty() || mean < best_mean) {
                    best_mesh = std::move(m);
                    best_params = "K=" + std::to_string(k);
                    best_ms = ms;
                    best_mean = mean;
                }
            }
            add("Taubin λ|μ (best K)", best_params, best_ms, best_mesh);

            Mesh lap = noisy;
            double t0 = now_ms();
            laplacian_smooth(lap, {});
            add("Laplacian", "λ=0.5, 10 steps", now_ms() - t0, lap);

            Mesh bil = noisy;
            t0 = now_ms();
            bilateral_normal_filter(bil, {});
            add("bilateral normal", "20+10 it., σr=0.35", now_ms() - t0, bil);

            if (with_normalflow) {
                const std::string list = "," + modes + ",";
                const auto wanted = [&](const char* token) {
                    std::string t(",");
                    t += token;
                    t += ',';
                    return list.find(t) != std::string::npos;
                };
                const std::pair<const char*, SmoothMode> study_modes[] = {{"iso", SmoothMode::Isotropic},
                                                                          {"aniso", SmoothMode::Anisotropic},
                                                                          {"bilateral", SmoothMode::Bilateral},
                                                                          {"guided", SmoothMode::Guided},
                                                                          {"tv", SmoothMode::TotalVariation}};
                for (const auto& [token, mode] : study_modes) {
                    if (!wanted(token)) continue;
                    t0 = now_ms();
                    const Mesh m = normalflow_smooth(noisy, resolution, mode, threads);
                    add(std::string("normalflow ") + to_string(mode), "R=" + std::to_string(resolution) + ", defaults",
                        now_ms() - t0, m);
                }
                // the pipeline's defaults (what `normalflow smooth IN OUT` runs), and with each
                // connectivity forced
                // connectivity forced; "full": the defaults with every triangle of a re-meshed result kept
                // (--full-density), the column the compact default is judged against
                const std::pair<const char*, Connectivity> pipelines[] = {{"default", Connectivity::Auto},
                                                                          {"full", Connectivity::Auto},
                                                                          {"keep", Connectivity::Keep},
                                                                          {"remesh", Connectivity::Remesh}};
                bool default_kept = false;  // a kept result is never decimated: "full" would repeat it
                for (const auto& [token, connectivity] : pipelines) {
                    if (!wanted(token) || (std::string(token) == "full" && default_kept)) continue;
                    t0 = now_ms();
                    const PipelineOptions defaults;
                    PipelineOptions o = defaults;
                    o.connectivity = connectivity;
                    o.full_density = std::string(token) == "full";
                    o.scan.threads = o.smooth.threads = threads;
                    const PipelineResult res = smooth_mesh(noisy, o);
                    const double ms = now_ms() - t0;
                    const std::string name = std::string("normalflow ") + token + " (" +
                                             to_string(defaults.smooth.mode) + ", " +
                                             (res.report.connectivity_kept ? "kept" : "remeshed") + ")";
                    const std::string res_params = "R=auto " + std::to_string(res.report.scan_options.resolution);
                    add(name, res_params + ", " + std::to_string(res.mesh.triangles.size()) + " faces", ms, res.mesh);
                    if (std::string(token) == "default") default_kept = res.report.connectivity_kept;
                    if (res.report.connectivity_kept) continue;
                    // the re-meshed result's vertex normals are the field's (set_volume_normals): the decimation
                    // the pipeline runs, on the same mesh
                    for (const auto& [e, deg] : sweep) {
                        Mesh d = res.mesh;
                        const double t1 = now_ms();
                        // as the compact default runs it (compact_surface in pipeline/pipeline.cpp)
                        const DecimationReport dr = decimate_mesh(d, {.max_error = e * res.report.scan.grid.voxel_size,
                                                                      .decimator = Decimator::Quadric,
                                                                      .tangent_planes = !o.sharpen,
                                                                      .max_normal_deviation_deg = deg,
                                                                      .measure_distance = false,
                                                                      .local_repair = true});
                        char p[160];
                        std::snprintf(p, sizeof p, "%s, max error %g voxel, %g°, %zu faces%s", res_params.c_str(), e,
                                      deg, d.triangles.size(), dr.fallback.empty() ? "" : " (cgal)");
                        add(name + " decimated", p, ms + now_ms() - t1, d);
                    }
                }
            }
            for (const auto& [label, path] : p.published) add(label, "", 0, read_mesh(path.string()));
        } catch (const std::exception& e) {
            std::fprintf(stderr, "nf_bench_study: %s: %s\n", key.c_str(), e.what());
            ++failures;
        }
        save_csv();
    }

    std::string md =
        "| set | noisy mesh | method | parameters | ms | mean dist / diag | RMS / diag | Hausdorff / diag | "
        "normal angle ° | volume Δ | crease kept | face-by-face angle ° | vertex dist. / diag |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows) {
        char buf[640];
        std::snprintf(
            buf, sizeof buf, "| %s | %s | %s | %s | %.0f | %.3e | %.3e | %.3e | %.2f | %+.2f%% | %.1f%% | %s | %s |\n",
            r.set.c_str(), r.noisy.c_str(), r.method.c_str(), r.params.c_str(), r.ms, r.c.mean_relative,
            r.c.rms_relative, r.c.hausdorff_relative, r.c.distance.mean_normal_angle_deg, 100 * r.c.volume_change,
            100 * r.c.crease.fraction, face_angle(r.c, "%.2f", "-").c_str(), vertex_distance(r.c, "%.3e", "-").c_str());
        md += buf;
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
        std::string tri =
            "\nTriangulation dependence (torus R=1, r=0.4, 96x48 quads, uniform vs u-graded):\n\n"
            "| method | max vertex distance to the torus (uniform / graded) | Hausdorff between the two results "
            "(/ diagonal) |\n|---|---|---|\n";
        char buf[512];
        std::snprintf(buf, sizeof buf, "| Taubin K=20, uniform weights | %.3e / %.3e | %.3e (%.3e) |\n", ea.first,
                      eb.first, ab.distance.hausdorff, ab.hausdorff_relative);
        tri += buf;
        if (with_normalflow) {  // normalflow sees only the volume, not the triangulation
            const Mesh na = normalflow_smooth(a0, 128, SmoothMode::Isotropic, threads);
            const Mesh nb = normalflow_smooth(b0, 128, SmoothMode::Isotropic, threads);
            const auto fa = torus_error(na, R, r), fb = torus_error(nb, R, r);
            const MeshComparison nab = compare_meshes(nb, na, co);
            std::snprintf(buf, sizeof buf, "| normalflow isotropic, R=128, defaults | %.3e / %.3e | %.3e (%.3e) |\n",
                          fa.first, fb.first, nab.distance.hausdorff, nab.hausdorff_relative);
            tri += buf;
        }
        std::printf("%s", tri.c_str());
        md += tri;
    }
    save_csv();
    if (!md_path.empty()) {
        AtomicFile f(md_path, "nf_bench_study");
        f.write(md);
        f.commit();
    }
    return failures ? 1 : 0;
}
