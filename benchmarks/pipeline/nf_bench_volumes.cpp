// nf_bench_volumes: volumes in (issue 23) — what the engine makes of a binary mask, a real MRI volume and a
// label map of a real surface, and what each stage costs, in one run.
//
//  1. Ball masks at 128³ (radius 40.3, spacing 1 × 1 × 1 and 1 × 1 × 2.5): the mask as extracted (its
//     staircase), then smoothed by each mode through smooth_volume_input, the bilateral default also at
//     1, 2 and 4 × the coarsest spacing as its length unit (the choice of kVolumeLengthScaleVoxels).
//     Columns: mean and max |r − R| over the vertices (voxels of the grid), the area-weighted mean angle
//     between the faces' normals and the sphere's (degrees), seconds of the smoothing.
//  2. medical/pve_2_whitematter.nii.gz at iso 0.5 (half its maximum): read, the isosurface as extracted,
//     smoothed by the default and by isotropic diffusion: triangles, seconds, and the distance between
//     each smoothed surface and the isosurface (surface_distance: mean, Hausdorff, mean normal angle).
//  3. medical/brainmesh_icbm152_lh.ply as a label map on a grid turned by 20° with spacing 0.9 × 0.9 × 1.5 mm
//     (the surface's inside, sampled from its scan conversion at 0.5 mm): the extraction and the smoothed
//     surfaces against the original mesh.
//  4. The default's length unit: label maps of the closed models of shared/data at 128 samples along the
//     longest side (spacing s, and s × s × 2s), the bilateral default at 0.75, 1, 1.5 and 2 × the coarsest
//     spacing, the mean normal angle to the model.
// The ratio column is each row's seconds over the extraction's in the same run.
//
// usage: nf_bench_volumes [--data DIR] [--threads N] [--only balls|mri|labels|study]
// Prints Markdown tables.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "core/mesh.h"
#include "extract/volume_sampler.h"
#include "io/formats/nifti.h"
#include "io/io.h"
#include "metrics/surface_distance.h"
#include "pipeline/pipeline.h"
#include "sdf/image_to_volume.h"

using namespace normalflow;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// The volume's zero level set, unsmoothed (volume_to_mesh), and its seconds: each table's baseline.
std::pair<Mesh, double> extract_timed(const Volume& v) {
    PipelineOptions raw;
    raw.smoothing = false;
    const auto t0 = Clock::now();
    Mesh m = volume_to_mesh(v, raw);
    return {std::move(m), since(t0)};
}

struct Run {
    const char* name;
    SmoothMode mode;
    double length_in_spacings;  // bilateral: length unit in coarsest spacings; 0 for the PDE modes
};

/// Radial errors of the vertices and the faces' normal error on a sphere (c, R), in voxels h and degrees.
void ball_row(const char* label, const Mesh& m, const Vec3d& c, double R, double h, double seconds, double base) {
    double mean = 0, worst = 0;
    for (const Vec3f& p : m.positions) {
        const double e = std::abs(norm(Vec3d{p.x, p.y, p.z} - c) - R) / h;
        mean += e;
        worst = std::max(worst, e);
    }
    mean /= double(m.positions.size());
    double angle = 0, area = 0;
    for (const Tri& t : m.triangles) {
        const Vec3f a = m.positions[t[0]], b = m.positions[t[1]], d = m.positions[t[2]];
        const Vec3d n = cross(Vec3d{b.x - a.x, b.y - a.y, b.z - a.z}, Vec3d{d.x - a.x, d.y - a.y, d.z - a.z});
        const double A = norm(n);
        if (!(A > 0)) continue;
        const Vec3d r = Vec3d{a.x + b.x + d.x, a.y + b.y + d.y, a.z + b.z + d.z} / 3.0 - c;
        angle += A * std::acos(std::clamp(dot(n / A, r / norm(r)), -1.0, 1.0));
        area += A;
    }
    std::printf("| %s | %.3f | %.3f | %.2f | %.2f | %.1f |\n", label, mean, worst,
                angle / area * 180 / std::numbers::pi, seconds, seconds / base);
}

