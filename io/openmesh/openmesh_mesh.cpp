// Mesh <-> OpenMesh TriMesh conversion and the mesh-side smoothing baselines (smoothing.h).
// OpenMesh is used for what it is good at: building a manifold half-edge mesh from the soup and
// walking one-rings. The neighbourhoods are then copied into flat arrays (CSR) so that the
// iterations run over plain vectors with TBB, reading one buffer and writing another.
#include "io/openmesh/smoothing.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "extract/surface_attributes.h"

namespace normalflow {

namespace {

using TriMesh = OpenMesh::TriMesh_ArrayKernelT<>;
using Clock = std::chrono::steady_clock;

/// A soup converted to a half-edge mesh: welded points (OpenMesh vertex i = welded point i).
struct HalfEdgeMesh {
    TriMesh om;
    std::vector<std::uint32_t> old_to_new;  ///< input position -> welded point
    std::vector<Vec3d> points;              ///< welded points, double
    std::size_t faces_skipped = 0;
};

/// Silences OpenMesh's error stream while faces are added (it reports rejected faces on omerr);
/// library code never prints.
class QuietOpenMesh {
public:
    QuietOpenMesh() : was_enabled_(::omerr().is_enabled()) { ::omerr().disable(); }
    ~QuietOpenMesh() {
        if (was_enabled_) ::omerr().enable();
    }
    QuietOpenMesh(const QuietOpenMesh&) = delete;
    QuietOpenMesh& operator=(const QuietOpenMesh&) = delete;

private:
    bool was_enabled_;
};

/// Mesh -> OpenMesh (the io boundary). Faces that would break the half-edge structure are skipped.
HalfEdgeMesh to_openmesh(const Mesh& m, const char* who) {
    if (m.triangles.empty()) throw InvalidInput(std::string(who) + ": mesh has no triangles");
    HalfEdgeMesh h;
    Mesh welded;
    try {
        welded = weld_exact(m, &h.old_to_new);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string(who) + ": " + e.what());
    }
    h.points.reserve(welded.positions.size());
    h.om.reserve(welded.positions.size(), 3 * welded.triangles.size() / 2, welded.triangles.size());
    for (const Vec3f& p : welded.positions) {
        h.points.emplace_back(p);
        h.om.add_vertex(TriMesh::Point(p.x, p.y, p.z));
    }
    QuietOpenMesh quiet;
    for (const Tri& t : welded.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
            ++h.faces_skipped;
            continue;
        }
        const auto f =
            h.om.add_face(h.om.vertex_handle(int(t[0])), h.om.vertex_handle(int(t[1])), h.om.vertex_handle(int(t[2])));
        if (!f.is_valid()) ++h.faces_skipped;
    }
    return h;
}

/// OpenMesh -> Mesh (the io boundary): the input's triangles, positions from the welded points.
void write_back(const HalfEdgeMesh& h, Mesh& m) {
    for (std::size_t k = 0; k < m.positions.size(); ++k) m.positions[k] = Vec3f(h.points[h.old_to_new[k]]);
    if (m.has_normals()) set_face_normals(m);  // the input's normals belong to the old positions
}

/// One-ring neighbourhoods with weights, as flat arrays.
struct Rings {
    std::vector<std::uint32_t> offset;  ///< #V + 1
    std::vector<std::uint32_t> nbr;
    std::vector<double> weight;
    std::vector<char> movable;  ///< 1 if the vertex may move
};

double cot_at(const Vec3d& apex, const Vec3d& a, const Vec3d& b) {
    const Vec3d u = a - apex, v = b - apex;
    const double s = norm(cross(u, v));
    return s > 0 ? dot(u, v) / s : 0.0;
}

