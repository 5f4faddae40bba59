// nf_bench_faces START GT [--guide MESH] [--rounds N] [--vsteps N] [--sigma-r S] [--sigma-s S] [--rings R] [--no-patch]
//                [--own B] [--discrepancy D | --risk | --sweep N] [--trace N [--sure EPS [--sure-normal-rounds K]
//                [--sure-sigma S] [--sure-oracle-sigma]]] [--out FILE]
// --trace N: N rounds one at a time, without guidance; after each, one line: the round, the vertices' RMS distance
// from START and the noise estimate of the result (both over START's estimated noise), the face-by-face angle.
// --sure EPS (with --trace): before the trace, the input's error along its vertex normals against GT (over the
// estimated noise); with each round one more line, "sure ROUND ESTIMATE TRUE div/n D": Monte-Carlo SURE (Stein's
// unbiased risk estimate; Ramani et al. 2008) of the vertices' RMS error along the normals, from a copy of START moved
// by EPS times the noise along the normals with random signs, and the true RMS error against GT (both over the
// estimated noise). --sure-normal-rounds K (3): the normals of START filtered K rounds (0: START's own).
// --sure-sigma S: SURE with the noise S (world units) instead of the estimate. --sure-oracle-sigma: SURE with the input's true error along the normals for the noise (an oracle, to tell the
// estimator's bias from the noise estimate's).
// --risk: as --discrepancy 1, with the risk stop instead (FaceFilterOptions::stop_noise, the noise estimated along
// the steady normals).
// --sweep N: for k = 1..N, k rounds from START in one run: "k angle error", the true RMS error along the steady
// normals over the estimated noise (a multi-round run keeps σ_s of its start, where --trace restarts every round).
// --discrepancy D: rounds one at a time, without guidance, until the vertices moved D times START's estimated
// noise (estimate_noise), at most 40: the rule of the kept mesh's default filter (KeepFilter::Faces) at D = 1.
// The face filter of the kept mesh (fit/face_filter.h) on its own: START (e.g. a kept result, or the noisy
// mesh) is filtered, guided by GUIDE's face normals where given (a kept result: the volume's normals), and
// measured face by face against GT (the papers' metric: the plain mean over faces of the normal angle).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "core/stopwatch.h"
#include "fit/face_filter.h"
#include "io/io.h"
#include "metrics/compare.h"
#include "metrics/noise.h"

