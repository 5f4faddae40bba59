#include "extract/surface_attributes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "extract/volume_sampler.h"

namespace normalflow {

void set_volume_normals(Mesh& m, const Volume& v) {
    check_mesh(m, "set_volume_normals");
    v.check("set_volume_normals");
    const detail::VolumeSampler S(v);
    m.normals.assign(m.positions.size(), Vec3f{});
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.positions.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              const Vec3d p(m.positions[i]);
                              if (S.outside_band(p)) continue;
                              Vec3d g;
                              S.phi(p, &g);
                              const double len = norm(g);
                              if (len > 0 && std::isfinite(len)) m.normals[i] = Vec3f(g / len);
                          }
                      });
}

std::vector<char> faces_against_volume(const Mesh& m, const Volume& v) {
    check_mesh(m, "faces_against_volume");
    v.check("faces_against_volume");
    const detail::VolumeSampler S(v);
    std::vector<char> against(m.triangles.size(), 0);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, m.triangles.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t f = r.begin(); f != r.end(); ++f) {
                const Tri& t = m.triangles[f];
                against[f] =
                    S.turned_against(Vec3d(m.positions[t[0]]), Vec3d(m.positions[t[1]]), Vec3d(m.positions[t[2]]));
            }
        });
    return against;
}

void set_face_normals(Mesh& m) {
    check_mesh(m, "set_face_normals");
    std::vector<std::uint32_t> group;
    const Mesh w = weld_exact(m, &group);
    std::vector<Vec3d> sum(w.positions.size(), Vec3d(0, 0, 0));
    for (const Tri& t : w.triangles) {
        const Vec3d a = face_area_vector(w, t);  // |a| = 2 area: area weighting
        for (const std::uint32_t v : t) sum[v] = sum[v] + a;
    }
    m.normals.assign(m.positions.size(), Vec3f{});
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        const Vec3d& s = sum[group[i]];
        const double len = norm(s);
        if (len > 0 && std::isfinite(len)) m.normals[i] = Vec3f(s / len);
    }
}

void transfer_colors(Mesh& m, const Mesh& source, const ClosestTriangleQuery& q) {
    check_mesh(m, "transfer_colors");
    check_mesh(source, "transfer_colors");
    if (!source.has_colors()) return;
    m.colors.assign(m.positions.size(), Rgba8{255, 255, 255, 255});
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, m.positions.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const ClosestHit h = q.closest(Vec3d(m.positions[i]));
                if (!h.found()) continue;
                const Tri& t = source.triangles[h.triangle];
                // barycentric coordinates of the closest point, clamped (the first corner's
                // colour for a zero-area face)
                double w[3] = {1, 0, 0};
                if (barycentric_coordinates(h.point, Vec3d(source.positions[t[0]]), Vec3d(source.positions[t[1]]),
                                            Vec3d(source.positions[t[2]]), w)) {
                    double total = 0;
                    for (double& x : w) total += (x = std::max(x, 0.0));
                    for (double& x : w) x = total > 0 ? x / total : 1.0 / 3;
                }
                Rgba8 out{};
                for (std::size_t k = 0; k < 4; ++k) {
                    double x = 0;
                    for (std::size_t c3 = 0; c3 < 3; ++c3) x += w[c3] * source.colors[t[c3]][k];
                    out[k] = std::uint8_t(std::lround(std::clamp(x, 0.0, 255.0)));
                }
                m.colors[i] = out;
            }
        });
}

}  // namespace normalflow
