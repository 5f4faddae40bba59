#include "fit/fit_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/errors.h"
#include "extract/volume_sampler.h"
#include "fit/weld.h"

namespace normalflow {

using detail::boundary_vertices;
using detail::weld;

namespace {

/// The volume's unit normal at c: the normal map's where it has one, else ∇φ's; zero outside the band.
Vec3d volume_normal(const detail::VolumeSampler& S, const NormalMap* targets, const Vec3d& c) {
    Vec3d n(0, 0, 0);
    if (S.outside_band(c)) return n;
    if (targets && detail::sample_normal_map(*targets, c, n)) return n;
    Vec3d g;
    S.phi(c, &g);
    const double len = norm(g);
    return len > 1e-12 ? g / len : Vec3d(0, 0, 0);
}

}  // namespace

std::vector<Vec3d> volume_normals_at_faces(const Mesh& m, const Volume& v, const NormalMap* targets) {
    v.check("volume_normals_at_faces");
    const detail::VolumeSampler S(v);
    std::vector<Vec3d> out(m.triangles.size());
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, out.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t f = r.begin(); f != r.end(); ++f) {
                const Tri& t = m.triangles[f];
                const Vec3d c = (Vec3d(m.positions[t[0]]) + Vec3d(m.positions[t[1]]) + Vec3d(m.positions[t[2]])) / 3.0;
                out[f] = volume_normal(S, targets, c);
            }
        });
    return out;
}

bool has_open_boundary(const Mesh& m) {
    std::vector<std::uint32_t> group;
    const std::size_t n = weld(m, group);
    const std::vector<char> on = boundary_vertices(m, group, n);
    return std::find(on.begin(), on.end(), 1) != on.end();
}