Rings build_rings(const HalfEdgeMesh& h, LaplacianWeights weights, bool fix_boundary, SmoothingReport& r) {
    const TriMesh& om = h.om;
    const std::size_t n = om.n_vertices();
    Rings g;
    g.offset.assign(n + 1, 0);
    g.movable.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const auto vh = om.vertex_handle(int(i));
        const bool boundary = om.is_boundary(vh) && !om.is_isolated(vh);
        if (boundary) ++r.boundary_vertices;
        std::size_t start = g.nbr.size();
        double wsum = 0;
        for (auto he = om.cvoh_iter(vh); he.is_valid(); ++he) {
            const auto to = om.to_vertex_handle(*he);
            double w = 1.0;
            if (weights == LaplacianWeights::Cotan) {
                double c = 0.0;
                const Vec3d& a = h.points[i];
                const Vec3d& b = h.points[std::size_t(to.idx())];
                if (!om.is_boundary(*he)) {
                    const auto apex = om.to_vertex_handle(om.next_halfedge_handle(*he));
                    c += 0.5 * cot_at(h.points[std::size_t(apex.idx())], a, b);
                }
                const auto opp = om.opposite_halfedge_handle(*he);
                if (!om.is_boundary(opp)) {
                    const auto apex = om.to_vertex_handle(om.next_halfedge_handle(opp));
                    c += 0.5 * cot_at(h.points[std::size_t(apex.idx())], a, b);
                }
                w = std::max(c, 0.0);
            }
            g.nbr.push_back(std::uint32_t(to.idx()));
            g.weight.push_back(w);
            wsum += w;
        }
        const std::size_t count = g.nbr.size() - start;
        if (count > 0 && !(wsum > 0)) {  // all cotan weights vanished: fall back to uniform
            for (std::size_t k = start; k < g.nbr.size(); ++k) g.weight[k] = 1.0;
            wsum = double(count);
        }
        for (std::size_t k = start; k < g.nbr.size(); ++k) g.weight[k] /= wsum;
        g.offset[i + 1] = std::uint32_t(g.nbr.size());
        g.movable[i] = (count > 0 && !(fix_boundary && boundary)) ? 1 : 0;
    }
    return g;
}

/// dst = src + factor · L(src).
void umbrella_step(const Rings& g, const std::vector<Vec3d>& src, std::vector<Vec3d>& dst, double factor) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, src.size(), 1024), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!g.movable[i]) {
                dst[i] = src[i];
                continue;
            }
            Vec3d lap{};
            for (std::uint32_t k = g.offset[i]; k < g.offset[i + 1]; ++k) lap += (src[g.nbr[k]] - src[i]) * g.weight[k];
            dst[i] = src[i] + lap * factor;
        }
    });
}

void start_report(const HalfEdgeMesh& h, SmoothingReport& r) {
    r.vertices = h.om.n_vertices();
    r.faces = h.om.n_faces();
    r.faces_skipped = h.faces_skipped;
    if (h.faces_skipped > 0)
        r.warnings.push_back(std::to_string(h.faces_skipped) +
                             " non-manifold or degenerate faces left out of the neighbourhoods");
}

void finish_report(const std::vector<Vec3d>& before, const std::vector<Vec3d>& after, SmoothingReport& r,
                   Clock::time_point t0, const char* who) {
    double m2 = 0;
    for (std::size_t i = 0; i < after.size(); ++i) {
        if (!is_finite(after[i])) throw NumericalError(std::string(who) + ": a vertex position became non-finite");
        m2 = std::max(m2, squared_norm(after[i] - before[i]));
    }
    r.max_displacement = std::sqrt(m2);
    r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
}

SmoothingReport umbrella_smooth(Mesh& m, const std::vector<double>& factors, int iterations, LaplacianWeights weights,
                                bool fix_boundary, Progress* p, const char* who) {
    const auto t0 = Clock::now();
    SmoothingReport r;
    HalfEdgeMesh h = to_openmesh(m, who);
    start_report(h, r);
    const Rings g = build_rings(h, weights, fix_boundary, r);
    const std::vector<Vec3d> before = h.points;
    std::vector<Vec3d> tmp(h.points.size());
    detail::begin(p, who);
    for (int it = 0; it < iterations; ++it) {
        for (double f : factors) {
            umbrella_step(g, h.points, tmp, f);
            h.points.swap(tmp);
        }
        r.iterations = it + 1;
        detail::tick(p, double(it + 1) / iterations, who);
    }
    finish_report(before, h.points, r, t0, who);
    write_back(h, m);
    return r;
}

}  // namespace