void balls(const std::vector<Run>& runs) {
    std::printf("\n### Ball masks at 128³\n\n");
    for (const double sz : {1.0, 2.5}) {
        const Vec3d c{63.7, 64.2, 63.4};
        const double R = 40.3;
        ScalarImage im;
        im.dims = {128, 128, int(127 / sz) + 1};
        im.axes = {Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, sz}};
        im.values.resize(im.sample_count());
        for (int k = 0; k < im.dims[2]; ++k)
            for (int j = 0; j < 128; ++j)
                for (int i = 0; i < 128; ++i)
                    im.values[std::size_t(i) + 128 * (std::size_t(j) + 128 * std::size_t(k))] =
                        norm(Vec3d{double(i), double(j), k * sz} - c) < R ? 1.f : 0.f;
        std::printf("Spacing 1 × 1 × %.1f (%d × %d × %d samples):\n\n", sz, im.dims[0], im.dims[1], im.dims[2]);
        std::printf("| surface | mean \\|r − R\\| (voxels) | max | normal error (°) | seconds | × extraction |\n");
        std::printf("|---|---|---|---|---|---|\n");
        auto t0 = Clock::now();
        const Volume mask = image_to_volume(im, {.surface = {.label = 1.0}});
        const double t_convert = since(t0);
        const auto [stairs, base] = extract_timed(mask);
        ball_row("the mask, extracted", stairs, c, R, 1.0, base, base);
        std::printf("| (image_to_volume) | | | | %.2f | %.1f |\n", t_convert, t_convert / base);
        for (const Run& r : runs) {
            Volume v = mask;
            PipelineOptions o;
            o.smooth.mode = r.mode;
            if (r.length_in_spacings > 0) o.length_scale = r.length_in_spacings * sz;
            t0 = Clock::now();
            const PipelineResult res = smooth_volume_input(v, o);
            ball_row(r.name, res.mesh, c, R, 1.0, since(t0), base);
        }
        std::printf("\n");
    }
}

void compare_row(const char* label, const Mesh& m, const Mesh& ref, double seconds, double base) {
    const SurfaceDistance d = surface_distance(m, ref);
    std::printf("| %s | %zu | %.3f | %.3f | %.2f | %.2f | %.1f |\n", label, m.triangles.size(), d.mean, d.hausdorff,
                d.mean_normal_angle_deg, seconds, seconds / base);
}

void table_head(const char* ref) {
    std::printf(
        "| surface | triangles | mean distance to %s | Hausdorff | mean normal angle (°) | seconds | × extraction |\n",
        ref);
    std::printf("|---|---|---|---|---|---|---|\n");
}

void mri(const std::string& data) {
    const std::string path = data + "/medical/pve_2_whitematter.nii.gz";
    std::printf("\n### The white-matter MRI (%s, iso 0.5)\n\n", path.c_str());
    auto t0 = Clock::now();
    VolumeInput in;
    in.iso = 0.5;
    VolumeReadInfo info;
    const Volume v = read_volume(path, in, &info);
    const double t_read = since(t0);
    const auto [iso, base] = extract_timed(v);
    std::printf("Read and made a signed distance in %.2f s (%.1f × the extraction); grid %d × %d × %d, %s.\n\n", t_read,
                t_read / base, v.grid.dims[0], v.grid.dims[1], v.grid.dims[2],
                info.placed ? "placed by its sform" : "axis-aligned");
    table_head("the isosurface (mm)");
    compare_row("isosurface, extracted", iso, iso, base, base);
    for (const SmoothMode mode : {SmoothMode::Bilateral, SmoothMode::Isotropic}) {
        Volume w = v;
        PipelineOptions o;
        o.smooth.mode = mode;
        t0 = Clock::now();
        const PipelineResult r = smooth_volume_input(w, o);
        compare_row(mode == SmoothMode::Bilateral ? "default (bilateral), smoothed" : "isotropic, smoothed", r.mesh,
                    iso, since(t0), base);
    }
}