FitReport fit_mesh_to_volume(Mesh& m, const Volume& v, const FitOptions& o, const NormalMap* targets) {
    if (o.projection_steps < 0 || o.relax_steps < 0 || o.vertex_steps < 0 || o.boundary_rings < 0)
        throw InvalidInput(
            "fit_mesh_to_volume: projection_steps, relax_steps, vertex_steps and boundary_rings must be >= 0");
    check_mesh(m, "fit_mesh_to_volume");
    v.check("fit_mesh_to_volume");
    FitReport rep;
    std::vector<std::uint32_t> group;
    const std::size_t n = weld(m, group);
    rep.vertices = n;
    // one position per welded vertex (the first occurrence's)
    std::vector<Vec3d> x(n), x0(n);
    std::vector<char> seen(n, 0);
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        if (!seen[group[i]]) {
            seen[group[i]] = 1;
            x[group[i]] = Vec3d(m.positions[i]);
        }
    x0 = x;

    // how much each vertex may move: 0 on an open boundary, rising over boundary_rings rings
    const std::vector<char> on = boundary_vertices(m, group, n);
    std::vector<double> weight(n, 1.0);
    // vertex → welded neighbours (CSR, each once per triangle they share), for the rings and the
    // tangential relaxation
    std::vector<std::uint32_t> start(n + 1, 0), nb;
    {
        for (const Tri& t : m.triangles)
            for (int e = 0; e < 3; ++e) ++start[group[t[std::size_t(e)]] + 1], ++start[group[t[std::size_t(e)]] + 1];
        for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
        nb.resize(start[n]);
        std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
        for (const Tri& t : m.triangles)
            for (int e = 0; e < 3; ++e) {
                const std::uint32_t a = group[t[std::size_t(e)]];
                nb[fill[a]++] = group[t[std::size_t((e + 1) % 3)]];
                nb[fill[a]++] = group[t[std::size_t((e + 2) % 3)]];
            }
        std::vector<int> ring(n, -1);
        std::vector<std::uint32_t> front, next;
        for (std::size_t i = 0; i < n; ++i)
            if (on[i]) {
                ring[i] = 0;
                front.push_back(std::uint32_t(i));
                ++rep.boundary_vertices;
            }
        for (int r = 1; r <= o.boundary_rings && !front.empty(); ++r) {
            next.clear();
            for (std::uint32_t a : front)
                for (std::uint32_t k = start[a]; k < start[a + 1]; ++k)
                    if (ring[nb[k]] < 0) {
                        ring[nb[k]] = r;
                        next.push_back(nb[k]);
                    }
            front.swap(next);
        }
        for (std::size_t i = 0; i < n; ++i) {
            if (ring[i] >= 0) weight[i] = double(ring[i]) / double(o.boundary_rings + 1);
            if (start[i] == start[i + 1]) weight[i] = 0.0;  // in no triangle: nothing says where it belongs
        }
    }

    const detail::VolumeSampler S(v);
    const double h = v.grid.voxel_size;
    std::vector<char> outside(n, 0);
    // Newton steps from p toward the zero level set, each at most a voxel long
    const auto project = [&](Vec3d p, int steps) {
        for (int s = 0; s < steps; ++s) {
            Vec3d g;
            const double d = S.phi(p, &g);
            const double g2 = dot(g, g);
            if (!(g2 > 1e-12)) break;
            Vec3d step = g * (-d / g2);
            const double len = norm(step);
            if (len > h) step = step * (h / len);
            p = p + step;
            if (std::abs(d) < 1e-6 * h || S.outside_band(p)) break;
        }
        return p;
    };
    // 1. projection onto the zero level set
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            if (weight[i] == 0.0) continue;  // held: on an open boundary, or in no triangle
            if (S.outside_band(x[i])) {
                outside[i] = 1;
                continue;
            }
            x[i] = x0[i] + (project(x[i], o.projection_steps) - x0[i]) * weight[i];
        }
    });
    for (char c : outside) rep.outside_band += std::size_t(c);

    // 1b. tangential relaxation: each vertex half way toward its neighbours' mean within its tangent
    // plane, then back onto the level set; untangles what noise moved along the surface
    if (o.relax_steps > 0) {
        std::vector<Vec3d> next(n);
        for (int s = 0; s < o.relax_steps; ++s) {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t i = r.begin(); i != r.end(); ++i) {
                                      next[i] = x[i];
                                      if (outside[i] || weight[i] == 0.0 || start[i] == start[i + 1]) continue;
                                      Vec3d mean(0, 0, 0);
                                      for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) mean = mean + x[nb[k]];
                                      Vec3d d = mean / double(start[i + 1] - start[i]) - x[i];
                                      Vec3d g;
                                      S.phi(x[i], &g);
                                      const double len = norm(g);
                                      if (!(len > 1e-12)) continue;
                                      const Vec3d nrm = g / len;
                                      d = d - nrm * dot(nrm, d);
                                      const Vec3d p = project(x[i] + d * 0.5, 2);
                                      next[i] = x[i] + (p - x[i]) * weight[i];
                                  }
                              });
            x.swap(next);
        }
    }

    // 2. vertex update toward the volume's normals at the projected faces' centroids
    if (o.vertex_steps > 0 && !m.triangles.empty()) {
        const std::size_t nf = m.triangles.size();
        std::vector<Vec3d> normal(nf);
        std::vector<char> usable(nf, 0);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t f = r.begin(); f != r.end(); ++f) {
                const Tri& t = m.triangles[f];
                normal[f] = volume_normal(S, targets, (x[group[t[0]]] + x[group[t[1]]] + x[group[t[2]]]) / 3.0);
                usable[f] = norm(normal[f]) > 0;
            }
        });
        // vertex → faces (CSR), faces in index order
        std::vector<std::uint32_t> start(n + 1, 0), faces;
        for (std::size_t f = 0; f < nf; ++f)
            if (usable[f])
                for (int e = 0; e < 3; ++e) ++start[group[m.triangles[f][std::size_t(e)]] + 1];
        for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
        faces.resize(start[n]);
        {
            std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
            for (std::size_t f = 0; f < nf; ++f)
                if (usable[f])
                    for (int e = 0; e < 3; ++e) faces[fill[group[m.triangles[f][std::size_t(e)]]]++] = std::uint32_t(f);
        }
        std::vector<Vec3d> next(n);
        for (int s = 0; s < o.vertex_steps; ++s) {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t i = r.begin(); i != r.end(); ++i) {
                                      next[i] = x[i];
                                      if (outside[i] || start[i] == start[i + 1] || weight[i] == 0.0) continue;
                                      Vec3d sum(0, 0, 0);
                                      for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) {
                                          const Tri& t = m.triangles[faces[k]];
                                          const Vec3d c = (x[group[t[0]]] + x[group[t[1]]] + x[group[t[2]]]) / 3.0;
                                          const Vec3d& nf_ = normal[faces[k]];
                                          sum = sum + nf_ * dot(nf_, c - x[i]);
                                      }
                                      next[i] = x[i] + sum * (weight[i] / double(start[i + 1] - start[i]));
                                  }
                              });
            x.swap(next);
        }
    }

    // back to the positions, and how far from the level set they ended
    for (std::size_t i = 0; i < m.positions.size(); ++i) m.positions[i] = Vec3f(x[group[i]]);
    double sum = 0.0;
    std::size_t counted = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (outside[i]) continue;
        const double d = std::abs(S.phi(x[i], nullptr));
        sum += d;
        rep.max_distance = std::max(rep.max_distance, d);
        ++counted;
    }
    rep.mean_distance = counted ? sum / double(counted) : 0.0;
    // how well the faces agree with the volume's normals (in face order: deterministic)
    std::vector<double> angle(m.triangles.size(), 0.0), area(m.triangles.size(), 0.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.triangles.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t f = r.begin(); f != r.end(); ++f) {
                              const Tri& t = m.triangles[f];
                              const Vec3d a = x[group[t[0]]], b = x[group[t[1]]], c = x[group[t[2]]];
                              const Vec3d cr = cross(b - a, c - a);
                              const double len = norm(cr);
                              const Vec3d centre = (a + b + c) / 3.0;
                              if (!(len > 0) || S.outside_band(centre)) continue;
                              Vec3d g;
                              S.phi(centre, &g);
                              const double gl = norm(g);
                              if (!(gl > 1e-12)) continue;
                              const double cosine = std::min(1.0, std::abs(dot(cr, g)) / (len * gl));
                              angle[f] = std::acos(cosine) * (180.0 / 3.14159265358979323846);
                              area[f] = 0.5 * len;
                          }
                      });
    double asum = 0.0, wsum = 0.0;
    for (std::size_t f = 0; f < angle.size(); ++f) {
        asum += angle[f] * area[f];
        wsum += area[f];
    }
    rep.mean_face_angle_deg = wsum > 0 ? asum / wsum : 0.0;
    return rep;
}

}  // namespace normalflow