SmoothingReport laplacian_smooth(Mesh& m, const LaplacianOptions& opt, Progress* p) {
    if (!(opt.lambda > 0 && opt.lambda <= 1))
        throw InvalidInput("laplacian_smooth: lambda " + std::to_string(opt.lambda) + " out of range, expected (0, 1]");
    if (opt.iterations < 0)
        throw InvalidInput("laplacian_smooth: iterations " + std::to_string(opt.iterations) + ", expected >= 0");
    return umbrella_smooth(m, {opt.lambda}, opt.iterations, opt.weights, opt.fix_boundary, p, "laplacian_smooth");
}

SmoothingReport taubin_smooth(Mesh& m, const TaubinOptions& opt, Progress* p) {
    if (!(opt.lambda > 0 && opt.lambda <= 1))
        throw InvalidInput("taubin_smooth: lambda " + std::to_string(opt.lambda) + " out of range, expected (0, 1]");
    if (!(opt.mu < 0 && -opt.mu >= opt.lambda && opt.mu >= -1.5))
        throw InvalidInput("taubin_smooth: mu " + std::to_string(opt.mu) +
                           " out of range, expected -1.5 <= mu <= -lambda (" + std::to_string(opt.lambda) + ")");
    if (opt.iterations < 0)
        throw InvalidInput("taubin_smooth: iterations " + std::to_string(opt.iterations) + ", expected >= 0");
    return umbrella_smooth(m, {opt.lambda, opt.mu}, opt.iterations, opt.weights, opt.fix_boundary, p, "taubin_smooth");
}