/// The inside of a closed mesh as a binary label image on a grid with unit axes u and spacing s, 4 spacings
/// of margin: each sample's sign in the mesh's scan conversion at `fine` (world units), interpolated.
ScalarImage label_image(const Mesh& mesh, const std::array<Vec3d, 3>& u, const std::array<double, 3>& s, double fine) {
    PipelineOptions scan;
    scan.smoothing = false;
    scan.scan.voxel_size = fine;
    const Volume sdf = mesh_to_volume(mesh, scan);
    const detail::VolumeSampler phi(sdf);
    ScalarImage im;
    for (int k = 0; k < 3; ++k) {
        double lo = 1e30, hi = -1e30;
        for (const Vec3f& p : mesh.positions) {
            lo = std::min(lo, dot(u[k], Vec3d{p.x, p.y, p.z}));
            hi = std::max(hi, dot(u[k], Vec3d{p.x, p.y, p.z}));
        }
        im.axes[k] = u[k] * s[k];
        im.dims[k] = int(std::ceil((hi - lo) / s[k])) + 9;
        im.origin = im.origin + u[k] * (lo - 4 * s[k]);
    }
    im.values.resize(im.sample_count());
    for (int z = 0; z < im.dims[2]; ++z)
        for (int y = 0; y < im.dims[1]; ++y)
            for (int x = 0; x < im.dims[0]; ++x)
                im.values[std::size_t(x) +
                          std::size_t(im.dims[0]) * (std::size_t(y) + std::size_t(im.dims[1]) * std::size_t(z))] =
                    phi.phi(im.origin + im.axes[0] * double(x) + im.axes[1] * double(y) + im.axes[2] * double(z),
                            nullptr) < 0;
    return im;
}

void label_map(const std::string& data) {
    const std::string path = data + "/medical/brainmesh_icbm152_lh.ply";
    std::printf("\n### A label map of the brain surface (0.9 × 0.9 × 1.5 mm, turned 20°)\n\n");
    const Mesh brain = read_mesh(path);
    const double a = 20 * std::numbers::pi / 180;
    const std::array<Vec3d, 3> u{Vec3d{std::cos(a), std::sin(a), 0}, Vec3d{-std::sin(a), std::cos(a), 0},
                                 Vec3d{0, 0, 1}};
    const Volume v = image_to_volume(label_image(brain, u, {0.9, 0.9, 1.5}, 0.5), {.surface = {.label = 1.0}});
    const auto [stairs, base] = extract_timed(v);
    table_head("the original (mm)");
    auto t0 = Clock::now();
    compare_row("label map, extracted", stairs, brain, base, base);
    for (const double L : {1.0, 2.0}) {
        Volume w = v;
        PipelineOptions o;
        o.length_scale = L * 1.5;
        t0 = Clock::now();
        const PipelineResult r = smooth_volume_input(w, o);
        const std::string label = "default (bilateral), length " + std::to_string(int(L)) + " × 1.5 mm";
        compare_row(label.c_str(), r.mesh, brain, since(t0), base);
    }
    Volume w = v;
    PipelineOptions o;
    o.smooth.mode = SmoothMode::Isotropic;
    t0 = Clock::now();
    const PipelineResult r = smooth_volume_input(w, o);
    compare_row("isotropic", r.mesh, brain, since(t0), base);
}