using namespace normalflow;

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: nf_bench_faces START GT [options]\n");
        return 2;
    }
    Mesh m = read_mesh(argv[1]);
    const Mesh gt = read_mesh(argv[2]);
    FaceFilterOptions o;
    std::string guide_path, out;
    double discrepancy = 0, sure_eps = 0;
    int trace = 0, sure_normal_rounds = 3;
    bool sure_oracle_sigma = false, risk = false;
    int sweep = 0;
    double sure_sigma_given = 0;
    for (int i = 3; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has = i + 1 < argc;
        if (a == "--guide" && has)
            guide_path = argv[++i];
        else if (a == "--rounds" && has)
            o.normal_steps = std::atoi(argv[++i]);
        else if (a == "--trace" && has)
            trace = std::atoi(argv[++i]);
        else if (a == "--vsteps" && has)
            o.vertex_steps = std::atoi(argv[++i]);
        else if (a == "--sigma-r" && has)
            o.sigma_r = std::atof(argv[++i]);
        else if (a == "--sigma-s" && has)
            o.sigma_s = std::atof(argv[++i]);
        else if (a == "--rings" && has)
            o.rings = std::atoi(argv[++i]);
        else if (a == "--no-patch")
            o.patch_guidance = false;
        else if (a == "--own" && has)
            o.own_patch_bias = std::atof(argv[++i]);
        else if (a == "--out" && has)
            out = argv[++i];
        else if (a == "--sure" && has)
            sure_eps = std::atof(argv[++i]);
        else if (a == "--sure-normal-rounds" && has)
            sure_normal_rounds = std::atoi(argv[++i]);
        else if (a == "--sure-sigma" && has)
            sure_sigma_given = std::atof(argv[++i]);
        else if (a == "--sure-oracle-sigma")
            sure_oracle_sigma = true;
        else if (a == "--sweep" && has)
            sweep = std::atoi(argv[++i]);
        else if (a == "--risk")
            risk = true;
        else if (a == "--discrepancy" && has)
            discrepancy = std::atof(argv[++i]);
        else {
            std::fprintf(stderr, "nf_bench_faces: unknown argument %s\n", a.c_str());
            return 2;
        }
    }
    std::vector<Vec3d> guidance;
    if (!guide_path.empty()) {
        const Mesh g = read_mesh(guide_path);
        for (const Tri& t : g.triangles) guidance.push_back(normalized(face_area_vector(g, t)));
    }
    // the mean angle of per-face unit normals (zero: none) to the faces of ref (the ground truth unless given), degrees
    const auto mean_angle = [&](const std::vector<Vec3d>& normals, const Mesh& ref) {
        double sum = 0;
        std::size_t count = 0;
        for (std::size_t f = 0; f < normals.size(); ++f) {
            const Vec3d b = face_area_vector(ref, ref.triangles[f]);
            if (!(norm(normals[f]) > 0) || !(norm(b) > 0)) continue;
            sum += std::acos(std::clamp(dot(normals[f], b) / norm(b), -1.0, 1.0)) * 57.29577951308232;
            ++count;
        }
        return count ? sum / double(count) : 0.0;
    };
    if (!guidance.empty()) std::printf("the guidance itself: %.2f deg\n", mean_angle(guidance, gt));
    const double before = correspondence_errors(m, gt).mean_face_angle_deg;
    if (trace > 0) {
        const double noise = estimate_noise(m).sigma;
        const Mesh m0 = m;
        FaceFilterOptions d = o;
        d.normal_steps = 1;
        // --sure EPS: Monte-Carlo SURE of the vertices' error along the input's vertex normals (Ramani et al. 2008):
        // a copy of the input moved by EPS·noise·b (b = ±1 at random) along the normals runs the same rounds
        Mesh mp = m;
        double sure_sigma = noise;
        std::vector<Vec3d> nrm(m.positions.size());
        std::vector<double> b(m.positions.size());
        if (sure_eps > 0) {
            Mesh t = m;
            if (sure_normal_rounds > 0) {  // the normals of a filtered copy: steadier than the noisy ones
                FaceFilterOptions q = o;
                q.normal_steps = sure_normal_rounds;
                filter_faces(t, q);
            }
            compute_vertex_normals(t);
            if (sure_normal_rounds < 0) {  // the steady normals (steady_vertex_normals) of the input
                const std::vector<Vec3d> steady = steady_vertex_normals(m);
                for (std::size_t i = 0; i < steady.size(); ++i) t.normals[i] = Vec3f(steady[i]);
            }
            std::mt19937_64 rng(7);
            for (std::size_t i = 0; i < nrm.size(); ++i) {
                nrm[i] = normalized(Vec3d(t.normals[i]));
                b[i] = (rng() & 1) ? 1.0 : -1.0;
                mp.positions[i] = Vec3f(Vec3d(m.positions[i]) + sure_eps * noise * b[i] * nrm[i]);
            }
        }
        if (sure_eps > 0) {
            double truth = 0;
            for (std::size_t i = 0; i < nrm.size(); ++i) {
                const double ei = dot(Vec3d(m.positions[i]) - Vec3d(gt.positions[i]), nrm[i]);
                truth += ei * ei;
            }
            std::printf("input: the error along the normals %.3f of the estimated noise\n",
                        std::sqrt(truth / double(nrm.size())) / noise);
            if (sure_sigma_given > 0) sure_sigma = sure_sigma_given;
            if (sure_oracle_sigma) sure_sigma = std::sqrt(truth / double(nrm.size()));
        }
        for (int r = 1; r <= trace; ++r) {
            filter_faces(m, d);
            if (sure_eps > 0) {
                filter_faces(mp, d);
                double res = 0, div = 0, truth = 0;
                for (std::size_t i = 0; i < nrm.size(); ++i) {
                    const double ri = dot(Vec3d(m.positions[i]) - Vec3d(m0.positions[i]), nrm[i]);
                    res += ri * ri;
                    div += b[i] * dot(Vec3d(mp.positions[i]) - Vec3d(m.positions[i]), nrm[i]) / (sure_eps * noise);
                    const double ei = dot(Vec3d(m.positions[i]) - Vec3d(gt.positions[i]), nrm[i]);
                    truth += ei * ei;
                }
                const double n = double(nrm.size()), s2 = sure_sigma * sure_sigma;
                const double sure = res - n * s2 + 2 * s2 * div;
                std::printf("sure %d %.4f %.4f div/n %.4f res %.4f\n", r, std::sqrt(std::max(sure, 0.0) / n) / noise,
                            std::sqrt(truth / n) / noise, div / n, res / n / s2);
            }
            double sum = 0;
            for (std::size_t i = 0; i < m.positions.size(); ++i) {
                const Vec3d v = Vec3d(m.positions[i]) - Vec3d(m0.positions[i]);
                sum += dot(v, v);
            }
            std::printf("%d %.3f %.3f %.2f\n", r, std::sqrt(sum / double(m.positions.size())) / noise,
                        estimate_noise(m).sigma / noise, correspondence_errors(m, gt).mean_face_angle_deg);
        }
        return 0;
    }
    if (sweep > 0) {
        const int last = sweep;
        const std::vector<Vec3d> steady = steady_vertex_normals(m);
        const double noise = estimate_noise(m).sigma;
        for (int k = 1; k <= last; ++k) {
            Mesh t = m;
            FaceFilterOptions d = o;
            d.normal_steps = k;
            filter_faces(t, d);
            double truth = 0;
            for (std::size_t i = 0; i < t.positions.size(); ++i) {
                const double ei = dot(Vec3d(t.positions[i]) - Vec3d(gt.positions[i]), steady[i]);
                truth += ei * ei;
            }
            std::printf("%d %.2f %.4f\n", k, correspondence_errors(t, gt).mean_face_angle_deg,
                        std::sqrt(truth / double(t.positions.size())) / noise);
        }
        return 0;
    }
    if (discrepancy > 0 || risk) {
        FaceFilterOptions d = o;
        d.normal_steps = 40;
        if (risk)
            d.stop_noise = estimate_noise(m, NoiseNormals::Steady).sigma;
        else
            d.stop_displacement = discrepancy * estimate_noise(m).sigma;
        Stopwatch c;
        std::vector<Vec3d> target;
        const FaceFilterReport r = filter_faces(m, d, nullptr, nullptr, &target);
        std::printf(
            "%s %.2f: %d rounds (%d run), %.2f deg, %.2f s, faces off their filtered normals %.2f deg, %zu reverted, "
            "estimated error %.4f of the noise\n",
            risk ? "risk" : "discrepancy", risk ? 1.0 : discrepancy, r.rounds, r.rounds_run,
            correspondence_errors(m, gt).mean_face_angle_deg, c.lap(), mean_angle(target, m), r.reverted_moves,
            d.stop_noise > 0 ? r.estimated_error / d.stop_noise : 0.0);
        if (!out.empty()) write_mesh(out, m);
        return 0;
    }
    Stopwatch clock;
    std::vector<Vec3d> filtered;
    const FaceFilterReport r = filter_faces(m, o, guidance.empty() ? nullptr : &guidance, nullptr, &filtered);
    const double seconds = clock.lap();
    const CorrespondenceErrors e = correspondence_errors(m, gt);
    std::printf("%s: %.2f -> %.2f deg face by face (vertex %.3e of diag), %zu reverted, %.2f s\n", argv[1], before,
                e.mean_face_angle_deg, e.mean_vertex_distance_relative, r.reverted_moves, seconds);
    // where the error sits: turned faces (over 90°), large (over 20°), and the mean of the rest
    std::size_t over90 = 0, over20 = 0, rest = 0;
    double sum_rest = 0.0, sum90 = 0.0, sum20 = 0.0;
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
        const Vec3d a = face_area_vector(m, m.triangles[f]), b = face_area_vector(gt, gt.triangles[f]);
        if (!(norm(a) > 0) || !(norm(b) > 0)) continue;
        const double deg = std::acos(std::clamp(dot(a, b) / (norm(a) * norm(b)), -1.0, 1.0)) * 57.29577951308232;
        if (deg > 90)
            ++over90, sum90 += deg;
        else if (deg > 20)
            ++over20, sum20 += deg;
        else
            ++rest, sum_rest += deg;
    }
    std::printf("  the filtered normals themselves: %.2f deg\n", mean_angle(filtered, gt));
    const double all = double(over90 + over20 + rest);
    std::printf(
        "  share of the mean: over 90 deg %zu faces %.2f, 20-90 deg %zu faces %.2f, rest %zu faces %.2f (their mean "
        "%.2f)\n",
        over90, sum90 / all, over20, sum20 / all, rest, sum_rest / all, sum_rest / double(rest));
    if (!out.empty()) write_mesh(out, m);
}
