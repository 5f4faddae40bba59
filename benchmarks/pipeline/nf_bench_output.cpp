// nf_bench_output: the output stage on real models, from scan conversion to the files users get.
//
// For each model: repair, scan-convert at resolution R and extract (pipeline/ smooth_mesh without
// the smoothing stage; binary PLY: faces, bytes), cleanup to a target face count (faces, bytes, time, sampled Hausdorff to the extracted mesh, self-intersections
// left), Draco .drc (bytes, encode time, sampled Hausdorff of the decoded mesh to its input), Draco
// .glb (bytes, time), and TetGen on the decimated surface (tetrahedra, smallest dihedral angle, time).
// Distances are in voxels of the grid (h = longest side / R).
//
// Models (shared/data): pairs_gnf/fandisk_gt.ply (CAD: planes, creases, corners), organic/armadillo.ply
// (organic, closed), medical/brainmesh_icbm152_lh.ply (MRI cortex surface: highly folded).
//
// usage: nf_bench_output [--data DIR] [--resolution R] [--target-faces N] [--min-dihedral DEG]
//                        [--out DIR] [--only SUBSTRING] [--no-tetgen] [--json]
// Prints a Markdown table (and, with --json, one JSON object with a "models" array on the last line).

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "io/cgal/cleanup.h"
#include "io/draco/draco_io.h"
#include "io/io.h"
#include "io/tetgen/tetmesh.h"
#include "pipeline/pipeline.h"

namespace fs = std::filesystem;
using namespace normalflow;

namespace {

double since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Row {
    std::string model;
    double h = 0;
    std::size_t extract_faces = 0, extract_bytes = 0;
    double extract_s = 0;
    std::size_t clean_faces = 0, clean_bytes = 0, clean_si = 0;
    double clean_s = 0, clean_haus = 0;
    std::size_t drc_bytes = 0;
    double drc_s = 0, drc_haus = 0;
    std::size_t glb_bytes = 0;
    double glb_s = 0;
    std::size_t tets = 0;
    double tet_min_dihedral = 0, tet_s = 0;
    std::string tet_error;
};

}  // namespace

