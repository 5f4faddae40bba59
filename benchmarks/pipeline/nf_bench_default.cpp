// nf_bench_default [DATA_DIR] [--only SUBSTRING]... [--threads T] [--samples N] [--repeat K] [--md FILE]
// The default `normalflow smooth IN OUT` against the previous default, in one process, on every
// noisy / ground-truth pair of shared/data (study_pairs.h; DATA_DIR is shared/data). For each pair,
// both configurations run end to end, read to write (read_mesh, smooth_mesh, write_mesh to a
// temporary .ply), alternating, K times each (the fastest time counts; the machines are shared):
//   - previous: PipelineOptions{} with the engine's speed-ups off: explicit refit steps
//     (refit_super_steps = 0), the filtered normals carried off the surface by a filter pass at
//     every closest point (extend_by_gather), every shell sample filtered (thin_samples = false);
//   - default: PipelineOptions{}, what the command line runs.
// Quality: mean normal angle to the ground truth (compare_meshes, 50,000 area-uniform samples,
// no correspondence) and, where the result kept the noisy mesh's connectivity, the face-by-face
// angle. Prints one Markdown row per pair (times, their ratio, both angles and the difference) and
// the totals.
// Not part of the test suite (about 10 minutes on 2 cores; see benchmarks/README.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "io/io.h"
#include "io/util/atomic_file.h"
#include "metrics/compare.h"
#include "pipeline/pipeline.h"
#include "study_pairs.h"

namespace fs = std::filesystem;
using namespace normalflow;

namespace {

struct Run {
    double seconds = 1e300;  // fastest of the repeats, read to write
    double angle = 0;        // mean normal angle to the ground truth, degrees
    double face_angle = -1;  // face-by-face angle (connectivity kept), or -1
    bool kept = false;
    int resolution = 0;
};

PipelineOptions previous_defaults(int threads) {
    PipelineOptions o;
    o.smooth.refit_super_steps = 0;
    o.smooth.extend_by_gather = true;
    o.smooth.thin_samples = false;
    o.scan.threads = o.smooth.threads = threads;
    return o;
}

PipelineOptions current_defaults(int threads) {
    PipelineOptions o;
    o.scan.threads = o.smooth.threads = threads;
    return o;
}

/// One end-to-end run: read, smooth, write; the time into r (the fastest so far), the mesh returned.
Mesh run_once(const fs::path& in, const fs::path& out, const PipelineOptions& o, Run& r) {
    const auto t0 = std::chrono::steady_clock::now();
    const Mesh noisy = read_mesh(in.string());
    PipelineResult res = smooth_mesh(noisy, o);
    write_mesh(out.string(), res.mesh);
    r.seconds = std::min(r.seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    r.kept = res.report.connectivity_kept;
    r.resolution = res.report.scan_options.resolution;
    return std::move(res.mesh);
}

void measure(const Mesh& m, const Mesh& gt, const CompareOptions& co, Run& r) {
    CompareOptions o = co;
    o.correspondence = correspondence_mismatch(m, gt).empty();
    const MeshComparison c = compare_meshes(m, gt, o);
    r.angle = c.distance.mean_normal_angle_deg;
    r.face_angle = c.correspondence ? c.correspondence->mean_face_angle_deg : -1.0;
}

std::string face(double a) {
    if (a < 0) return "–";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", a);
    return buf;
}

}  // namespace

int main(int argc, char** argv) {
    fs::path data = NORMALFLOW_TEST_DATA;
    std::string md_path;
    std::vector<std::string> only;
    int threads = 0, repeat = 1;
    CompareOptions co;
    co.sampling.samples = 50000;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has = i + 1 < argc;
        if (a == "--samples" && has)
            co.sampling.samples = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--md" && has)
            md_path = argv[++i];
        else if (a == "--threads" && has)
            threads = std::atoi(argv[++i]);
        else if (a == "--repeat" && has)
            repeat = std::max(1, std::atoi(argv[++i]));
        else if (a == "--only" && has)
            only.emplace_back(argv[++i]);
        else if (!a.starts_with("--"))
            data = a;
        else {
            std::fprintf(stderr, "nf_bench_default: unknown or incomplete argument %s\n", a.c_str());
            return 2;
        }
    }
    const std::vector<bench::Pair> pairs = bench::find_pairs(data);
    if (pairs.empty()) {
        std::fprintf(stderr, "nf_bench_default: %s: no pairs (pairs_gnf, pairs_gcn, pairs_nllr)\n",
                     data.string().c_str());
        return 1;
    }
    const fs::path tmp = fs::temp_directory_path() / ("nf_bench_default_" + std::to_string(::getpid()));
    fs::create_directories(tmp);

    std::string md =
        "| noisy mesh | R | connectivity | previous s | default s | speed-up | previous ° | default ° | Δ ° | "
        "face-by-face previous / default ° |\n|---|---|---|---|---|---|---|---|---|---|\n";
    double total_prev = 0, total_cur = 0, worst = 0;
    int failures = 0, within = 0, count = 0;
    for (const bench::Pair& p : pairs) {
        const std::string key = p.set + "/" + p.noisy_name;
        if (!bench::selected(only, key)) continue;
        try {
            const Mesh gt = read_mesh(p.truth.string());
            Run prev, cur;
            Mesh mp, mc;
            for (int k = 0; k < repeat; ++k) {  // alternating, so that a slow spell of the machine hits both
                mp = run_once(p.noisy, tmp / "previous.ply", previous_defaults(threads), prev);
                mc = run_once(p.noisy, tmp / "default.ply", current_defaults(threads), cur);
            }
            measure(mp, gt, co, prev);
            measure(mc, gt, co, cur);
            const double d = cur.angle - prev.angle;
            total_prev += prev.seconds;
            total_cur += cur.seconds;
            worst = std::max(worst, d);
            within += std::abs(d) <= 0.2 ? 1 : 0;
            ++count;
            char buf[512];
            std::snprintf(buf, sizeof buf, "| %s | %d | %s | %.2f | %.2f | %.2f× | %.2f | %.2f | %+.2f | %s / %s |\n",
                          key.c_str(), cur.resolution, cur.kept ? "kept" : "re-meshed", prev.seconds, cur.seconds,
                          prev.seconds / cur.seconds, prev.angle, cur.angle, d, face(prev.face_angle).c_str(),
                          face(cur.face_angle).c_str());
            md += buf;
            std::fprintf(stderr, "%s", buf);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "nf_bench_default: %s: %s\n", key.c_str(), e.what());
            ++failures;
        }
    }
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "\n%d pairs: previous %.1f s, default %.1f s in all (%.2f× faster); the default within 0.2° of the "
                  "previous on %d, worst change %+.2f°.\n",
                  count, total_prev, total_cur, total_cur > 0 ? total_prev / total_cur : 0.0, within, worst);
    md += buf;
    std::printf("%s", md.c_str());
    if (!md_path.empty()) {
        AtomicFile f(md_path, "nf_bench_default");
        f.write(md);
        f.commit();
    }
    std::error_code ec;
    fs::remove_all(tmp, ec);
    return failures ? 1 : 0;
}
