#include "io/render/comparison_pictures.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <set>
#include <system_error>

#include "core/errors.h"
#include "io/render/png.h"

namespace normalflow {

std::vector<float> vertex_distances(const Mesh& m, const ClosestTriangleQuery& reference) {
    std::vector<float> d(m.positions.size(), 0.0f);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, d.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i < r.end(); ++i) {
                              const ClosestHit h = reference.closest(Vec3d(m.positions[i]));
                              d[i] = h.found() ? float(std::sqrt(h.squared_distance)) : 0.0f;
                          }
                      });
    return d;
}

namespace {

/// The file stems of ComparisonPicturesOptions::names (see there), or mesh<i>.
std::vector<std::string> file_stems(const std::vector<std::string>& names, std::size_t count) {
    std::vector<std::string> out;
    std::set<std::string> used;
    for (std::size_t i = 0; i < count; ++i) {
        std::string s = "mesh" + std::to_string(i);
        if (!names.empty()) {
            std::string stem = std::filesystem::path(names[i]).stem().string();
            for (char& c : stem)
                if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_')) c = '_';
            s = (i == 0 ? "reference_" : "") + (stem.empty() ? "mesh" + std::to_string(i) : stem);
        }
        std::string unique = s;
        for (int k = 2; used.count(unique) > 0; ++k) unique = s + "_" + std::to_string(k);
        used.insert(unique);
        out.push_back(unique);
    }
    return out;
}

}  // namespace

ComparisonPictures write_comparison_pictures(const std::string& dir, const Mesh& reference,
                                             std::span<const Mesh> candidates, const ComparisonPicturesOptions& opt) {
    const auto t0 = std::chrono::steady_clock::now();
    check_mesh(reference, "write_comparison_pictures: reference");
    if (reference.triangles.empty()) throw InvalidInput("write_comparison_pictures: the reference has no triangles");
    for (std::size_t i = 0; i < candidates.size(); ++i)
        check_mesh(candidates[i], ("write_comparison_pictures: candidate " + std::to_string(i + 1)).c_str());
    if (!opt.names.empty() && opt.names.size() != candidates.size() + 1)
        throw InvalidInput("write_comparison_pictures: " + std::to_string(opt.names.size()) + " names for " +
                           std::to_string(candidates.size() + 1) + " meshes (the reference and the candidates)");
    if (!(opt.distance_percentile > 0 && opt.distance_percentile <= 100))
        throw InvalidInput("write_comparison_pictures: distance_percentile must be in (0, 100]");

    const std::filesystem::path folder = std::filesystem::path(dir) / opt.subfolder;
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec)
        throw IoError("write_comparison_pictures: " + folder.string() + ": cannot create the folder: " + ec.message());
    const std::string prefix = opt.subfolder.empty() ? std::string() : opt.subfolder + "/";

    // Meshes: the reference (index 0) and the candidates; distances of each to the reference.
    std::vector<const Mesh*> meshes{&reference};
    for (const Mesh& c : candidates) meshes.push_back(&c);
    std::vector<std::vector<float>> dist(meshes.size());
    dist[0].assign(reference.positions.size(), 0.0f);
    if (!candidates.empty()) {
        const auto query = make_bvh_query(reference);
        for (std::size_t i = 1; i < meshes.size(); ++i) dist[i] = vertex_distances(*meshes[i], *query);
    }

    ComparisonPictures out;
    out.views = {"front", "side", "oblique"};
    const Vec3d directions[3] = {{0, 0, -1}, {-1, 0, 0}, {-1, -1, -1}};
    const Box3d box = bounding_box(reference);
    std::vector<Camera> cameras;
    for (const Vec3d& d : directions) cameras.push_back(camera_from_box(box, d, opt.projection));

    const std::vector<std::string> stems = file_stems(opt.names, meshes.size());
    double largest = 0;
    out.meshes.resize(meshes.size());
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        double mx = 0;
        for (float v : dist[i]) mx = std::max(mx, double(v));
        out.meshes[i].max_distance = mx;
        largest = std::max(largest, mx);
        for (const std::string& v : out.views) {
            const std::string stem = prefix + stems[i] + "_" + v;
            out.meshes[i].shaded.push_back(stem + ".png");
            out.meshes[i].distance.push_back(stem + "_distance.png");
        }
    }
    // The colour range: a high percentile of every candidate's vertex distances together (one range for all, so
    // that the pictures compare), unless given; the largest distance when that percentile is 0 (most vertices on
    // the reference).
    double range = opt.distance_max;
    if (!(range > 0) && candidates.size() > 0) {
        std::vector<float> all;
        for (std::size_t i = 1; i < dist.size(); ++i) all.insert(all.end(), dist[i].begin(), dist[i].end());
        if (!all.empty()) {
            const auto rank = std::size_t(std::ceil(opt.distance_percentile / 100.0 * double(all.size())));
            const auto kth = all.begin() + std::ptrdiff_t(std::min(rank, all.size()) - 1);
            std::nth_element(all.begin(), kth, all.end());
            range = *kth;
            out.percentile = opt.distance_percentile;
        }
        if (!(range > 0)) {
            range = largest;
            out.percentile = 100.0;
        }
    }
    if (!(range > 0)) {  // every candidate on the reference
        range = 1e-3 * std::max(box.diagonal(), 1e-30);
        out.percentile = 0.0;
    }
    out.distance_max = range;
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        std::size_t over = 0;
        for (float v : dist[i]) over += double(v) > range;
        out.meshes[i].clipped_fraction = dist[i].empty() ? 0.0 : double(over) / double(dist[i].size());
    }

    const std::filesystem::path root(dir);
    const std::size_t nviews = out.views.size();
    const std::size_t jobs = meshes.size() * nviews * 2 + 1;
    tbb::parallel_for(std::size_t(0), jobs, [&](std::size_t job) {
        if (job + 1 == jobs) {
            LegendOptions lo;
            lo.width = std::max(64, opt.render.width);
            lo.over_color = opt.over_color;
            out.legend = prefix + "legend.png";
            write_png((root / out.legend).string(), render_legend(ColorMap::Viridis, 0.0, range, lo));
            return;
        }
        const std::size_t mesh = job / (nviews * 2), view = (job / 2) % nviews;
        const bool distance = job % 2 == 1;
        RenderOptions ro = opt.render;
        std::string path;
        if (distance) {
            ro.vertex_scalars = dist[mesh];
            ro.color_map = ColorMap::Viridis;
            ro.scalar_min = 0.0;
            ro.scalar_max = range;
            ro.over_color = opt.over_color;
            path = out.meshes[mesh].distance[view];
        } else {
            ro.vertex_scalars = {};
            path = out.meshes[mesh].shaded[view];
        }
        write_png((root / path).string(), render_mesh(*meshes[mesh], cameras[view], ro));
    });
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

}  // namespace normalflow
