#pragma once
/// \file quadric.h
/// Internal to lib/remesh: the quadric error of a set of planes (Garland & Heckbert 1997) and its minimisers,
/// shared by the quadric decimation (decimate.cpp) and the feature sharpening (sharpen.cpp).
#include <algorithm>
#include <cmath>

#include "core/vec.h"

namespace normalflow::detail {

/// The eigen-decomposition of a symmetric 3×3 matrix by Jacobi rotations: values w, vectors the
/// columns of v.
inline void symmetric_eigen(double a[3][3], double w[3], double v[3][3]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) v[i][j] = i == j ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 30; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (!(off > 1e-30 * diag)) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) continue;
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; ++k) {  // a ← a·J
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {  // a ← Jᵀ·a
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    for (int i = 0; i < 3; ++i) w[i] = a[i][i];
}

/// Σ w (n·x + d)² over planes: xᵀAx + 2bᵀx + c, A symmetric.
struct Quadric {
    double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0, b0 = 0, b1 = 0, b2 = 0, c = 0, w = 0;
    void add_plane(const Vec3d& n, double d, double weight) {
        a00 += weight * n.x * n.x;
        a01 += weight * n.x * n.y;
        a02 += weight * n.x * n.z;
        a11 += weight * n.y * n.y;
        a12 += weight * n.y * n.z;
        a22 += weight * n.z * n.z;
        b0 += weight * d * n.x;
        b1 += weight * d * n.y;
        b2 += weight * d * n.z;
        c += weight * d * d;
        w += weight;
    }
    Quadric& operator+=(const Quadric& q) {
        a00 += q.a00, a01 += q.a01, a02 += q.a02, a11 += q.a11, a12 += q.a12, a22 += q.a22;
        b0 += q.b0, b1 += q.b1, b2 += q.b2, c += q.c, w += q.w;
        return *this;
    }
    double operator()(const Vec3d& x) const {
        const double v = x.x * (a00 * x.x + 2 * (a01 * x.y + a02 * x.z + b0)) +
                         x.y * (a11 * x.y + 2 * (a12 * x.z + b1)) + x.z * (a22 * x.z + 2 * b2) + c;
        return std::max(v, 0.0);
    }
    /// The minimiser of the quadric plus λ|x − c|², λ = regularisation · trace(A) / 3: the quadric's own
    /// minimiser where its planes span space (a corner), the point of the crease line or of the plane
    /// nearest to c where they do not (a crease, a flat patch). False if the system is singular.
    bool minimiser_near(const Vec3d& c, double regularisation, Vec3d& x) const {
        const double lambda = regularisation * (a00 + a11 + a22) / 3.0;
        if (!(lambda > 0)) return false;
        const double m00 = a00 + lambda, m11 = a11 + lambda, m22 = a22 + lambda;
        const double r0 = lambda * c.x - b0, r1 = lambda * c.y - b1, r2 = lambda * c.z - b2;
        const double c00 = m11 * m22 - a12 * a12, c01 = a02 * a12 - a01 * m22, c02 = a01 * a12 - a02 * m11;
        const double det = m00 * c00 + a01 * c01 + a02 * c02;
        if (!(std::abs(det) > 0)) return false;
        const double c11 = m00 * m22 - a02 * a02, c12 = a01 * a02 - m00 * a12, c22 = m00 * m11 - a01 * a01;
        const double inv = 1.0 / det;
        x = Vec3d((c00 * r0 + c01 * r1 + c02 * r2) * inv, (c01 * r0 + c11 * r1 + c12 * r2) * inv,
                  (c02 * r0 + c12 * r1 + c22 * r2) * inv);
        return std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z);
    }
    /// The minimiser nearest to c of the quadric with its eigenvalues below tau × the largest taken as
    /// zero (Lindstrom 2000; the dual contouring solve of Ju et al. 2002): planes that are nearly parallel
    /// move the point only across them, never along a crease they do not really make. rank, when given, receives the
    /// number of eigenvalues kept: 1 a plane, 2 a crease, 3 a corner.
    bool truncated_minimiser_near(const Vec3d& c, double tau, Vec3d& x, int* rank = nullptr) const {
        double a[3][3] = {{a00, a01, a02}, {a01, a11, a12}, {a02, a12, a22}}, w[3], v[3][3];
        symmetric_eigen(a, w, v);
        const double top = std::max({w[0], w[1], w[2]});
        if (!(top > 0)) return false;
        // gradient/2 at c: A c + b; step −Σ (vᵢ·r)/wᵢ vᵢ over the kept eigenvalues
        const Vec3d r(a00 * c.x + a01 * c.y + a02 * c.z + b0, a01 * c.x + a11 * c.y + a12 * c.z + b1,
                      a02 * c.x + a12 * c.y + a22 * c.z + b2);
        x = c;
        if (rank) *rank = 0;
        for (int i = 0; i < 3; ++i) {
            if (!(w[i] > tau * top)) continue;
            if (rank) ++*rank;
            const Vec3d e(v[0][i], v[1][i], v[2][i]);
            x = x - e * (dot(e, r) / w[i]);
        }
        return std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z);
    }
};

}  // namespace normalflow::detail