/// The default's length unit on label maps of every closed model: 128 samples along the longest side,
/// spacing s × s × s and s × s × 2s; the mean normal angle to the model (degrees) of the extraction and of
/// the bilateral default at 0.75, 1, 1.5 and 2 × the coarsest spacing.
void length_study(const std::string& data) {
    const std::vector<std::string> models{"pairs_gnf/fandisk_gt.ply",     "pairs_gnf/block_gt.ply",
                                          "pairs_gnf/twelve_gt.ply",      "pairs_gnf/trimstar_gt.ply",
                                          "pairs_gnf/sharpsphere_gt.ply", "cad/wingnut.ply",
                                          "organic/armadillo.ply",        "medical/brainmesh_icbm152_lh.ply"};
    const std::vector<double> lengths{0.75, 1.0, 1.5, 2.0};
    std::printf(
        "\n### The length unit of a volume input, on label maps of the closed models (128 samples along the longest "
        "side)\n\n");
    std::printf(
        "Mean normal angle to the model (°); the bilateral default with its length unit L × the coarsest spacing.\n\n");
    std::printf("| model | z spacing | extracted |");
    for (const double L : lengths) std::printf(" L = %.3g |", L);
    std::printf("\n|---|---|---|");
    for (std::size_t i = 0; i < lengths.size(); ++i) std::printf("---|");
    std::printf("\n");
    const std::array<Vec3d, 3> u{Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};
    std::vector<std::vector<double>> sums(2, std::vector<double>(lengths.size(), 0.0));
    int n = 0;
    for (const std::string& name : models) {
        Mesh m = read_mesh(data + "/" + name);
        double longest = 0;
        Vec3f lo = m.positions[0], hi = lo;
        for (const Vec3f& p : m.positions) {
            lo = Vec3f{std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
            hi = Vec3f{std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        }
        longest = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
        const double s = longest / 128;
        for (int z = 0; z < 2; ++z) {
            const std::array<double, 3> sp{s, s, z ? 2 * s : s};
            const Volume v = image_to_volume(label_image(m, u, sp, s / 2), {.surface = {.label = 1.0}});
            std::printf("| %s | %s | %.2f |", name.c_str(), z ? "2 s" : "s",
                        surface_distance(extract_timed(v).first, m).mean_normal_angle_deg);
            for (std::size_t l = 0; l < lengths.size(); ++l) {
                Volume w = v;
                PipelineOptions o;
                o.length_scale = lengths[l] * sp[2];
                const double angle = surface_distance(smooth_volume_input(w, o).mesh, m).mean_normal_angle_deg;
                sums[std::size_t(z)][l] += angle;
                std::printf(" %.2f |", angle);
            }
            std::printf("\n");
            std::fflush(stdout);
        }
        ++n;
    }
    for (int z = 0; z < 2; ++z) {
        std::printf("| **mean** | %s | |", z ? "2 s" : "s");
        for (const double x : sums[std::size_t(z)]) std::printf(" %.2f |", x / n);
        std::printf("\n");
    }
}

}  // namespace

int main(int argc, char** argv) {
    std::string data = NORMALFLOW_TEST_DATA, only;
    int threads = 0;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string k = argv[i];
        if (k == "--data")
            data = argv[i + 1];
        else if (k == "--threads")
            threads = std::atoi(argv[i + 1]);
        else if (k == "--only")
            only = argv[i + 1];
        else {
            std::fprintf(stderr,
                         "usage: nf_bench_volumes [--data DIR] [--threads N] [--only balls|mri|labels|study]\n");
            return 2;
        }
    }
    std::unique_ptr<tbb::global_control> gc;
    if (threads > 0) gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    try {
        if (only.empty() || only == "balls")
            balls({{"isotropic", SmoothMode::Isotropic, 0},
                   {"anisotropic (the paper's)", SmoothMode::Anisotropic, 0},
                   {"default (bilateral), length 1 × spacing", SmoothMode::Bilateral, 1},
                   {"default (bilateral), length 2 × spacing", SmoothMode::Bilateral, 2},
                   {"default (bilateral), length 4 × spacing", SmoothMode::Bilateral, 4}});
        if (only.empty() || only == "mri") mri(data);
        if (only.empty() || only == "labels") label_map(data);
        if (only.empty() || only == "study") length_study(data);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nf_bench_volumes: %s\n", e.what());
        return 1;
    }
}
