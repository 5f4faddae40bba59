#include "sdf/winding_number.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/errors.h"
#include "sdf/triangle_bvh.h"

namespace normalflow {

double solid_angle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d x = a - p, y = b - p, z = c - p;
    const double lx = norm(x), ly = norm(y), lz = norm(z);
    const double det = dot(x, cross(y, z));
    const double den = lx * ly * lz + dot(x, y) * lz + dot(y, z) * lx + dot(z, x) * ly;
    if (det == 0.0 && den == 0.0) return 0.0;  // p on the triangle's plane at a corner/edge
    return 2.0 * std::atan2(det, den);
}

struct WindingNumber::Impl {
    // Far-field expansion of one BVH node about its area-weighted centre p̃ (Barill et al. 2018, §3.2,
    // eq. 15-17, to the second derivative of the kernel G(r) = r / |r|³, i.e. libigl's order 2):
    //   w·4π ≈ Σ_a N_a G_a + Σ_ab M_ab ∂_b G_a + ½ Σ_abc T_abc ∂_b ∂_c G_a,
    // N = Σ a_f n_f, M_ab = Σ a_f n_fa (c_f − p̃)_b, T_abc = Σ n_fa ∫_f (x − p̃)_b (x − p̃)_c dA.
    struct Moments {
        Vec3d center;                 // area-weighted centre p̃
        Vec3d area;                   // N
        std::array<double, 9> m{};    // M, row-major
        double tr = 0;                // trace of M
        Vec3d u, v;                   // u_c = Σ_a T_aac, v_a = Σ_b T_abb
        std::array<double, 10> t3{};  // symmetrised T: coefficients of the cubic form Σ T_abc r_a r_b r_c
        double radius_sq = 0;         // (beta · r)²
    };
    detail::TriangleBvh bvh;
    std::vector<Moments> mom;
    std::vector<Vec3d> corners;  // 3 per triangle in leaf order

    double exact_leaf(const Vec3d& p, const detail::BvhNode& nd) const {
        double s = 0;
        for (std::uint32_t i = nd.first; i < nd.first + nd.count; ++i) {
            const Vec3d* c = &corners[3 * std::size_t(i)];
            s += solid_angle(p, c[0], c[1], c[2]);
        }
        return s;
    }
};

namespace {

// Index of the monomial r_a r_b r_c (a <= b <= c) among the 10 cubic monomials.
constexpr int cubic_index(int a, int b, int c) {
    // sorted triples in lexicographic order: 000 001 002 011 012 022 111 112 122 222
    constexpr int table[27] = {0, 1, 2, 1, 3, 4, 2, 4, 5, 1, 3, 4, 3, 6, 7, 4, 7, 8, 2, 4, 5, 4, 7, 8, 5, 8, 9};
    return table[9 * a + 3 * b + c];
}

}  // namespace

