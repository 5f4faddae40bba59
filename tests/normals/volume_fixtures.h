#pragma once
// Analytic test volumes for the normal-map engine: exact signed distances sampled into the sparse
// block Volume (blocks near the surface allocated, the others tiled with the right sign).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>

#include "core/mesh.h"
#include "core/volume.h"
#include "extract/extract_surface.h"

namespace normalflow::test {

using Sdf = std::function<double(const Vec3d&)>;  // world position -> signed distance (world units)

/// An n×n×n grid of voxel size h at the origin, with exact values in every block whose centre is
/// closer to the surface than half_width voxels plus the block's half diagonal.
inline Volume make_volume(int n, double h, const Sdf& sdf, float half_width = 3.0f) {
    Grid g;
    g.origin = Vec3d(0, 0, 0);
    g.voxel_size = h;
    g.dims = {n, n, n};
    Volume v(g, half_width);
    const double reach = (half_width + 0.5 * std::sqrt(3.0) * kBlockDim) * h;
    for (int bk = 0; bk < v.block_dims[2]; ++bk)
        for (int bj = 0; bj < v.block_dims[1]; ++bj)
            for (int bi = 0; bi < v.block_dims[0]; ++bi) {
                const Vec3d c = g.world(Vec3d(bi * kBlockDim + 3.5, bj * kBlockDim + 3.5, bk * kBlockDim + 3.5));
                const double d = sdf(c);
                if (std::abs(d) > reach) {
                    v.block_table[v.table_index(bi, bj, bk)] = d < 0 ? kBlockInside : kBlockOutside;
                    continue;
                }
                const std::int32_t s = v.allocate_block(bi, bj, bk);
                float* vals = v.block_values(s);
                for (int z = 0; z < kBlockDim; ++z)
                    for (int y = 0; y < kBlockDim; ++y)
                        for (int x = 0; x < kBlockDim; ++x) {
                            const Vec3d w = g.world(Vec3d(bi * kBlockDim + x, bj * kBlockDim + y, bk * kBlockDim + z));
                            vals[Volume::local_index(x, y, z)] =
                                float(std::clamp(sdf(w), -double(v.background), double(v.background)));
                        }
            }
    return v;
}

inline Sdf sphere_sdf(const Vec3d& c, double r) {
    return [=](const Vec3d& p) { return norm(p - c) - r; };
}

/// Axis-aligned box with centre c and half sizes e.
inline Sdf box_sdf(const Vec3d& c, const Vec3d& e) {
    return [=](const Vec3d& p) {
        const Vec3d q(std::abs(p.x - c.x) - e.x, std::abs(p.y - c.y) - e.y, std::abs(p.z - c.z) - e.z);
        const Vec3d qp(std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0));
        return norm(qp) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
    };
}

/// Deterministic hash noise in [-1, 1] per integer lattice point.
/// A box with bumps fixed in world units: the same surface at every voxel size.
inline Sdf bumpy_box(const Vec3d& c, const Vec3d& e, double amplitude, double wavelength) {
    const Sdf box = box_sdf(c, e);
    const double w = 2.0 * 3.14159265358979323846 / wavelength;
    return [=](const Vec3d& p) {
        return box(p) + amplitude * std::sin(w * p.x + 0.3) * std::sin(w * p.y + 1.1) * std::sin(w * p.z + 0.7);
    };
}

inline double hash_noise(int i, int j, int k, std::uint32_t seed) {
    std::uint32_t hsh = seed * 0x9E3779B9u;
    hsh ^= std::uint32_t(i) * 0x85EBCA6Bu;
    hsh = (hsh ^ (hsh >> 13)) * 0xC2B2AE35u;
    hsh ^= std::uint32_t(j) * 0x27D4EB2Fu;
    hsh = (hsh ^ (hsh >> 15)) * 0x165667B1u;
    hsh ^= std::uint32_t(k) * 0x9E3779B1u;
    hsh = (hsh ^ (hsh >> 16)) * 0x85EBCA77u;
    hsh ^= hsh >> 13;
    return double(hsh & 0xFFFFFFu) / double(0xFFFFFF) * 2.0 - 1.0;
}