int main(int argc, char** argv) {
    fs::path data = fs::path(__FILE__).parent_path() / "../../../shared/data";
    int resolution = 256;
    std::size_t target_faces = 20000;
    double min_dihedral = TetmeshOptions{}.min_dihedral_deg;
    fs::path out = fs::temp_directory_path() / "nf_bench_output";
    std::vector<std::string> only;
    bool json = false, tetgen = true;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "nf_bench_output: %s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--data")
            data = next();
        else if (a == "--resolution")
            resolution = std::stoi(next());
        else if (a == "--target-faces")
            target_faces = std::stoul(next());
        else if (a == "--min-dihedral")
            min_dihedral = std::stod(next());
        else if (a == "--out")
            out = next();
        else if (a == "--only")
            only.push_back(next());
        else if (a == "--no-tetgen")
            tetgen = false;
        else if (a == "--json")
            json = true;
        else {
            std::fprintf(stderr, "nf_bench_output: unknown argument %s\n", a.c_str());
            return 2;
        }
    }
    fs::create_directories(out);
    const std::vector<std::string> models = {"pairs_gnf/fandisk_gt.ply", "organic/armadillo.ply",
                                             "medical/brainmesh_icbm152_lh.ply"};
    std::vector<Row> rows;
    int failures = 0;
    for (const auto& name : models) {
        bool skip = !only.empty();
        for (const auto& s : only) skip = skip && name.find(s) == std::string::npos;
        if (skip) continue;
        const fs::path in = data / name;
        if (!fs::exists(in)) {
            std::fprintf(stderr, "nf_bench_output: %s missing\n", in.string().c_str());
            ++failures;
            continue;
        }
        try {
            Row r;
            r.model = name;
            const std::string stem = fs::path(name).stem().string();
            const Mesh src = read_mesh(in.string());
            // The shipped pipeline without the smoothing stage (pipeline/ smooth_mesh: repair, scan
            // conversion, extraction); decimation runs below, on its own, to be measured.
            PipelineOptions po;
            po.scan.resolution = resolution;
            po.smoothing = false;
            auto t0 = std::chrono::steady_clock::now();
            const PipelineResult ext_result = smooth_mesh(src, po);
            const PipelineReport& pr = ext_result.report;
            const Mesh& ext = ext_result.mesh;
            r.extract_s = since(t0);
            r.h = pr.scan.grid.voxel_size;
            const fs::path ext_path = out / (stem + "_extract.ply");
            write_mesh(ext_path.string(), ext);
            r.extract_faces = ext.triangles.size();
            r.extract_bytes = fs::file_size(ext_path);

            Mesh dec = ext;
            cgal::CleanupOptions co;
            co.reduction = cgal::CleanupReduction::FaceCount;
            co.target_faces = target_faces;
            const cgal::CleanupReport cr = cgal::cleanup_mesh(dec, co);
            r.clean_s = cr.seconds;
            r.clean_faces = dec.triangles.size();
            r.clean_haus = cr.hausdorff;
            r.clean_si = cr.self_intersections;
            const fs::path dec_path = out / (stem + "_clean.ply");
            write_mesh(dec_path.string(), dec);
            r.clean_bytes = fs::file_size(dec_path);

            const fs::path drc = out / (stem + ".drc");
            t0 = std::chrono::steady_clock::now();
            write_drc(drc.string(), dec);
            r.drc_s = since(t0);
            r.drc_bytes = fs::file_size(drc);
            r.drc_haus = cgal::sampled_hausdorff(read_drc(drc.string()), dec).hausdorff;

            const fs::path glb = out / (stem + ".glb");
            t0 = std::chrono::steady_clock::now();
            write_draco_glb(glb.string(), dec);
            r.glb_s = since(t0);
            r.glb_bytes = fs::file_size(glb);

            if (tetgen) {
                try {
                    TetmeshOptions to;
                    to.min_dihedral_deg = min_dihedral;
                    TetmeshReport tr;
                    tetrahedralize(dec, to, &tr);
                    r.tets = tr.tetrahedra;
                    r.tet_min_dihedral = tr.min_dihedral_deg;
                    r.tet_s = tr.seconds;
                } catch (const std::exception& e) {
                    r.tet_error = e.what();
                }
            }
            rows.push_back(r);
            std::fprintf(stderr, "nf_bench_output: %s done\n", name.c_str());
        } catch (const std::exception& e) {
            std::fprintf(stderr, "nf_bench_output: %s: %s\n", name.c_str(), e.what());
            ++failures;
        }
    }

    std::printf("resolution %d, cleanup --target-faces %zu, tetmesh --min-dihedral %g; Hausdorff in voxels (h)\n\n",
                resolution, target_faces, min_dihedral);
    std::printf(
        "| model | extract: faces, PLY bytes, s | cleanup: faces, PLY bytes, s, Hausdorff, SI left | "
        ".drc: bytes, s, Hausdorff | .glb (Draco): bytes, s | TetGen: tets, min dihedral, s |\n");
    std::printf("|---|---|---|---|---|---|\n");
    for (const Row& r : rows) {
        char tet[160];
        if (!tetgen)
            std::snprintf(tet, sizeof tet, "not run");
        else if (!r.tet_error.empty())
            std::snprintf(tet, sizeof tet, "failed: %.120s", r.tet_error.c_str());
        else
            std::snprintf(tet, sizeof tet, "%zu, %.2f°, %.1f", r.tets, r.tet_min_dihedral, r.tet_s);
        std::printf("| %s | %zu, %zu, %.1f | %zu, %zu, %.1f, %.3f, %zu | %zu, %.3f, %.4f | %zu, %.3f | %s |\n",
                    r.model.c_str(), r.extract_faces, r.extract_bytes, r.extract_s, r.clean_faces, r.clean_bytes,
                    r.clean_s, r.clean_haus / r.h, r.clean_si, r.drc_bytes, r.drc_s, r.drc_haus / r.h, r.glb_bytes,
                    r.glb_s, tet);
    }
    if (json) {  // one JSON object on the last line
        std::printf("{\"resolution\":%d,\"target_faces\":%zu,\"min_dihedral\":%g,\"models\":[", resolution,
                    target_faces, min_dihedral);
        for (std::size_t i = 0; i < rows.size(); ++i) {
            const Row& r = rows[i];
            std::printf(
                "%s{\"model\":\"%s\",\"resolution\":%d,\"voxel_size\":%.9g,\"extract_faces\":%zu,"
                "\"extract_bytes\":%zu,\"extract_seconds\":%.4f,\"cleanup_faces\":%zu,\"cleanup_bytes\":%zu,"
                "\"cleanup_seconds\":%.4f,\"cleanup_hausdorff\":%.9g,\"cleanup_self_intersections\":%zu,"
                "\"drc_bytes\":%zu,\"drc_seconds\":%.4f,\"drc_hausdorff\":%.9g,\"glb_bytes\":%zu,"
                "\"glb_seconds\":%.4f,\"tetrahedra\":%zu,\"min_dihedral_deg\":%.4f,\"tetgen_seconds\":%.4f,"
                "\"tetgen_ok\":%s}",
                i ? "," : "", r.model.c_str(), resolution, r.h, r.extract_faces, r.extract_bytes, r.extract_s,
                r.clean_faces, r.clean_bytes, r.clean_s, r.clean_haus, r.clean_si, r.drc_bytes, r.drc_s, r.drc_haus,
                r.glb_bytes, r.glb_s, r.tets, r.tet_min_dihedral, r.tet_s,
                (tetgen && r.tet_error.empty()) ? "true" : "false");
        }
        std::printf("]}\n");
    }
    return failures ? 1 : 0;
}