WindingNumber::WindingNumber(const Mesh& m, double beta) : impl_(std::make_unique<Impl>()) {
    check_mesh(m, "WindingNumber");
    if (!(beta >= 1.0) || !std::isfinite(beta))
        throw InvalidInput("WindingNumber: beta = " + std::to_string(beta) + ", expected a finite value >= 1");
    Impl& I = *impl_;
    I.bvh.build(m, 8);
    const std::size_t nf = I.bvh.order.size();
    I.corners.resize(3 * nf);
    for (std::size_t i = 0; i < nf; ++i) {
        const Tri& t = m.triangles[I.bvh.order[i]];
        for (int c = 0; c < 3; ++c) I.corners[3 * i + std::size_t(c)] = Vec3d(m.positions[t[c]]);
    }
    // Leaf-order range [lo, hi) of every node, bottom-up (children have larger indices than their parent).
    const std::size_t nn = I.bvh.nodes.size();
    std::vector<std::uint32_t> rb(nn), re(nn);
    for (std::size_t k = nn; k-- > 0;) {
        const detail::BvhNode& nd = I.bvh.nodes[k];
        if (nd.count > 0) {
            rb[k] = nd.first;
            re[k] = nd.first + nd.count;
        } else {
            rb[k] = rb[k + 1];
            re[k] = re[nd.first];
        }
    }
    // Moments of every node, computed directly about its own centre (no parallel-axis shifts, so no
    // cancellation far from the origin). Each node writes only its own entry: deterministic.
    I.mom.resize(nn);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nn, 64), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            const detail::BvhNode& nd = I.bvh.nodes[k];
            Impl::Moments& mo = I.mom[k];
            // Centre: area-weighted centroid, relative to the box centre for precision.
            const Vec3d box_c = (nd.lo + nd.hi) * 0.5;
            double wsum = 0;
            Vec3d wc;
            for (std::uint32_t i = rb[k]; i < re[k]; ++i) {
                const Vec3d* c = &I.corners[3 * std::size_t(i)];
                const double a = norm(cross(c[1] - c[0], c[2] - c[0])) * 0.5;
                wsum += a;
                wc += ((c[0] + c[1] + c[2]) / 3.0 - box_c) * a;
            }
            mo.center = wsum > 0 ? box_c + wc / wsum : box_c;
            double t[3][3][3] = {};
            for (std::uint32_t i = rb[k]; i < re[k]; ++i) {
                const Vec3d* c = &I.corners[3 * std::size_t(i)];
                const Vec3d A = cross(c[1] - c[0], c[2] - c[0]) * 0.5;
                const Vec3d y0 = c[0] - mo.center, y1 = c[1] - mo.center, y2 = c[2] - mo.center;
                const Vec3d s = y0 + y1 + y2;
                const Vec3d cen = s / 3.0;
                mo.area += A;
                for (int a = 0; a < 3; ++a)
                    for (int b = 0; b < 3; ++b) {
                        mo.m[std::size_t(3 * a + b)] += A[a] * cen[b];
                        // ∫_f y yᵀ dA = (area / 12) (Σ_i y_i y_iᵀ + s sᵀ); times n_a: A_a / 12 (...).
                        for (int cc = b; cc < 3; ++cc)
                            t[a][b][cc] +=
                                A[a] / 12.0 * (y0[b] * y0[cc] + y1[b] * y1[cc] + y2[b] * y2[cc] + s[b] * s[cc]);
                    }
            }
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b)
                    for (int cc = 0; cc < b; ++cc) t[a][b][cc] = t[a][cc][b];
            mo.tr = mo.m[0] + mo.m[4] + mo.m[8];
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) {
                    mo.u[b] += t[a][a][b];
                    mo.v[a] += t[a][b][b];
                    for (int cc = 0; cc < 3; ++cc)
                        mo.t3[std::size_t(cubic_index(std::min({a, b, cc}),
                                                      a + b + cc - std::min({a, b, cc}) - std::max({a, b, cc}),
                                                      std::max({a, b, cc})))] += t[a][b][cc];
                }
            double r2 = 0;
            for (int corner = 0; corner < 8; ++corner) {
                const Vec3d x{corner & 1 ? nd.hi.x : nd.lo.x, corner & 2 ? nd.hi.y : nd.lo.y,
                              corner & 4 ? nd.hi.z : nd.lo.z};
                r2 = std::max(r2, squared_norm(x - mo.center));
            }
            mo.radius_sq = beta * beta * r2;
        }
    });
}

WindingNumber::~WindingNumber() = default;
WindingNumber::WindingNumber(WindingNumber&&) noexcept = default;
WindingNumber& WindingNumber::operator=(WindingNumber&&) noexcept = default;

double WindingNumber::operator()(const Vec3d& p) const {
    const Impl& I = *impl_;
    if (I.bvh.nodes.empty()) return 0.0;
    double sum = 0;  // in units of 4π
    double far = 0;
    std::uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const std::uint32_t k = stack[--top];
        const Impl::Moments& mo = I.mom[k];
        const Vec3d r = mo.center - p;
        const double d2 = squared_norm(r);
        if (d2 > mo.radius_sq) {
            const double d = std::sqrt(d2);
            const double inv3 = 1.0 / (d2 * d), inv5 = inv3 / d2, inv7 = inv5 / d2;
            const auto& M = mo.m;
            double rmr = 0;
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) rmr += r[a] * M[std::size_t(3 * a + b)] * r[b];
            const auto& c = mo.t3;
            const double x = r.x, y = r.y, z = r.z;
            const double cubic = c[0] * x * x * x + c[1] * x * x * y + c[2] * x * x * z + c[3] * x * y * y +
                                 c[4] * x * y * z + c[5] * x * z * z + c[6] * y * y * y + c[7] * y * y * z +
                                 c[8] * y * z * z + c[9] * z * z * z;
            // ∂_b∂_c G_a = −3 (δ_ab r_c + δ_ac r_b + δ_bc r_a) / |r|⁵ + 15 r_a r_b r_c / |r|⁷.
            far += dot(r, mo.area) * inv3 + mo.tr * inv3 - 3.0 * rmr * inv5 +
                   0.5 * (-3.0 * (2.0 * dot(mo.u, r) + dot(mo.v, r)) * inv5 + 15.0 * cubic * inv7);
            continue;
        }
        const detail::BvhNode& nd = I.bvh.nodes[k];
        if (nd.count > 0) {
            sum += I.exact_leaf(p, nd);
        } else {
            stack[top++] = nd.first;
            stack[top++] = k + 1;
        }
    }
    // Exact parts are solid angles (divide by 4π); far-field terms already carry 1/|r|³ (divide by 4π).
    return (sum + far) / (4.0 * std::numbers::pi);
}

double WindingNumber::exact(const Vec3d& p) const {
    const Impl& I = *impl_;
    double s = 0;
    for (std::size_t i = 0; i < I.corners.size(); i += 3)
        s += solid_angle(p, I.corners[i], I.corners[i + 1], I.corners[i + 2]);
    return s / (4.0 * std::numbers::pi);
}

}  // namespace normalflow
