#include "sdf/winding_number.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

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
    struct Moments {
        Vec3d center;                   // area-weighted centre p̃
        Vec3d area;                     // N = Σ a_f n_f
        std::array<double, 9> m{};      // Σ a_f n_f (c_f − p̃)ᵀ, row-major
        double radius_sq = 0;           // (beta · r)²
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

WindingNumber::WindingNumber(const Mesh& m, double beta) : impl_(std::make_unique<Impl>()) {
    detail::validate_mesh(m, "WindingNumber");
    Impl& I = *impl_;
    I.bvh.build(m, 8);
    const std::size_t nf = I.bvh.order.size();
    I.corners.resize(3 * nf);
    for (std::size_t i = 0; i < nf; ++i) {
        const Tri& t = m.triangles[I.bvh.order[i]];
        for (int c = 0; c < 3; ++c) I.corners[3 * i + std::size_t(c)] = Vec3d(m.positions[t[c]]);
    }
    // Raw sums per node, bottom-up (children have larger indices than their parent).
    const std::size_t nn = I.bvh.nodes.size();
    std::vector<double> wsum(nn, 0.0);
    std::vector<Vec3d> wc(nn), area(nn);
    std::vector<std::array<double, 9>> s(nn);  // Σ A_f c_fᵀ
    for (std::size_t k = nn; k-- > 0;) {
        const detail::BvhNode& nd = I.bvh.nodes[k];
        std::array<double, 9> sk{};
        if (nd.count > 0) {
            for (std::uint32_t i = nd.first; i < nd.first + nd.count; ++i) {
                const Vec3d* c = &I.corners[3 * std::size_t(i)];
                const Vec3d A = cross(c[1] - c[0], c[2] - c[0]) * 0.5;
                const Vec3d cen = (c[0] + c[1] + c[2]) / 3.0;
                const double a = norm(A);
                wsum[k] += a;
                wc[k] += cen * a;
                area[k] += A;
                for (int r = 0; r < 3; ++r)
                    for (int q = 0; q < 3; ++q) sk[std::size_t(3 * r + q)] += A[r] * cen[q];
            }
        } else {
            for (const std::size_t ch : {k + 1, std::size_t(nd.first)}) {
                wsum[k] += wsum[ch];
                wc[k] += wc[ch];
                area[k] += area[ch];
                for (std::size_t q = 0; q < 9; ++q) sk[q] += s[ch][q];
            }
        }
        s[k] = sk;
    }
    I.mom.resize(nn);
    for (std::size_t k = 0; k < nn; ++k) {
        const detail::BvhNode& nd = I.bvh.nodes[k];
        Impl::Moments& mo = I.mom[k];
        mo.center = wsum[k] > 0 ? wc[k] / wsum[k] : (nd.lo + nd.hi) * 0.5;
        mo.area = area[k];
        for (int r = 0; r < 3; ++r)
            for (int q = 0; q < 3; ++q)
                mo.m[std::size_t(3 * r + q)] = s[k][std::size_t(3 * r + q)] - area[k][r] * mo.center[q];
        double r2 = 0;
        for (int corner = 0; corner < 8; ++corner) {
            const Vec3d x{corner & 1 ? nd.hi.x : nd.lo.x, corner & 2 ? nd.hi.y : nd.lo.y,
                          corner & 4 ? nd.hi.z : nd.lo.z};
            r2 = std::max(r2, squared_norm(x - mo.center));
        }
        mo.radius_sq = beta * beta * r2;
    }
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
            const double inv3 = 1.0 / (d2 * d), inv5 = inv3 / d2;
            const auto& M = mo.m;
            const double tr = M[0] + M[4] + M[8];
            double rmr = 0;
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) rmr += r[a] * M[std::size_t(3 * a + b)] * r[b];
            far += dot(r, mo.area) * inv3 + tr * inv3 - 3.0 * rmr * inv5;
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
    for (std::size_t i = 0; i < I.corners.size(); i += 3) s += solid_angle(p, I.corners[i], I.corners[i + 1], I.corners[i + 2]);
    return s / (4.0 * std::numbers::pi);
}

}  // namespace normalflow