/// Adds amplitude·noise (world units) to every allocated sample.
inline void add_noise(Volume& v, double amplitude, std::uint32_t seed) {
    for (std::size_t b = 0; b < v.block_count(); ++b) {
        const auto& bc = v.block_coords[b];
        float* vals = v.block_values(std::int32_t(b));
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x)
                    vals[Volume::local_index(x, y, z)] +=
                        float(amplitude *
                              hash_noise(bc[0] * kBlockDim + x, bc[1] * kBlockDim + y, bc[2] * kBlockDim + z, seed));
    }
}

/// Adds spatially correlated noise of the given amplitude to every allocated sample: hash noise
/// on a lattice of `spacing` voxels, interpolated trilinearly (like mesh noise with edges of that
/// length, which a few steps of smoothing cannot remove, unlike per-sample noise).
inline void add_smooth_noise(Volume& v, double amplitude, double spacing, std::uint32_t seed) {
    for (std::size_t b = 0; b < v.block_count(); ++b) {
        const auto& bc = v.block_coords[b];
        float* vals = v.block_values(std::int32_t(b));
        for (int z = 0; z < kBlockDim; ++z)
            for (int y = 0; y < kBlockDim; ++y)
                for (int x = 0; x < kBlockDim; ++x) {
                    const double p[3] = {(bc[0] * kBlockDim + x) / spacing, (bc[1] * kBlockDim + y) / spacing,
                                         (bc[2] * kBlockDim + z) / spacing};
                    const int i0[3] = {int(std::floor(p[0])), int(std::floor(p[1])), int(std::floor(p[2]))};
                    const double f[3] = {p[0] - i0[0], p[1] - i0[1], p[2] - i0[2]};
                    double n = 0.0;
                    for (int c = 0; c < 8; ++c) {
                        const int d[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
                        double w = 1.0;
                        for (int a = 0; a < 3; ++a) w *= d[a] ? f[a] : 1.0 - f[a];
                        n += w * hash_noise(i0[0] + d[0], i0[1] + d[1], i0[2] + d[2], seed);
                    }
                    vals[Volume::local_index(x, y, z)] += float(amplitude * n);
                }
    }
}

/// Volume of {φ < 0} in voxels³, with a linear ramp of one voxel across the interface.
inline double inside_volume(const Volume& v) {
    double vol = 0.0;
    const double inv_h = 1.0 / v.grid.voxel_size;
    for (int k = 0; k < v.grid.dims[2]; ++k)
        for (int j = 0; j < v.grid.dims[1]; ++j)
            for (int i = 0; i < v.grid.dims[0]; ++i) vol += std::clamp(0.5 - v.value(i, j, k) * inv_h, 0.0, 1.0);
    return vol;
}

/// Radius (voxels) of the sphere with the same inside volume.
inline double equivalent_radius(const Volume& v) {
    return std::cbrt(3.0 * inside_volume(v) / (4.0 * 3.14159265358979323846));
}

/// Σ κ² over samples with |φ| < 1 voxel: κ² = ‖∇N‖² − |∇N n|² with N = ∇φ/|∇φ| (central differences).
inline double total_curvature(const Volume& v) {
    const double inv_h = 1.0 / v.grid.voxel_size;
    auto phi = [&](int i, int j, int k) { return double(v.value(i, j, k)) * inv_h; };
    auto normal = [&](int i, int j, int k) {
        const Vec3d g(0.5 * (phi(i + 1, j, k) - phi(i - 1, j, k)), 0.5 * (phi(i, j + 1, k) - phi(i, j - 1, k)),
                      0.5 * (phi(i, j, k + 1) - phi(i, j, k - 1)));
        return normalized(g);
    };
    double sum = 0.0;
    for (int k = 2; k < v.grid.dims[2] - 2; ++k)
        for (int j = 2; j < v.grid.dims[1] - 2; ++j)
            for (int i = 2; i < v.grid.dims[0] - 2; ++i) {
                if (std::abs(phi(i, j, k)) >= 1.0) continue;
                const Vec3d n = normal(i, j, k);
                const Vec3d d[3] = {(normal(i + 1, j, k) - normal(i - 1, j, k)) * 0.5,
                                    (normal(i, j + 1, k) - normal(i, j - 1, k)) * 0.5,
                                    (normal(i, j, k + 1) - normal(i, j, k - 1)) * 0.5};
                double dn2 = 0.0;
                Vec3d dnn(0, 0, 0);  // ∇N n
                for (int a = 0; a < 3; ++a) {
                    dn2 += squared_norm(d[a]);
                    dnn += d[a] * n[a];
                }
                sum += std::max(dn2 - squared_norm(dnn), 0.0);
            }
    return sum;
}

/// A triangle of a mesh against a box (centre c, half extents e): its unit normal and area, the box
/// face nearest its centroid (axis, and side: -1 or +1), and how many of the box's three slabs
/// |p_k - c_k| > e_k - reach its centroid lies in (1: on a flat part, 2: within reach of an edge,
/// 3: of a corner).
struct BoxTriangle {
    Vec3d normal;
    double area = 0;
    int axis = 0;
    double side = 1;
    int near = 0;
};
/// False for a triangle of zero area.
inline bool box_triangle(const Mesh& m, const Tri& t, const Vec3d& c, const Vec3d& e, double reach, BoxTriangle& out) {
    const Vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), d(m.positions[t[2]]);
    const Vec3d cr = cross(b - a, d - a);
    out.area = 0.5 * norm(cr);
    if (out.area <= 0) return false;
    out.normal = cr / (2 * out.area);
    const Vec3d p = (a + b + d) / 3.0 - c;
    double q[3];
    out.axis = 0;
    for (int k = 0; k < 3; ++k) {
        q[k] = std::abs(p[k]) - e[k];
        if (q[k] > q[out.axis]) out.axis = k;
    }
    out.near = 0;
    for (int k = 0; k < 3; ++k) out.near += q[k] > -reach;
    out.side = p[out.axis] < 0 ? -1.0 : 1.0;
    return true;
}

