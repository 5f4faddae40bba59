// nf_bench_speed [DATA_DIR] [--only SUBSTRING]... [--threads T] [--repeat K] [--md FILE]
// The default `normalflow smooth IN OUT`, read to write, against a yardstick measured in the same run: 20,000
// iterations of Taubin's λ|μ smoothing (λ 0.5, μ −0.53, uniform umbrella, one thread, written here and sharing
// nothing with the library) on pairs_gnf/fandisk_n0.3.ply. Each time is the fastest of K runs (the machines are
// shared). The yardstick runs before every input and once more at the end, and the fastest of its runs is the unit:
// on these machines the same one-thread loop takes 1.1 s in one process and 1.9 s in the next (the speed of the
// core it lands on), so one run of it can mislead; the slowest is printed too.
// Inputs: every noisy mesh of the study (study_pairs.h) and the real scans real_scans/angel.ply and
// real_scans/bun000_tri.ply. Prints one Markdown row per input: its triangles, open or closed, what the default
// did (kept, re-meshed), seconds per stage (repair, voxelize, smooth, extract + face filter, decimate), the total, its
// ratio to the yardstick and the target it is held to (fandisk_n0.3 1.5×; open inputs 5×; the others 7.5×).
// Not part of the test suite (about 5 minutes on 2 cores at K = 1; see benchmarks/README.md, "Speed").
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "core/mesh_report.h"
#include "fit/fit_mesh.h"
#include "io/io.h"
#include "pipeline/pipeline.h"
#include "study_pairs.h"

namespace fs = std::filesystem;
using namespace normalflow;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

/// Taubin λ|μ smoothing, uniform weights, boundary fixed, on exactly welded positions: the yardstick. Returns
/// the seconds it took (the mesh is read before the clock starts). The neighbours are in one compressed array.
double taubin_yardstick(const Mesh& input, int iterations) {
    const Mesh m = weld_exact(input);
    const std::size_t n = m.positions.size();
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
    for (const Tri& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
            edges.emplace_back(std::min(a, b), std::max(a, b));
        }
    std::sort(edges.begin(), edges.end());
    std::vector<char> fixed(n, 0);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> unique;
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i == 1) fixed[edges[i].first] = fixed[edges[i].second] = 1;
        unique.push_back(edges[i]);
        i = j;
    }
    std::vector<std::uint32_t> start(n + 1, 0), nb(2 * unique.size());
    for (const auto& [a, b] : unique) ++start[a + 1], ++start[b + 1];
    for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
    {
        std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
        for (const auto& [a, b] : unique) nb[fill[a]++] = b, nb[fill[b]++] = a;
    }
    std::vector<Vec3d> xs(n), ys(n);
    Vec3d* x = xs.data();
    Vec3d* y = ys.data();
    for (std::size_t i = 0; i < n; ++i) x[i] = Vec3d(m.positions[i]);
    const double t0 = now();
    for (int it = 0; it < iterations; ++it)
        for (const double f : {0.5, -0.53}) {
            for (std::size_t i = 0; i < n; ++i) {
                y[i] = x[i];
                if (fixed[i] || start[i] == start[i + 1]) continue;
                Vec3d c(0, 0, 0);
                for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) c += x[nb[k]];
                y[i] = x[i] + (c / double(start[i + 1] - start[i]) - x[i]) * f;
            }
            std::swap(x, y);
        }
    const double seconds = now() - t0;
    volatile double sink = x[0].x;  // the result is used
    (void)sink;
    return seconds;
}

struct Input {
    std::string name;
    fs::path path;
};

}  // namespace