SmoothingReport bilateral_normal_filter(Mesh& m, const BilateralNormalOptions& opt, Progress* p) {
    const char* who = "bilateral_normal_filter";
    if (opt.normal_iterations < 0 || opt.vertex_iterations < 0)
        throw InvalidInput(std::string(who) + ": iterations must be >= 0");
    if (!(opt.sigma_spatial >= 0) || !std::isfinite(opt.sigma_spatial))
        throw InvalidInput(std::string(who) + ": sigma_spatial " + std::to_string(opt.sigma_spatial) +
                           ", expected >= 0");
    if (!(opt.sigma_range > 0 && opt.sigma_range <= 2))
        throw InvalidInput(std::string(who) + ": sigma_range " + std::to_string(opt.sigma_range) +
                           " out of range, expected (0, 2]");
    const auto t0 = Clock::now();
    SmoothingReport r;
    HalfEdgeMesh h = to_openmesh(m, who);
    start_report(h, r);
    const TriMesh& om = h.om;
    const std::size_t nf = om.n_faces(), nv = om.n_vertices();

    // Face corners, face neighbourhoods (faces sharing a vertex) and vertex -> faces, as flat arrays.
    std::vector<Tri> corners(nf);
    for (std::size_t f = 0; f < nf; ++f) {
        int k = 0;
        for (auto v = om.cfv_iter(om.face_handle(int(f))); v.is_valid() && k < 3; ++v)
            corners[f][k++] = std::uint32_t(v->idx());
    }
    std::vector<std::uint32_t> vf_offset(nv + 1, 0), vf;
    for (std::size_t v = 0; v < nv; ++v) {
        for (auto f = om.cvf_iter(om.vertex_handle(int(v))); f.is_valid(); ++f) vf.push_back(std::uint32_t(f->idx()));
        std::sort(vf.begin() + vf_offset[v], vf.end());  // fixed order: determinism of sums
        vf_offset[v + 1] = std::uint32_t(vf.size());
    }
    std::vector<std::uint32_t> ff_offset(nf + 1, 0), ff;
    for (std::size_t f = 0; f < nf; ++f) {
        const std::size_t start = ff.size();
        for (std::uint32_t c : corners[f])
            ff.insert(ff.end(), vf.begin() + vf_offset[c], vf.begin() + vf_offset[c + 1]);
        std::sort(ff.begin() + std::ptrdiff_t(start), ff.end());
        ff.erase(std::unique(ff.begin() + std::ptrdiff_t(start), ff.end()), ff.end());
        ff_offset[f + 1] = std::uint32_t(ff.size());
    }

    std::vector<char> movable(nv, 0);
    for (std::size_t v = 0; v < nv; ++v) {
        const auto vh = om.vertex_handle(int(v));
        const bool boundary = om.is_boundary(vh) && !om.is_isolated(vh);
        if (boundary) ++r.boundary_vertices;
        movable[v] = (vf_offset[v + 1] > vf_offset[v] && !(opt.fix_boundary && boundary)) ? 1 : 0;
    }

    std::vector<Vec3d> centroid(nf), normal(nf), filtered(nf);
    std::vector<double> area(nf);
    auto update_faces = [&](const std::vector<Vec3d>& x) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf, 1024), [&](const auto& range) {
            for (std::size_t f = range.begin(); f != range.end(); ++f) {
                const Vec3d &a = x[corners[f][0]], &b = x[corners[f][1]], &c = x[corners[f][2]];
                const Vec3d n = cross(b - a, c - a);
                area[f] = 0.5 * norm(n);
                normal[f] = normalized(n);
                centroid[f] = (a + b + c) / 3.0;
            }
        });
    };
    update_faces(h.points);

    double sigma_s = opt.sigma_spatial;
    if (sigma_s == 0) {  // mean centroid distance over edge-adjacent face pairs
        double sum = 0;
        std::size_t count = 0;
        for (auto e = om.edges_begin(); e != om.edges_end(); ++e) {
            const auto h0 = om.halfedge_handle(*e, 0), h1 = om.halfedge_handle(*e, 1);
            if (om.is_boundary(h0) || om.is_boundary(h1)) continue;
            sum +=
                norm(centroid[std::size_t(om.face_handle(h0).idx())] - centroid[std::size_t(om.face_handle(h1).idx())]);
            ++count;
        }
        sigma_s = count > 0 ? sum / double(count) : 1.0;
        if (!(sigma_s > 0)) sigma_s = 1.0;
    }
    const double inv_2ss = 1.0 / (2 * sigma_s * sigma_s), inv_2sr = 1.0 / (2 * opt.sigma_range * opt.sigma_range);

    detail::begin(p, who);
    const int total = opt.normal_iterations + 1;
    for (int it = 0; it < opt.normal_iterations; ++it) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf, 512), [&](const auto& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                Vec3d s{};
                for (std::uint32_t k = ff_offset[i]; k < ff_offset[i + 1]; ++k) {
                    const std::uint32_t j = ff[k];
                    const double ds = squared_norm(centroid[i] - centroid[j]);
                    const double dr = squared_norm(normal[i] - normal[j]);
                    s += normal[j] * (area[j] * std::exp(-ds * inv_2ss - dr * inv_2sr));
                }
                filtered[i] = squared_norm(s) > 0 ? normalized(s) : normal[i];
            }
        });
        normal.swap(filtered);
        r.iterations = it + 1;
        detail::tick(p, double(it + 1) / total, who);
    }

    // Vertex update (Sun et al. 2007): move each vertex towards the planes of its faces' filtered normals.
    const std::vector<Vec3d> before = h.points;
    const std::vector<Vec3d> target_normal = normal;
    std::vector<Vec3d> next(nv);
    for (int it = 0; it < opt.vertex_iterations; ++it) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1024), [&](const auto& range) {
            for (std::size_t v = range.begin(); v != range.end(); ++v) {
                if (!movable[v]) {
                    next[v] = h.points[v];
                    continue;
                }
                Vec3d d{};
                const std::uint32_t b = vf_offset[v], e = vf_offset[v + 1];
                for (std::uint32_t k = b; k < e; ++k) {
                    const std::uint32_t f = vf[k];
                    d += target_normal[f] * dot(target_normal[f], centroid[f] - h.points[v]);
                }
                next[v] = h.points[v] + d / double(e - b);
            }
        });
        h.points.swap(next);
        update_faces(h.points);  // new centroids for the next pass (normals stay the filtered ones)
    }
    detail::tick(p, 1.0, who);
    finish_report(before, h.points, r, t0, who);
    write_back(h, m);
    return r;
}

}  // namespace normalflow