/// Mean angle (degrees) between the face normals of the extracted mesh and the true normal of the
/// nearest box face, over triangles within `reach` voxels of an edge of the box (not near a corner),
/// and over triangles on the flat parts.
struct BoxNormalError {
    double near_edges = 0, on_faces = 0;
};
inline BoxNormalError box_normal_error(const Mesh& m, const Vec3d& c, const Vec3d& e, double reach) {
    double sum_e = 0, sum_f = 0, area_e = 0, area_f = 0;
    for (const auto& t : m.triangles) {
        BoxTriangle bt;
        if (!box_triangle(m, t, c, e, reach, bt)) continue;
        Vec3d truth(0, 0, 0);
        truth[bt.axis] = bt.side;
        const double ang = std::acos(std::clamp(dot(bt.normal, truth), -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
        if (bt.near == 2) {
            sum_e += ang * bt.area;
            area_e += bt.area;
        } else if (bt.near == 1) {
            sum_f += ang * bt.area;
            area_f += bt.area;
        }
    }
    return {area_e > 0 ? sum_e / area_e : 180.0, area_f > 0 ? sum_f / area_f : 180.0};
}

/// Mean and max |‖p − c‖ − mean radius| of the extracted surface's vertices (voxels, h = 1).
struct RadialStats {
    double mean_radius = 0, max_deviation = 0;
};
inline RadialStats radial_stats(const Volume& v, const Vec3d& c) {
    const Mesh m = extract_surface(v);
    RadialStats s;
    if (m.positions.empty()) return s;
    for (const auto& p : m.positions) s.mean_radius += norm(Vec3d(p) - c);
    s.mean_radius /= double(m.positions.size());
    for (const auto& p : m.positions)
        s.max_deviation = std::max(s.max_deviation, std::abs(norm(Vec3d(p) - c) - s.mean_radius));
    return s;
}

}  // namespace normalflow::test