int main(int argc, char** argv) {
    fs::path data = NORMALFLOW_TEST_DATA;
    std::string md_path;
    std::vector<std::string> only;
    int threads = 0, repeat = 1;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has = i + 1 < argc;
        if (a == "--md" && has)
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
            std::fprintf(stderr, "nf_bench_speed: unknown or incomplete argument %s\n", a.c_str());
            return 2;
        }
    }
    const fs::path yard_path = data / "pairs_gnf/fandisk_n0.3.ply";
    if (!fs::exists(yard_path)) {
        std::fprintf(stderr, "nf_bench_speed: %s: not found (the yardstick's mesh)\n", yard_path.string().c_str());
        return 1;
    }
    std::vector<Input> inputs;
    for (const bench::Pair& p : bench::find_pairs(data)) inputs.push_back({p.set + "/" + p.noisy_name, p.noisy});
    for (const char* scan : {"real_scans/angel.ply", "real_scans/bun000_tri.ply"})
        if (fs::exists(data / scan)) inputs.push_back({scan, data / scan});
    std::erase_if(inputs, [&](const Input& in) { return !bench::selected(only, in.name); });
    const fs::path tmp = fs::temp_directory_path() / ("nf_bench_speed_" + std::to_string(::getpid()));
    fs::create_directories(tmp);
    const Mesh yard_mesh = read_mesh(yard_path.string());
    constexpr int kTaubinIterations = 20000;
    double unit = 1e300, slowest = 0;
    const auto yardstick = [&] {
        const double s = taubin_yardstick(yard_mesh, kTaubinIterations);
        unit = std::min(unit, s), slowest = std::max(slowest, s);
        std::printf("yardstick (Taubin, %d iterations on fandisk_n0.3, one thread): %.2f s\n", kTaubinIterations, s);
        std::fflush(stdout);
    };

    std::string md =
        "| input | triangles | open | result | repair s | voxelize s | smooth s | extract s | decimate s | total s | × "
        "yardstick "
        "| target |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    struct Row {
        std::string name, line;
        double seconds, target;
    };
    std::vector<Row> rows;
    int failures = 0;
    for (const Input& in : inputs) {
        yardstick();
        try {
            PipelineOptions o;
            o.scan.threads = o.smooth.threads = threads;
            double best = 1e300;
            PipelineReport rep;
            std::size_t triangles = 0;
            bool open = false;
            for (int k = 0; k < repeat; ++k) {
                const double t0 = now();
                const Mesh m = read_mesh(in.path.string());
                PipelineResult res = smooth_mesh(m, o);
                write_mesh((tmp / "out.ply").string(), res.mesh);
                const double s = now() - t0;
                if (s < best) best = s, rep = res.report;
                triangles = m.triangles.size();
                open = has_open_boundary(m);
            }
            const double target = in.name == "pairs_gnf/fandisk_n0.3" ? 1.5 : open ? 5.0 : 7.5;
            rows.push_back({in.name, "", best, target});
            char buf[512];
            std::snprintf(buf, sizeof buf, "| %s | %zu | %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |",
                          in.name.c_str(), triangles, open ? "open" : "closed",
                          rep.connectivity_kept ? "kept" : "re-meshed", rep.seconds.repair, rep.seconds.voxelize,
                          rep.seconds.smooth, rep.seconds.extract, rep.seconds.decimate, best);
            rows.back().line = buf;
            std::printf("%s %.2f s\n", in.name.c_str(), best);
            std::fflush(stdout);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "nf_bench_speed: %s: %s\n", in.name.c_str(), e.what());
            ++failures;
        }
    }
    yardstick();
    int met = 0;
    double total = 0;
    for (const Row& r : rows) {
        const double ratio = r.seconds / unit;
        met += ratio <= r.target;
        total += r.seconds;
        char buf[128];
        std::snprintf(buf, sizeof buf, " %.1f | %.1f%s |\n", ratio, r.target, ratio <= r.target ? "" : " (missed)");
        md += r.line + buf;
    }
    char tail[320];
    std::snprintf(
        tail, sizeof tail,
        "\nYardstick: %.2f s (Taubin, %d iterations, fandisk_n0.3, one thread; the fastest of its runs before "
        "each input and at the end, the slowest %.2f s). Within target: %d of %zu. Total %.1f s.\n",
        unit, kTaubinIterations, slowest, met, rows.size(), total);
    md += tail;
    std::fputs(md.c_str(), stdout);
    if (!md_path.empty())
        if (FILE* f = std::fopen(md_path.c_str(), "w")) {
            std::fputs(md.c_str(), f);
            std::fclose(f);
        }
    fs::remove_all(tmp);
    return failures ? 1 : 0;
}
