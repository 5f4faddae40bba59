#include "normals/smooth.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/band_memory.h"
#include "core/errors.h"

namespace normalflow {

const char* to_string(SmoothMode mode) {
    switch (mode) {
        case SmoothMode::Isotropic: return "isotropic";
        case SmoothMode::Anisotropic: return "anisotropic";
        case SmoothMode::HighBoost: return "highboost";
        case SmoothMode::MeanCurvature: return "mcf";
    }
    return "unknown";
}

namespace detail {
namespace {

// The row kernels below are plain C++ that the compiler vectorises. On x86-64 each is also built
// for AVX2 and the widest the CPU has is picked at load time (GCC function multiversioning; Clang 14
// clones no templates and no noinline function, so a Clang build, like the sanitizer and fuzz
// builds, keeps the baseline). AVX2 without FMA (no contraction) does the same IEEE operations on
// wider vectors, so the results are the same, bit for bit, on every machine.
// NORMALFLOW_NO_TARGET_CLONES builds the baseline only.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(NORMALFLOW_NO_TARGET_CLONES)
#define NF_ROW_KERNEL [[gnu::noinline, gnu::target_clones("avx2", "default")]]
#else
#define NF_ROW_KERNEL [[gnu::noinline]]
#endif

constexpr float kHalfWidth = 8.0f;      // engine band half width, voxels
constexpr float kMaxDt = 1.0f / 6.0f;   // explicit stability bound of the 3-D second-order operators
// Reinitialisation stops when no sample moved by more than this in a Jacobi pass (voxels). The
// passes reach the far end of the band within ~15 passes; after that the values creep by ~2e-5 per
// pass along chains of nearly equal distances (fandisk at 256: all 24 passes ran on 90% of the
// blocks before this tolerance). What is left is below 1e-3 voxel.
constexpr float kReinitTolerance = 1e-3f;
constexpr int L = 10;                   // local buffer: 8 + 2 halo
constexpr int L2 = L * L;
constexpr int L3 = L * L * L;
constexpr int kStride[3] = {1, L, L2};

constexpr int lidx(int x, int y, int z) { return (z + 1) * L2 + (y + 1) * L + (x + 1); }
/// Rows of faces of one block, per axis a: (y, z) in [−1, 7]² (the faces x+½e_a, x = −1…7 or 0…7).
constexpr int kRowFlags = 3 * 9 * 9;
constexpr int row_flag(int a, int y, int z) { return (a * 9 + (z + 1)) * 9 + (y + 1); }
constexpr int bidx(int x, int y, int z) { return (z * kBlockDim + y) * kBlockDim + x; }

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// The engine's per-sample arrays (φ, the normals and their ping-pong buffers, H_N, the mask) are
/// written by every stage before it reads them after the band moved (see update_band): their
/// allocator does not zero them on resize (zero-filling only cost a serial pass and its page faults
/// over the whole band, 0.2 s of the set-up at 256), and maps them in huge pages (core/band_memory.h).
using Samples = std::vector<float, NoInitAllocator<float>>;

/// Where the halo of one block comes from: its 27 neighbour slots and, per axis and local
/// coordinate -1..8, which neighbour and which in-block coordinate (clamped at the grid border).
struct Neighbourhood {
    std::int32_t slot[27];
    std::uint8_t nb[3][L];
    std::uint8_t li[3][L];
    int ext[3];            // in-grid extent of the block itself
    bool contiguous_x;     // local x 0..7 read the block's own row unclamped (a memcpy)
};

/// Per-thread scratch of the kernels (a view into a thread-local buffer).
struct Scratch {
    float* buf;
    float* at(int k) { return buf + std::size_t(k) * L3; }
};

/// G(κ²), the penalty of the normal energy, and its derivative g.
inline float penalty(SmoothMode mode, float k2, float inv2mu2) {
    if (mode == SmoothMode::Anisotropic) return (1.0f - std::exp(-k2 * inv2mu2)) / inv2mu2;
    return k2;
}

/// Face terms at the staggered point q + ½e_a (Appendix B, Eq. 43–47, 50): flux column m and κ².
inline void face_terms(const float* P, const float* const N[3], int q, int sa, int sb, int sc, float m[3],
                       float& k2) {
    const int q1 = q + sa;
    const float dphi = P[q1] - P[q];
    const float gb = 0.25f * ((P[q + sb] - P[q - sb]) + (P[q1 + sb] - P[q1 - sb]));
    const float gc = 0.25f * ((P[q + sc] - P[q - sc]) + (P[q1 + sc] - P[q1 - sc]));
    const float g2 = dphi * dphi + gb * gb + gc * gc;
    const float inv = 1.0f / std::max(g2, 1e-12f);
    float dn2 = 0.0f, c2 = 0.0f;
    for (int c = 0; c < 3; ++c) {
        const float* Nc = N[c];
        const float a = Nc[q1] - Nc[q];
        const float b = 0.25f * ((Nc[q + sb] - Nc[q - sb]) + (Nc[q1 + sb] - Nc[q1 - sb]));
        const float d = 0.25f * ((Nc[q + sc] - Nc[q - sc]) + (Nc[q1 + sc] - Nc[q1 - sc]));
        const float C = (a * dphi + b * gb + d * gc) * inv;
        m[c] = a - dphi * C;
        dn2 += a * a + b * b + d * d;
        c2 += C * C;
    }
    k2 = std::max(dn2 - c2 * g2, 0.0f);
}

/// e^x for x <= 0, branch-free so that the loops calling it vectorise (expf is a library call
/// per element): x = n ln2 + r with |r| <= ln2/2, e^r by Cephes' expf polynomial (1 + r + r²/2 + …,
/// degree 7), 2ⁿ from the exponent bits. Within 1 ulp of expf on [−87, 0] (relative error < 8e−8,
/// checked on every 256th float of the range); below −87 it returns
/// e^−87 ≈ 1.6e−38 (where expf gives a denormal or 0). Plain float operations, no contraction: the
/// same value at every vector width and on every thread.
inline float exp_nonpositive(float x) {
    x = std::max(x, -87.0f);
    const float t = x * 1.44269504088896341f + 12582912.0f;  // 1.5·2²³: rounds x·log₂e to an integer
    const float n = t - 12582912.0f;
    const std::int32_t ni = std::bit_cast<std::int32_t>(t) - 0x4B400000;
    const float r = (x - n * 0.693359375f) + n * 2.12194440e-4f;  // ln2 = 0.693359375 − 2.12194440e−4
    const float r2 = r * r;
    float p = 1.9875691500e-4f;
    p = p * r + 1.3981999507e-3f;
    p = p * r + 8.3334519073e-3f;
    p = p * r + 4.1665795894e-2f;
    p = p * r + 1.6666665459e-1f;
    p = p * r + 5.0000001201e-1f;
    const float er = p * r2 + r + 1.0f;
    return er * std::bit_cast<float>((ni + 127) << 23);
}

/// How a normal step weighs the flux of a face: 1 (isotropic), a conductance g held for the whole
/// normal loop, or the paper's g = exp(−κ²/(2µ²)) of the current normals.
enum class FaceWeight { One, Frozen, Live };

/// face_terms over `rows` rows of faces q0 + r·L … q0 + r·L + n−1 (each contiguous in x; rows of 8,
/// or one run across a plane for the x faces), branch-free so that the compiler vectorises it. Rows
/// are passed several at a time because one row of 8 is one vector iteration whose dependency
/// chain (the division, the exp) would otherwise stall on its own. The same operations in the
/// same order as face_terms, so the results are bit-identical. F = g·m, or 0 where both samples of the face lie outside the band (the faces the
/// engine skips); g = 1, G[q] or exp(−κ²·inv2mu2) by kWeight. E = the face's energy density: κ²,
/// G[q]·κ² or (1 − g)·2µ² (the penalty G(κ²) of Eq. 20, as a product where penalty() divides: the
/// reported G may differ in the last bit, the normals do not).
/// N holds the three components L3 apart, F likewise (the kernels' scratch layout), and the axis
/// is a template argument: every load and store is then a fixed offset from one of five pointers,
/// which leaves the registers to the arithmetic (with run-time strides and a pointer per component,
/// a third of the loop's instructions were address arithmetic and stack reloads).
template <FaceWeight kWeight, int kAxis>
NF_ROW_KERNEL
void face_row(const float* __restrict P, const float* __restrict N, const float* __restrict G, int q0, int n, int rows,
              float band, float inv2mu2, float* __restrict F, float* __restrict E) {
    constexpr int sa = kStride[kAxis], sb = kStride[(kAxis + 1) % 3], sc = kStride[(kAxis + 2) % 3];
    const float* N0 = N;
    const float* N1 = N + L3;
    const float* N2 = N + 2 * L3;
    float* F0 = F;
    float* F1 = F + L3;
    float* F2 = F + 2 * L3;
    const float two_mu2 = 1.0f / inv2mu2;  // E of Live as a product: a division per face costs more
    for (int r = 0; r < rows; ++r) {
        for (int j = 0; j < n; ++j) {
            const int q = q0 + r * L + j;
            const int q1 = q + sa;
            const float dphi = P[q1] - P[q];
            const float gb = 0.25f * ((P[q + sb] - P[q - sb]) + (P[q1 + sb] - P[q1 - sb]));
            const float gc = 0.25f * ((P[q + sc] - P[q - sc]) + (P[q1 + sc] - P[q1 - sc]));
            const float g2 = dphi * dphi + gb * gb + gc * gc;
            const float inv = 1.0f / std::max(g2, 1e-12f);
            const float a0 = N0[q1] - N0[q];
            const float b0 = 0.25f * ((N0[q + sb] - N0[q - sb]) + (N0[q1 + sb] - N0[q1 - sb]));
            const float d0 = 0.25f * ((N0[q + sc] - N0[q - sc]) + (N0[q1 + sc] - N0[q1 - sc]));
            const float C0 = (a0 * dphi + b0 * gb + d0 * gc) * inv;
            const float a1 = N1[q1] - N1[q];
            const float b1 = 0.25f * ((N1[q + sb] - N1[q - sb]) + (N1[q1 + sb] - N1[q1 - sb]));
            const float d1 = 0.25f * ((N1[q + sc] - N1[q - sc]) + (N1[q1 + sc] - N1[q1 - sc]));
            const float C1 = (a1 * dphi + b1 * gb + d1 * gc) * inv;
            const float a2 = N2[q1] - N2[q];
            const float b2 = 0.25f * ((N2[q + sb] - N2[q - sb]) + (N2[q1 + sb] - N2[q1 - sb]));
            const float d2 = 0.25f * ((N2[q + sc] - N2[q - sc]) + (N2[q1 + sc] - N2[q1 - sc]));
            const float C2 = (a2 * dphi + b2 * gb + d2 * gc) * inv;
            const float dn2 = ((a0 * a0 + b0 * b0 + d0 * d0) + (a1 * a1 + b1 * b1 + d1 * d1)) + (a2 * a2 + b2 * b2 + d2 * d2);
            const float c2 = (C0 * C0 + C1 * C1) + C2 * C2;
            const float k2 = std::max(dn2 - c2 * g2, 0.0f);
            // a mask, not a branch (no short-circuit): the loop stays vectorisable
            const float keep = float(!(int(std::abs(P[q]) > band) & int(std::abs(P[q1]) > band)));
            float g = keep, e = k2;
            if constexpr (kWeight == FaceWeight::Frozen) {
                g = G[q] * keep;
                e = G[q] * k2;
            } else if constexpr (kWeight == FaceWeight::Live) {
                const float c = exp_nonpositive(-k2 * inv2mu2);
                g = c * keep;
                e = (1.0f - c) * two_mu2;
            }
            F0[q] = g * (a0 - dphi * C0);
            F1[q] = g * (a1 - dphi * C1);
            F2[q] = g * (a2 - dphi * C2);
            E[q] = e;
        }
    }
}

/// face_row for the faces x+½e_axis.
template <FaceWeight kWeight>
void face_rows(int axis, const float* P, const float* N, const float* G, int q0, int n, int rows, float band,
               float inv2mu2, float* F, float* E) {
    switch (axis) {
        case 0: face_row<kWeight, 0>(P, N, G, q0, n, rows, band, inv2mu2, F, E); break;
        case 1: face_row<kWeight, 1>(P, N, G, q0, n, rows, band, inv2mu2, F, E); break;
        default: face_row<kWeight, 2>(P, N, G, q0, n, rows, band, inv2mu2, F, E); break;
    }
}

/// The mask of a row as 32-bit lanes: with 8-bit lanes GCC 12 vectorises a row of 8 at 128 bits
/// only, even for AVX2; with 32-bit ones at 256.
inline void widen_mask(const std::uint8_t* __restrict m, std::int32_t* __restrict out) {
    for (int x = 0; x < kBlockDim; ++x) out[x] = m[x];
}

/// Whether a row of 8 mask bytes has any set.
inline bool any_in_row(const std::uint8_t* m) {
    std::uint64_t w;
    std::memcpy(&w, m, sizeof w);
    return w != 0;
}

/// The first and the last y in [lo, kBlockDim) for which has(y) holds, as {y0, y1}; y1 < y0 when
/// none does. The kernels take the rows y0 … y1 of a plane in one call.
template <class Has>
std::pair<int, int> row_span(int lo, Has&& has) {
    int y0 = kBlockDim, y1 = lo - 1;
    for (int y = lo; y < kBlockDim; ++y)
        if (has(y)) {
            y0 = std::min(y0, y);
            y1 = y;
        }
    return {y0, y1};
}

/// Σ m·E over the 8³ samples of a block (E in the padded layout, m in the block's): eight lanes,
/// each summing its column over the rows in order, then a fixed tree; so the same on every thread
/// and vector width. A mask, not a product: E holds stale values where m is 0. Written with vector
/// types because GCC 12 leaves the eight column sums scalar, with a branch per sample.
NF_ROW_KERNEL double masked_block_sum(const float* __restrict E, const std::uint8_t* __restrict m) {
    using v8f = float __attribute__((vector_size(32)));
    using v8i = std::int32_t __attribute__((vector_size(32)));
    v8f acc = {};
    for (int z = 0; z < kBlockDim; ++z)
        for (int y = 0; y < kBlockDim; ++y) {
            v8f e;
            std::memcpy(&e, E + lidx(0, y, z), sizeof e);
            const std::uint8_t* r = m + bidx(0, y, z);
            const v8i mi = {r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7]};
            const v8i keep = mi != 0;  // lanes of all ones or zeros
            acc += reinterpret_cast<v8f>(reinterpret_cast<v8i>(e) & keep);
        }
    return double(((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7])));
}

/// The update of `rows` consecutive rows of 8 samples of the normal loop (stride L in the padded
/// buffers, kBlockDim in m and d): N ← normalize(N + dt (I − NNᵀ) ∇·F) where m (the active samples),
/// N elsewhere. f<a><c>: flux component c through the faces x+½e_a of the row (the face below a
/// sample is at −1, −L, −L² from it); n<c>: the normals. Branch-free (selects) and with restrict
/// parameters so that it vectorises. Returns 1 if an active result is not finite.
NF_ROW_KERNEL int update_row(const float* __restrict fx0, const float* __restrict fx1, const float* __restrict fx2,
               const float* __restrict fy0, const float* __restrict fy1, const float* __restrict fy2,
               const float* __restrict fz0, const float* __restrict fz1, const float* __restrict fz2,
               const float* __restrict n0, const float* __restrict n1, const float* __restrict n2,
               const std::uint8_t* __restrict m, float dt, int rows, float* __restrict d0, float* __restrict d1,
               float* __restrict d2) {
    int nonfinite = 0;
    for (int r = 0; r < rows; ++r, fx0 += L, fx1 += L, fx2 += L, fy0 += L, fy1 += L, fy2 += L, fz0 += L, fz1 += L,
             fz2 += L, n0 += L, n1 += L, n2 += L, m += kBlockDim, d0 += kBlockDim, d1 += kBlockDim, d2 += kBlockDim) {
        std::int32_t mi[kBlockDim];
        widen_mask(m, mi);
        for (int x = 0; x < kBlockDim; ++x) {
            const float v0 = (fx0[x] - fx0[x - 1]) + (fy0[x] - fy0[x - L]) + (fz0[x] - fz0[x - L2]);
            const float v1 = (fx1[x] - fx1[x - 1]) + (fy1[x] - fy1[x - L]) + (fz1[x] - fz1[x - L2]);
            const float v2 = (fx2[x] - fx2[x - 1]) + (fy2[x] - fy2[x - L]) + (fz2[x] - fz2[x - L2]);
            const float nx = n0[x], ny = n1[x], nz = n2[x];
            const float pn = v0 * nx + v1 * ny + v2 * nz;
            const float ux = nx + dt * (v0 - pn * nx);
            const float uy = ny + dt * (v1 - pn * ny);
            const float uz = nz + dt * (v2 - pn * nz);
            const float len = std::sqrt(ux * ux + uy * uy + uz * uz);
            const bool act = mi[x] != 0;
            nonfinite |= int(act & !(len <= std::numeric_limits<float>::max()));
            const float div = len > 1e-6f ? len : 1.0f;
            d0[x] = act ? ux / div : nx;
            d1[x] = act ? uy / div : ny;
            d2[x] = act ? uz / div : nz;
        }
    }
    return nonfinite;
}

/// The refit terms of one axis at the samples of a row: H_φ's staggered part (Eq. 54), the
/// upwind squared gradients for F > 0 / F < 0.
template <int sa, int sb, int sc>
inline void refit_axis(const float* __restrict P, int x, float& H, float& gp2, float& gm2) {
    const float p = P[x];
    const float dp = P[x + sa] - p;
    const float dm = p - P[x - sa];
    const float bp = 0.25f * ((P[x + sb] - P[x - sb]) + (P[x + sa + sb] - P[x + sa - sb]));
    const float cp = 0.25f * ((P[x + sc] - P[x - sc]) + (P[x + sa + sc] - P[x + sa - sc]));
    const float bm = 0.25f * ((P[x + sb] - P[x - sb]) + (P[x - sa + sb] - P[x - sa - sb]));
    const float cm = 0.25f * ((P[x + sc] - P[x - sc]) + (P[x - sa + sc] - P[x - sa - sc]));
    const float np = std::sqrt(dp * dp + bp * bp + cp * cp);
    const float nm = std::sqrt(dm * dm + bm * bm + cm * cm);
    H += dp / std::max(np, 1e-6f) - dm / std::max(nm, 1e-6f);
    const float dmp = std::max(dm, 0.0f), dmn = std::min(dm, 0.0f);
    const float dpp = std::max(dp, 0.0f), dpn = std::min(dp, 0.0f);
    gp2 += dmp * dmp + dpn * dpn;
    gm2 += dmn * dmn + dpp * dpp;
}

/// One refit step on `rows` consecutive rows of 8 samples (one call per plane: see face_row):
/// out = φ + dt |∇φ|_upwind (H_φ − hn) where m (the active samples), φ elsewhere. P points at the
/// first row's first sample in the padded local buffer (rows L apart; hn, m, out kBlockDim apart).
/// Branch-free, so that it vectorises.
/// Returns 1 if an active result is not finite.
NF_ROW_KERNEL int refit_row(const float* __restrict P, const float* __restrict hn, const std::uint8_t* __restrict m,
                            float dt, int rows, float* __restrict out) {
    int nonfinite = 0;
    for (int r = 0; r < rows; ++r, P += L, hn += kBlockDim, m += kBlockDim, out += kBlockDim) {
        std::int32_t mi[kBlockDim];
        widen_mask(m, mi);
        for (int x = 0; x < kBlockDim; ++x) {
            float H = 0.0f, gp2 = 0.0f, gm2 = 0.0f;
            refit_axis<kStride[0], kStride[1], kStride[2]>(P, x, H, gp2, gm2);
            refit_axis<kStride[1], kStride[2], kStride[0]>(P, x, H, gp2, gm2);
            refit_axis<kStride[2], kStride[0], kStride[1]>(P, x, H, gp2, gm2);
            const float rhs = H - hn[x];  // φ_t = |∇φ| rhs, speed F = −rhs
            const float grad = std::sqrt(rhs < 0.0f ? gp2 : gm2);
            const float v = P[x] + dt * grad * rhs;
            const bool act = mi[x] != 0;
            nonfinite |= int(act & !(std::abs(v) <= std::numeric_limits<float>::max()));
            out[x] = act ? v : P[x];
        }
    }
    return nonfinite;
}

/// The refit energy D = Σ (|∇φ| − ∇φ·N) over the active samples of a row of 8 (central differences,
/// P at the row's first sample in the padded local buffer), summed in x order: the refit's steps
/// and refit_energy() give the same D for the same φ.
NF_ROW_KERNEL double refit_energy_row(const float* __restrict P, const std::uint8_t* __restrict m,
                                      const float* __restrict n0, const float* __restrict n1,
                                      const float* __restrict n2) {
    float gnorm[kBlockDim], gdot[kBlockDim];
    for (int x = 0; x < kBlockDim; ++x) {  // vectorised
        const float gx = 0.5f * (P[x + 1] - P[x - 1]);
        const float gy = 0.5f * (P[x + L] - P[x - L]);
        const float gz = 0.5f * (P[x + L2] - P[x - L2]);
        gnorm[x] = std::sqrt(gx * gx + gy * gy + gz * gz);
        gdot[x] = gx * n0[x] + gy * n1[x] + gz * n2[x];
    }
    double e = 0.0;
    for (int x = 0; x < kBlockDim; ++x)
        if (m[x]) e += double(gnorm[x]) - double(gdot[x]);
    return e;
}

/// One Jacobi pass of the unsigned distance over the 8³ samples of a block, row by row in one call
/// (a row is one vector iteration whose sorting network and roots would otherwise stall alone; see
/// face_row): where m is set the sample is fixed (out = U), elsewhere out = min(U, the Godunov
/// upwind solution of |∇u| = 1 from the smaller neighbour per axis, h = 1). U and out: the padded
/// local buffers, m in the block's layout.
/// Branch-free (a sorting network and selects) so that it vectorises; the same values as solving
/// with the sorted neighbours a0 <= a1 <= a2 in turn: a0 + 1, then the 2-D, then the 3-D root.
/// Returns 1 when a free sample decreased by more than kReinitTolerance to below limit (a value
/// depends only on smaller ones, so the samples below limit converge whatever happens above it).
NF_ROW_KERNEL int eikonal_block(const float* __restrict U0, const std::uint8_t* __restrict m0, float limit,
                                float* __restrict out0) {
    int changed = 0;
    for (int r = 0; r < kBlockDim * kBlockDim; ++r) {
        const int q0 = lidx(0, r % kBlockDim, r / kBlockDim);
        const float* U = U0 + q0;
        float* out = out0 + q0;
        std::int32_t mi[kBlockDim];
        widen_mask(m0 + r * kBlockDim, mi);
        for (int x = 0; x < kBlockDim; ++x) {
            const float c = U[x];
            float a0 = std::min(U[x - 1], U[x + 1]);
            float a1 = std::min(U[x - L], U[x + L]);
            float a2 = std::min(U[x - L2], U[x + L2]);
            const float s01 = std::min(a0, a1), l01 = std::max(a0, a1);
            a0 = s01;
            a1 = std::min(l01, a2);
            a2 = std::max(l01, a2);
            const float s0 = std::min(a0, a1);
            a1 = std::max(a0, a1);
            a0 = s0;
            const float d1 = a0 + 1.0f;
            const float s2 = a0 + a1;
            const float dd = a0 - a1;
            const float d2 = 0.5f * (s2 + std::sqrt(std::max(2.0f - dd * dd, 0.0f)));
            const float s3 = a0 + a1 + a2;
            const float q2 = a0 * a0 + a1 * a1 + a2 * a2;
            const float d3 = (s3 + std::sqrt(std::max(s3 * s3 - 3.0f * (q2 - 1.0f), 0.0f))) / 3.0f;
            const float d = d1 > a1 ? (d2 > a2 ? d3 : d2) : d1;
            const float nu = std::min(c, d);
            const bool fixed = mi[x] != 0;
            changed |= int(!fixed & (c - nu > kReinitTolerance) & (nu < limit));
            out[x] = fixed ? c : nu;
        }
    }
    return changed;
}


class LevelSetEngine {
public:
    LevelSetEngine(const Volume& v, const SmoothOptions& opt, SmoothReport& rep, Progress* progress)
        : grid_(v.grid), opt_(opt), rep_(rep), progress_(progress) {
        if (opt_.iterations == 0) opt_.iterations = default_iterations(opt_.mode);
        block_dims_ = v.block_dims;
        table_ = v.block_table;
        coords_ = v.block_coords;
        const float inv_h = float(1.0 / v.grid.voxel_size);
        phi_.resize(v.values.size());
        for_samples(v.values.size(), [&](std::size_t i) {
            phi_[i] = std::clamp(v.values[i] * inv_h, -kHalfWidth, kHalfWidth);
        });
        inv2mu2_ = 1.0f / (2.0f * opt.mu * opt.mu);
    }

    bool has_surface() const {
        for (std::size_t b = 0; b < coords_.size(); ++b) {
            const float* p = phi_.data() + b * kBlockVoxels;
            bool neg = false, pos = false;
            for (int i = 0; i < kBlockVoxels; ++i) (p[i] < 0.0f ? neg : pos) = true;
            if (neg && pos) return true;
        }
        // a surface can also lie between a block and an unallocated neighbour of the other sign
        for (std::size_t b = 0; b < coords_.size(); ++b) {
            const float s = phi_[b * kBlockVoxels];
            for (int a = 0; a < 3; ++a)
                for (int d = -1; d <= 1; d += 2) {
                    auto c = coords_[b];
                    c[a] += d;
                    if (c[a] < 0 || c[a] >= block_dims_[a]) continue;
                    const std::int32_t t = table_[tindex(c[0], c[1], c[2])];
                    if ((t == kBlockInside && s >= 0.0f) || (t == kBlockOutside && s < 0.0f)) return true;
                }
        }
        return false;
    }

    void run() {
        const auto t_band = Clock::now();
        update_band();
        // out to the full half width, not just working_limit(): a run that stops in its first
        // iteration (below) then returns this φ as it is
        reinitialise(kHalfWidth);
        rep_.seconds_reinit += seconds_since(t_band);
        for (int it = 0; it < opt_.iterations; ++it) {
            const auto t_it = Clock::now();
            iteration_ = it;
            build_active();
            rep_.band_voxels.push_back(active_voxels_);
            rep_.allocated_voxels.push_back(coords_.size() * kBlockVoxels);
            if (opt_.mode == SmoothMode::MeanCurvature) {
                const auto t0 = Clock::now();
                std::fill(hn_.begin(), hn_.end(), 0.0f);
                copy_samples(phi_, phi2_);  // refit_step writes only the active blocks of phi2_
                for (int s = 0; s < opt_.normal_steps; ++s) {
                    refit_step(false);
                    tick(double(s + 1) / opt_.normal_steps);
                }
                rep_.seconds_refit += seconds_since(t0);
            } else {
                const auto t0 = Clock::now();
                normal_loop();
                rep_.seconds_normals += seconds_since(t0);
                const auto t1 = Clock::now();
                refit_loop();
                rep_.seconds_refit += seconds_since(t1);
            }
            // A refit that kept no step leaves φ bit for bit as this iteration found it (refit_loop
            // restores it), and the next iteration would start from that φ and the same µ (the
            // schedule takes the smaller of the last µ and one measured on the same normals): it
            // and every later one would repeat this one exactly. So stop, with the final
            // reinitialisation, which φ already had if the last one went out to kHalfWidth (a
            // stop in the first iteration): the surface did not move, so neither does the band.
            // (Reinitialising the unchanged φ and going on would only let the interface samples'
            // φ/|∇φ| drift a little each time.)
            const bool unchanged = opt_.mode != SmoothMode::MeanCurvature && rep_.refit_steps.back() == 0;
            const auto t2 = Clock::now();
            if (!(unchanged && reinit_limit_ >= kHalfWidth)) {
                update_band();
                reinitialise(it + 1 < opt_.iterations && !unchanged ? working_limit() : kHalfWidth);
            }
            rep_.seconds_reinit += seconds_since(t2);
            rep_.seconds_per_iteration.push_back(seconds_since(t_it));
            rep_.iterations = it + 1;
            if (unchanged && it + 1 < opt_.iterations) {
                rep_.stopped_unchanged = true;
                detail::tick(progress_, 1.0, "smooth_volume");
                break;
            }
        }
    }

    /// The distances a main iteration reads are exact below this (voxels); above, φ need only be at
    /// least this. The normal loop and the refit read φ at the active samples (|φ| <= active_band)
    /// and at their neighbours up to 2 voxels away (tangential gradients at the faces, curvature);
    /// one voxel more for safety. The last reinitialisation, whose φ is returned, is exact to
    /// kHalfWidth.
    float working_limit() const { return std::min(kHalfWidth, opt_.active_band + 3.0f); }

    void write_back(Volume& v) const {
        const float h = float(v.grid.voxel_size);
        v.half_width = kHalfWidth;
        v.background = float(kHalfWidth * v.grid.voxel_size);
        v.block_table = table_;
        v.block_coords = coords_;
        v.values.resize(phi_.size());
        for_samples(phi_.size(), [&](std::size_t i) { v.values[i] = phi_[i] * h; });
    }

private:
    // ---------------------------------------------------------------- layout helpers
    std::size_t tindex(int bi, int bj, int bk) const {
        return (std::size_t(bk) * block_dims_[1] + std::size_t(bj)) * block_dims_[0] + std::size_t(bi);
    }
    std::size_t nblocks() const { return coords_.size(); }

    void neighbourhood(std::size_t b, Neighbourhood& n) const {
        const auto& bc = coords_[b];
        for (int a = 0; a < 3; ++a) {
            n.ext[a] = std::min(kBlockDim, grid_.dims[a] - bc[a] * kBlockDim);
            for (int l = -1; l <= kBlockDim; ++l) {
                const int g = std::clamp(bc[a] * kBlockDim + l, 0, grid_.dims[a] - 1);
                n.nb[a][l + 1] = std::uint8_t((g >> kBlockLog2) - bc[a] + 1);
                n.li[a][l + 1] = std::uint8_t(g & (kBlockDim - 1));
            }
        }
        n.contiguous_x = true;
        for (int l = 0; l < kBlockDim; ++l)
            if (n.nb[0][l + 1] != 1 || n.li[0][l + 1] != l) n.contiguous_x = false;
        for (int dz = 0; dz < 3; ++dz)
            for (int dy = 0; dy < 3; ++dy)
                for (int dx = 0; dx < 3; ++dx) {
                    const int c[3] = {bc[0] + dx - 1, bc[1] + dy - 1, bc[2] + dz - 1};
                    std::int32_t s = kBlockOutside;
                    if (c[0] >= 0 && c[1] >= 0 && c[2] >= 0 && c[0] < block_dims_[0] && c[1] < block_dims_[1] &&
                        c[2] < block_dims_[2])
                        s = table_[tindex(c[0], c[1], c[2])];
                    n.slot[(dz * 3 + dy) * 3 + dx] = s;
                }
    }

    /// Copies K fields f[k] (with halo 1) into out[k]; unallocated blocks give t_in / t_out.
    /// Row by row: the 8 interior samples of a row come from one block (one copy or fill); where
    /// each row's samples come from is worked out once for all K fields.
    template <int K>
    static void gather_k(const Neighbourhood& n, const float* const (&f)[K], float t_in, float t_out,
                         float* const (&out)[K]) {
        auto src = [&](std::int32_t s, int idx) -> std::ptrdiff_t {  // offset, or -1 / -2 for a tile
            return s >= 0 ? std::ptrdiff_t(s) * kBlockVoxels + idx : std::ptrdiff_t(s);
        };
        auto value = [&](const float* fk, std::ptrdiff_t o) {
            return o >= 0 ? fk[o] : (o == kBlockInside ? t_in : t_out);
        };
        for (int z = 0; z < L; ++z) {
            const int nz = n.nb[2][z], lz = n.li[2][z];
            for (int y = 0; y < L; ++y) {
                const int ny = n.nb[1][y], ly = n.li[1][y];
                const int row = (lz * kBlockDim + ly) * kBlockDim;
                const std::int32_t* srow = n.slot + (nz * 3 + ny) * 3;
                const int q = (z * L + y) * L;
                const std::ptrdiff_t left = src(srow[n.nb[0][0]], row + n.li[0][0]);
                const std::ptrdiff_t right = src(srow[n.nb[0][L - 1]], row + n.li[0][L - 1]);
                if (n.contiguous_x) {
                    const std::ptrdiff_t mid = src(srow[1], row);
                    for (int k = 0; k < K; ++k) {
                        float* o = out[k] + q;
                        o[0] = value(f[k], left);
                        if (mid >= 0)
                            std::memcpy(o + 1, f[k] + mid, sizeof(float) * kBlockDim);
                        else
                            std::fill(o + 1, o + 1 + kBlockDim, mid == kBlockInside ? t_in : t_out);
                        o[L - 1] = value(f[k], right);
                    }
                } else {
                    for (int x = 0; x < L; ++x) {
                        const std::ptrdiff_t o = src(srow[n.nb[0][x]], row + n.li[0][x]);
                        for (int k = 0; k < K; ++k) out[k][q + x] = value(f[k], o);
                    }
                }
            }
        }
    }
    static void gather(const Neighbourhood& n, const float* f, float t_in, float t_out, float* out) {
        const float* fs[1] = {f};
        float* os[1] = {out};
        gather_k<1>(n, fs, t_in, t_out, os);
    }
    void gather_phi(const Neighbourhood& n, const Samples& f, float* out) const {
        gather(n, f.data(), -kHalfWidth, kHalfWidth, out);
    }
    void gather_n(const Neighbourhood& n, const Samples (&f)[3], float* out0, float* out1,
                  float* out2) const {
        const float* fs[3] = {f[0].data(), f[1].data(), f[2].data()};
        float* os[3] = {out0, out1, out2};
        gather_k<3>(n, fs, 0.0f, 0.0f, os);
    }

    /// parallel_for over a list of block slots; body(slot, scratch).
    template <class Body>
    void for_blocks(const std::vector<std::int32_t>& list, int scratch_fields, Body&& body) const {
        const std::size_t need = std::size_t(scratch_fields) * L3;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, list.size(), 4),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              std::vector<float>& buf = scratch_.local();
                              if (buf.size() < need) buf.resize(need);
                              Scratch s{buf.data()};
                              for (std::size_t i = r.begin(); i != r.end(); ++i) body(i, list[i], s);
                          });
    }

    /// Honours a stop request between passes of work that reports no progress of its own
    /// (reinitialisation sweeps, conductance pre-smoothing), so cancelling stays prompt.
    void poll() const {
        if (progress_ && progress_->should_stop()) throw Cancelled("smooth_volume: cancelled");
    }

    void tick(double frac_in_iteration) {
        const double f = (iteration_ + std::clamp(frac_in_iteration, 0.0, 1.0)) / opt_.iterations;
        detail::tick(progress_, f, "smooth_volume");
    }

    void fail(const char* what) const {
        throw NumericalError(std::string("smooth_volume: non-finite ") + what + " at main iteration " +
                             std::to_string(iteration_ + 1));
    }

    // ---------------------------------------------------------------- band
    /// body(lo, hi) over [0, n) in chunks of 64 Ki samples, in parallel: elementwise passes over the
    /// whole band, whose first writes to a fresh buffer cost page faults that one thread would take
    /// one after another.
    template <class Body>
    static void for_chunks(std::size_t n, Body&& body) {
        constexpr std::size_t kChunk = std::size_t(1) << 16;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, (n + kChunk - 1) / kChunk),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t c = r.begin(); c != r.end(); ++c)
                                  body(c * kChunk, std::min(n, (c + 1) * kChunk));
                          });
    }
    /// body(i) for every i in [0, n), in parallel (for_chunks).
    template <class Body>
    static void for_samples(std::size_t n, Body&& body) {
        for_chunks(n, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i) body(i);
        });
    }

    /// Resizes a work array to n elements, reallocating with a quarter of headroom when it must grow.
    template <class V>
    static void fit_samples(V& v, std::size_t n) {
        if (v.capacity() < n) {
            v = {};
            v.reserve(n + n / 4);
        }
        v.resize(n);
    }

    /// Blocks holding the surface (a sign change to a 6-neighbour, or |φ| < 1) plus their 26
    /// neighbours stay or become allocated; every other block becomes a tile of its sign.
    void update_band() {
        const std::size_t nb = nblocks();
        std::vector<std::uint8_t> surf(nb, 0);
        std::vector<std::int32_t> all(nb);
        for (std::size_t b = 0; b < nb; ++b) all[b] = std::int32_t(b);
        for_blocks(all, 1, [&](std::size_t, std::int32_t b, Scratch& s) {
            Neighbourhood n;
            neighbourhood(std::size_t(b), n);  // the blocks are about to change: no cached nbh_
            float* P = s.at(0);
            gather_phi(n, phi_, P);
            bool found = false;
            for (int z = 0; z < n.ext[2] && !found; ++z)
                for (int y = 0; y < n.ext[1] && !found; ++y)
                    for (int x = 0; x < n.ext[0]; ++x) {
                        const int q = lidx(x, y, z);
                        const bool in = P[q] < 0.0f;
                        if (std::abs(P[q]) < 1.0f || (P[q + 1] < 0.0f) != in || (P[q - 1] < 0.0f) != in ||
                            (P[q + L] < 0.0f) != in || (P[q - L] < 0.0f) != in || (P[q + L2] < 0.0f) != in ||
                            (P[q - L2] < 0.0f) != in) {
                            found = true;
                            break;
                        }
                    }
            surf[std::size_t(b)] = found;
        });
        std::vector<std::uint8_t> req(table_.size(), 0);
        for (std::size_t b = 0; b < nb; ++b) {
            if (!surf[b]) continue;
            const auto& c = coords_[b];
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
                        if (x < 0 || y < 0 || z < 0 || x >= block_dims_[0] || y >= block_dims_[1] ||
                            z >= block_dims_[2])
                            continue;
                        req[tindex(x, y, z)] = 1;
                    }
        }
        std::vector<std::array<int, 3>> coords;
        std::vector<std::int32_t> table(table_.size());
        std::size_t count = 0;
        for (std::size_t t = 0; t < table_.size(); ++t) count += req[t];
        coords.reserve(count);
        std::vector<std::int32_t> source;  // per new slot: the old slot, or the tile it was
        source.reserve(count);
        // The new φ goes into phi2_'s buffer (free between stages, its pages already touched
        // after the first main iteration), which then becomes phi_.
        Samples& phi = phi2_;
        fit_samples(phi, count * kBlockVoxels);
        for (int z = 0; z < block_dims_[2]; ++z)
            for (int y = 0; y < block_dims_[1]; ++y)
                for (int x = 0; x < block_dims_[0]; ++x) {
                    const std::size_t t = tindex(x, y, z);
                    const std::int32_t old = table_[t];
                    if (req[t]) {
                        const std::int32_t slot = std::int32_t(coords.size());
                        coords.push_back({x, y, z});
                        source.push_back(old);
                        table[t] = slot;
                    } else if (old >= 0) {
                        table[t] = phi_[std::size_t(old) * kBlockVoxels] < 0.0f ? kBlockInside : kBlockOutside;
                    } else {
                        table[t] = old;
                    }
                }
        // the blocks' values, in parallel (their first writes to a fresh buffer fault)
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, source.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t slot = r.begin(); slot != r.end(); ++slot) {
                float* dst = phi.data() + slot * kBlockVoxels;
                const std::int32_t old = source[slot];
                if (old >= 0)
                    std::memcpy(dst, phi_.data() + std::size_t(old) * kBlockVoxels, sizeof(float) * kBlockVoxels);
                else
                    std::fill(dst, dst + kBlockVoxels, old == kBlockInside ? -kHalfWidth : kHalfWidth);
            }
        });
        table_ = std::move(table);
        coords_ = std::move(coords);
        std::swap(phi_, phi2_);
        // The per-sample work arrays: every stage writes what it reads after the blocks moved, so
        // their contents need not survive (their slots changed anyway). A growing array is
        // reallocated with headroom rather than copied: as the band moves it grows by a few blocks
        // at a time, and resizing these twelve arrays of the whole band (copy, zero fill, page
        // faults) took 0.2–0.3 s per call on bunny at resolution 256, serial. Untouched headroom
        // costs address space, not memory.
        const std::size_t n = phi_.size();
        fit_samples(phi2_, n);
        for (int c = 0; c < 3; ++c) {
            fit_samples(n_[c], n);
            fit_samples(n2_[c], n);
            fit_samples(aux_[c], n);
        }
        fit_samples(hn_, n);
        fit_samples(mask_, n);
        nbh_.resize(nblocks());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks(), 64),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t b = r.begin(); b != r.end(); ++b) neighbourhood(b, nbh_[b]);
                          });
    }

    /// φ ← signed distance in the band: interface samples keep φ/|∇φ| (bounded by the distance to
    /// the axis crossings of the zero level), the others get Jacobi sweeps of the Godunov update.
    /// The sweeps stop when the distances below limit have converged; those at or above it are
    /// then at least limit (the sweeps only lower an upper bound), not necessarily converged.
    void reinitialise(float limit) {
        reinit_limit_ = limit;
        const std::size_t nb = nblocks();
        std::vector<std::int32_t> all(nb);
        for (std::size_t b = 0; b < nb; ++b) all[b] = std::int32_t(b);
        Samples& u = phi2_;       // unsigned distance
        Samples& u2 = aux_[0];    // ping-pong buffer
        std::atomic<bool> bad{false};
        for_blocks(all, 1, [&](std::size_t, std::int32_t b, Scratch& s) {
            const Neighbourhood& n = nbh_[std::size_t(b)];
            float* P = s.at(0);
            gather_phi(n, phi_, P);
            const std::size_t base = std::size_t(b) * kBlockVoxels;
            for (int z = 0; z < kBlockDim; ++z)
                for (int y = 0; y < kBlockDim; ++y)
                    for (int x = 0; x < kBlockDim; ++x) {
                        const int q = lidx(x, y, z);
                        const float p = P[q];
                        const bool in = p < 0.0f;
                        float bound = kHalfWidth;
                        for (int a = 0; a < 3; ++a) {
                            const int st = kStride[a];
                            for (const float o : {P[q + st], P[q - st]})
                                if ((o < 0.0f) != in) bound = std::min(bound, p / (p - o));
                        }
                        const std::size_t i = base + std::size_t(bidx(x, y, z));
                        if (bound < kHalfWidth) {
                            const float gx = 0.5f * (P[q + 1] - P[q - 1]);
                            const float gy = 0.5f * (P[q + L] - P[q - L]);
                            const float gz = 0.5f * (P[q + L2] - P[q - L2]);
                            const float gn = std::sqrt(gx * gx + gy * gy + gz * gz);
                            float d = gn > 1e-6f ? std::abs(p) / gn : bound;
                            d = std::min(d, bound);
                            if (!std::isfinite(d)) bad = true;
                            u[i] = d;
                            mask_[i] = 1;
                        } else {
                            u[i] = kHalfWidth;
                            mask_[i] = 0;
                        }
                    }
        });
        if (bad) fail("distance during reinitialisation");
        // Block-Jacobi passes. Each pass gathers a block with its halo from the last pass's
        // distances and runs Jacobi passes inside the block, the halo held, until they settle
        // (kLocalPasses at most): a front then crosses a whole block per pass instead of one
        // voxel, and the gather, which costs more than a pass over the block, is paid once.
        // Every block reads only the last pass's buffer, so the result does not depend on the
        // order or the thread count. The update reads the six face neighbours only, so a block is
        // computed again only when the layer a face neighbour shares with it changed (a sample
        // lowered by more than kReinitTolerance to below limit) in the last pass, when its own
        // passes stopped at kLocalPasses before settling, or, on the grid's border, where its halo
        // is its own outer layer, when it changed itself. The newest values of a block skipped now
        // but computed in the last pass are copied into the buffer this pass writes, so that it
        // always holds every block's newest.
        constexpr int kLocalPasses = 3 * kBlockDim;  // a front crosses a block in at most 3·(8−1)+1
        constexpr std::uint8_t kAnyChange = 1 << 6;  // bits 2a, 2a+1: layer 0, 7 of axis a changed
        std::vector<std::uint8_t> changed(nb, 0), unsettled(nb, 0), computed(nb, 0), computed_now(nb, 0);
        std::vector<std::int32_t> todo;
        todo.reserve(nb);
        auto needed = [&](std::size_t b) {
            if (unsettled[b]) return true;
            const Neighbourhood& n = nbh_[b];
            for (int a = 0; a < 3; ++a) {
                const int st = a == 0 ? 1 : a == 1 ? 3 : 9;  // slot stride of axis a
                for (int side = 0; side < 2; ++side) {
                    const int off = n.nb[a][side ? L - 1 : 0];  // 0 or 2: a neighbour, 1: the border (itself)
                    const std::int32_t sb = n.slot[13 + (off - 1) * st];
                    if (sb < 0) continue;  // a tile: constant
                    const std::uint8_t bits = changed[std::size_t(sb)];
                    if (off == 1 ? (bits & kAnyChange) != 0 : ((bits >> (2 * a + 1 - side)) & 1) != 0) return true;
                }
            }
            return false;
        };
        const int max_passes = int(kHalfWidth * 3);
        for (int pass = 0; pass < max_passes; ++pass) {
            poll();
            todo.clear();
            for (std::size_t b = 0; b < nb; ++b) {
                computed_now[b] = pass == 0 || needed(b);
                if (computed_now[b]) todo.push_back(std::int32_t(b));
            }
            if (todo.empty()) break;  // settled: u holds every block's newest
            for (std::size_t b = 0; b < nb; ++b)
                if (!computed_now[b] && computed[b])
                    std::memcpy(u2.data() + b * kBlockVoxels, u.data() + b * kBlockVoxels, sizeof(float) * kBlockVoxels);
            std::swap(computed, computed_now);
            std::fill(changed.begin(), changed.end(), std::uint8_t(0));
            for_blocks(todo, 2, [&](std::size_t, std::int32_t b, Scratch& s) {
                const Neighbourhood& n = nbh_[std::size_t(b)];
                float* U = s.at(0);
                float* V = s.at(1);
                gather(n, u.data(), kHalfWidth, kHalfWidth, U);
                std::memcpy(V, U, sizeof(float) * L3);  // the halo, held during the local passes
                const std::size_t base = std::size_t(b) * kBlockVoxels;
                const std::uint8_t* M = mask_.data() + base;
                int ch = 1, local = 0;
                for (; ch && local < kLocalPasses; ++local) {
                    ch = eikonal_block(U, M, limit, V);
                    std::swap(U, V);
                }
                // which outer layers changed since the last pass (u holds the block's last values)
                std::uint8_t bits = 0;
                const float* old = u.data() + base;
                float* out = u2.data() + base;
                for (int z = 0; z < kBlockDim; ++z)
                    for (int y = 0; y < kBlockDim; ++y) {
                        const int i0 = bidx(0, y, z);
                        const float* row = U + lidx(0, y, z);
                        std::memcpy(out + i0, row, sizeof(float) * kBlockDim);
                        for (int x = 0; x < kBlockDim; ++x) {
                            if (!(old[i0 + x] - row[x] > kReinitTolerance && row[x] < limit)) continue;
                            bits |= kAnyChange;
                            if (x == 0) bits |= 1;
                            if (x == kBlockDim - 1) bits |= 2;
                            if (y == 0) bits |= 4;
                            if (y == kBlockDim - 1) bits |= 8;
                            if (z == 0) bits |= 16;
                            if (z == kBlockDim - 1) bits |= 32;
                        }
                    }
                changed[std::size_t(b)] = bits;
                unsettled[std::size_t(b)] = std::uint8_t(ch);
            });
            std::swap(phi2_, aux_[0]);  // u <-> u2 (references follow the buffers' names)
        }
        // after the swaps the newest distances are in phi2_ (u refers to phi2_)
        for_samples(phi_.size(), [&](std::size_t i) {
            const float d = std::min(phi2_[i], kHalfWidth);
            phi_[i] = phi_[i] < 0.0f ? -d : d;
        });
    }

    // ---------------------------------------------------------------- active band
    void build_active() {
        const float band = opt_.active_band;
        std::vector<std::uint32_t> count(nblocks());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t b = r.begin(); b != r.end(); ++b) {
                const auto& c = coords_[b];
                int ext[3];
                for (int a = 0; a < 3; ++a) ext[a] = std::min(kBlockDim, grid_.dims[a] - c[a] * kBlockDim);
                std::uint32_t cnt = 0;
                const std::size_t base = b * kBlockVoxels;
                for (int z = 0; z < kBlockDim; ++z)
                    for (int y = 0; y < kBlockDim; ++y)
                        for (int x = 0; x < kBlockDim; ++x) {
                            const std::size_t i = base + std::size_t(bidx(x, y, z));
                            const bool a = x < ext[0] && y < ext[1] && z < ext[2] && std::abs(phi_[i]) <= band;
                            mask_[i] = a;
                            cnt += a;
                        }
                count[b] = cnt;
            }
        });
        active_.clear();
        active_voxels_ = 0;
        for (std::size_t b = 0; b < nblocks(); ++b) {
            if (count[b]) active_.push_back(std::int32_t(b));
            active_voxels_ += count[b];
        }
    }

    // ---------------------------------------------------------------- normals
    void init_normals() {
        std::vector<std::int32_t> all(nblocks());
        for (std::size_t b = 0; b < all.size(); ++b) all[b] = std::int32_t(b);
        for_blocks(all, 1, [&](std::size_t, std::int32_t b, Scratch& s) {
            const Neighbourhood& n = nbh_[std::size_t(b)];
            float* P = s.at(0);
            gather_phi(n, phi_, P);
            const std::size_t base = std::size_t(b) * kBlockVoxels;
            for (int z = 0; z < kBlockDim; ++z)
                for (int y = 0; y < kBlockDim; ++y)
                    for (int x = 0; x < kBlockDim; ++x) {
                        const int q = lidx(x, y, z);
                        const float gx = 0.5f * (P[q + 1] - P[q - 1]);
                        const float gy = 0.5f * (P[q + L] - P[q - L]);
                        const float gz = 0.5f * (P[q + L2] - P[q - L2]);
                        const float gn = std::sqrt(gx * gx + gy * gy + gz * gz);
                        const float inv = gn > 1e-6f ? 1.0f / gn : 0.0f;
                        const std::size_t i = base + std::size_t(bidx(x, y, z));
                        n_[0][i] = gx * inv;
                        n_[1][i] = gy * inv;
                        n_[2][i] = gz * inv;
                    }
        });
    }

    /// φ of every active block with its halo, held for the whole normal loop (φ does not change
    /// there): the steps read it instead of gathering it again.
    void cache_phi() {
        pad_phi_.resize(active_.size() * std::size_t(L3));
        row_band_.resize(active_.size() * std::size_t(kRowFlags));
        const float band = opt_.active_band;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active_.size(), 16),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t k = r.begin(); k != r.end(); ++k) {
                                  float* P = pad_phi_.data() + k * L3;
                                  gather_phi(nbh_[std::size_t(active_[k])], phi_, P);
                                  std::uint8_t* rows = row_band_.data() + k * kRowFlags;
                                  for (int a = 0; a < 3; ++a) {
                                      const int sa = kStride[a];
                                      int lo[3] = {0, 0, 0};
                                      lo[a] = -1;
                                      for (int z = lo[2]; z < kBlockDim; ++z)
                                          for (int y = lo[1]; y < kBlockDim; ++y) {
                                              const int q0 = lidx(lo[0], y, z);
                                              bool any = false;  // a face of the row touches the band
                                              for (int j = 0; j < kBlockDim - lo[0]; ++j)
                                                  any |= !(std::abs(P[q0 + j]) > band && std::abs(P[q0 + j + sa]) > band);
                                              rows[row_flag(a, y, z)] = any;
                                          }
                                  }
                              }
                          });
    }

    /// One step of the normal loop on src → dst over the active blocks; returns G(src).
    /// update == false: only the energy. Reads φ from pad_phi_ and, when Frozen, g from pad_g_.
    double normal_step(Samples (&src)[3], Samples (&dst)[3], FaceWeight cond,
                       bool update) {
        std::vector<double> energy(active_.size(), 0.0);
        std::atomic<bool> bad{false};
        const float dt = std::min(opt_.normal_dt, kMaxDt);
        const float inv2mu2 = inv2mu2_;
        const float band = opt_.active_band;
        for_blocks(active_, 13, [&](std::size_t k, std::int32_t b, Scratch& s) {
            const Neighbourhood& n = nbh_[std::size_t(b)];
            const float* P = pad_phi_.data() + k * L3;
            float* N[3] = {s.at(0), s.at(1), s.at(2)};
            float* F[3][3] = {{s.at(3), s.at(4), s.at(5)}, {s.at(6), s.at(7), s.at(8)}, {s.at(9), s.at(10), s.at(11)}};
            float* E = s.at(12);  // energy density of the faces of one axis
            gather_n(n, src, N[0], N[1], N[2]);
            const std::size_t base = std::size_t(b) * kBlockVoxels;
            const std::uint8_t* M = mask_.data() + base;
            const std::uint8_t* rows = row_band_.data() + k * kRowFlags;
            double e = 0.0;
            for (int a = 0; a < 3; ++a) {
                int lo[3] = {0, 0, 0};
                lo[a] = -1;
                auto faces = [&](int q0, int count, int nrows) {
                    switch (cond) {
                        case FaceWeight::One:
                            face_rows<FaceWeight::One>(a, P, N[0], nullptr, q0, count, nrows, band, inv2mu2, F[a][0], E);
                            break;
                        case FaceWeight::Frozen:
                            face_rows<FaceWeight::Frozen>(a, P, N[0], pad_g_[a].data() + k * L3, q0, count, nrows, band,
                                                          inv2mu2, F[a][0], E);
                            break;
                        case FaceWeight::Live:
                            face_rows<FaceWeight::Live>(a, P, N[0], nullptr, q0, count, nrows, band, inv2mu2, F[a][0], E);
                            break;
                    }
                };
                // Rows whose faces all lie outside the band are not computed: the divergence below
                // reads only the faces of active samples, which lie in the band.
                if (a == 0) {
                    // x faces, 9 per row (x = −1 … 7): the flagged rows of a z plane in one run over
                    // the padded buffer, rounded up to whole vectors, instead of a row of 8 plus a
                    // scalar ninth face each. The extra faces (x = 8, and unflagged rows inside the
                    // run) lie in the buffer and are never read.
                    for (int z = 0; z < kBlockDim; ++z) {
                        const auto [y0, y1] = row_span(0, [&](int y) { return rows[row_flag(0, y, z)] != 0; });
                        if (y1 < y0) continue;
                        const int count = ((y1 - y0) * L + (kBlockDim + 1) + (kBlockDim - 1)) / kBlockDim * kBlockDim;
                        faces(lidx(-1, y0, z), count, 1);
                    }
                } else {
                    // y and z faces, 8 per row: the flagged rows of a z plane in one call, row by
                    // row (unflagged rows inside the span are computed and never read), so that
                    // the rows' long dependency chains (division, exp) overlap.
                    for (int z = lo[2]; z < kBlockDim; ++z) {
                        const auto [y0, y1] = row_span(lo[1], [&](int y) { return rows[row_flag(a, y, z)] != 0; });
                        if (y1 >= y0) faces(lidx(0, y0, z), kBlockDim, y1 - y0 + 1);
                    }
                }
                // energy of the faces owned by the active samples of this block (in band: computed)
                e += masked_block_sum(E, M);
            }
            energy[k] = e;
            if (!update) return;
            // N ← normalize(N + dt (I − NNᵀ) ∇·F) at the active samples; the rest keep N. Rows of
            // 8, branch-free (selects), so that the loop vectorises.
            int nonfinite = 0;
            auto update_rows = [&](int y, int z, int count) {
                const int q0 = lidx(0, y, z);
                const std::size_t i0 = base + std::size_t(bidx(0, y, z));
                nonfinite |= update_row(F[0][0] + q0, F[0][1] + q0, F[0][2] + q0, F[1][0] + q0, F[1][1] + q0,
                                        F[1][2] + q0, F[2][0] + q0, F[2][1] + q0, F[2][2] + q0, N[0] + q0, N[1] + q0,
                                        N[2] + q0, mask_.data() + i0, dt, count, dst[0].data() + i0,
                                        dst[1].data() + i0, dst[2].data() + i0);
            };
            // Row by row over the span of a z plane's rows with active samples, in one call (see
            // face_row). A row inside the span without any gets dst = N, which dst already holds
            // there (see normal_loop).
            for (int z = 0; z < kBlockDim; ++z) {
                const auto [y0, y1] = row_span(0, [&](int y) { return any_in_row(M + bidx(0, y, z)); });
                if (y1 >= y0) update_rows(y0, z, y1 - y0 + 1);
            }
            if (nonfinite) bad = true;
        });
        if (bad) fail("normal in the normal loop");
        double sum = 0.0;
        for (const double e : energy) sum += e;
        return sum;
    }

    /// κ² at the faces q+½e_a of every allocated sample i for which keep(i, φ_i) holds, from the
    /// normals in src: emit(block, a, i, κ²), in parallel over blocks.
    template <class Keep, class Emit>
    void face_curvatures(Samples (&src)[3], Keep&& keep, Emit&& emit) {
        std::vector<std::int32_t> all(nblocks());
        for (std::size_t b = 0; b < all.size(); ++b) all[b] = std::int32_t(b);
        for_blocks(all, 4, [&](std::size_t, std::int32_t b, Scratch& s) {
            const Neighbourhood& n = nbh_[std::size_t(b)];
            float* P = s.at(0);
            float* N[3] = {s.at(1), s.at(2), s.at(3)};
            gather_phi(n, phi_, P);
            gather_n(n, src, N[0], N[1], N[2]);
            const float* Nc[3] = {N[0], N[1], N[2]};
            const std::size_t base = std::size_t(b) * kBlockVoxels;
            for (int a = 0; a < 3; ++a) {
                const int sa = kStride[a], sb = kStride[(a + 1) % 3], sc = kStride[(a + 2) % 3];
                for (int z = 0; z < kBlockDim; ++z)
                    for (int y = 0; y < kBlockDim; ++y)
                        for (int x = 0; x < kBlockDim; ++x) {
                            const int q = lidx(x, y, z);
                            const std::size_t i = base + std::size_t(bidx(x, y, z));
                            if (!keep(i, P[q])) continue;
                            float m[3], k2;
                            face_terms(P, Nc, q, sa, sb, sc, m, k2);
                            emit(std::size_t(b), a, i, k2);
                        }
            }
        });
    }

    /// The robust noise scale of the curvature, σ_κ, from the normals in src (after Black, Sapiro,
    /// Marimont & Heeger 1998): the lower quartile of |κ| over the faces of the active samples next
    /// to the surface (|φ| <= 1), divided by 0.3186, the quartile of |x| for x ~ N(0, 1). The
    /// quartile, not the median: creases and curved parts may cover up to 3/4 of the surface.
    float curvature_noise_scale(Samples (&src)[3]) {
        std::vector<std::vector<float>> near(nblocks());
        face_curvatures(
            src, [&](std::size_t i, float phi) { return mask_[i] && std::abs(phi) <= 1.0f; },
            [&](std::size_t b, int, std::size_t, float k2) { near[b].push_back(k2); });
        std::vector<float> k2s;  // in block order: the quartile does not depend on the threads
        for (const auto& v : near) k2s.insert(k2s.end(), v.begin(), v.end());
        if (k2s.empty()) return 0.0f;
        auto q = k2s.begin() + std::ptrdiff_t(k2s.size() / 4);
        std::nth_element(k2s.begin(), q, k2s.end());
        return std::sqrt(std::max(*q, 0.0f)) / 0.3186f;
    }

    /// g = exp(−κ²/(2µ²)) at every face q+½e_a of the active blocks, q = −1…7 along a and 0…7
    /// across (all the faces a normal step reads), from the normals in src (Catté et al.), with the
    /// conductance scale mu, into pad_g_ (the padded layout of pad_phi_).
    void conductance_from(Samples (&src)[3], float mu) {
        const float inv2mu2 = 1.0f / (2.0f * mu * mu);
        const float band = opt_.active_band;
        for (int a = 0; a < 3; ++a) pad_g_[a].resize(active_.size() * std::size_t(L3));
        for_blocks(active_, 7, [&](std::size_t k, std::int32_t b, Scratch& s) {
            const float* P = pad_phi_.data() + k * L3;
            float* N[3] = {s.at(0), s.at(1), s.at(2)};
            float* F = s.at(3);  // face fluxes: computed by face_row, unused here
            float* K = s.at(6);
            gather_n(nbh_[std::size_t(b)], src, N[0], N[1], N[2]);
            for (int a = 0; a < 3; ++a) {
                float* G = pad_g_[a].data() + k * L3;
                int lo[3] = {0, 0, 0};
                lo[a] = -1;
                const int nx = kBlockDim - lo[0];
                for (int z = lo[2]; z < kBlockDim; ++z)
                    for (int y = lo[1]; y < kBlockDim; ++y) {
                        const int q0 = lidx(lo[0], y, z);
                        face_rows<FaceWeight::One>(a, P, N[0], nullptr, q0, nx, 1, band, inv2mu2, F, K);
                        for (int j = 0; j < nx; ++j) G[q0 + j] = std::exp(-K[q0 + j] * inv2mu2);
                    }
            }
        });
    }

    /// The conductance scale of this main iteration (see SmoothOptions::mu_robust): µ, or
    /// max(µ, mu_robust · σ_κ). σ_κ is measured on the pre-smoothed normals (the noise that the
    /// conductance will see), but taken as at most the same scale of the raw normals: on a clean
    /// surface the raw normals are exactly flat on its flat parts (σ = 0), while pre-smoothing bends
    /// them near every crease, which on a small part can cover most of the surface. The scale is
    /// never above the previous iteration's (the schedule only goes from coarse to fine).
    float conductance_scale(Samples (&raw)[3], Samples (&presmoothed)[3]) {
        if (!(opt_.mu_robust > 0.0f)) return opt_.mu;
        const float sigma = std::min(curvature_noise_scale(presmoothed), curvature_noise_scale(raw));
        float mu = std::max(opt_.mu, opt_.mu_robust * sigma);
        if (!rep_.mu.empty()) mu = std::min(mu, rep_.mu.back());
        return mu;
    }

    /// dst = src, in parallel (see for_samples).
    static void copy_samples(const Samples& src, Samples& dst) {
        fit_samples(dst, src.size());
        for_chunks(src.size(), [&](std::size_t lo, std::size_t hi) {
            std::memcpy(dst.data() + lo, src.data() + lo, sizeof(float) * (hi - lo));
        });
    }

    void copy_fields(Samples (&src)[3], Samples (&dst)[3]) {
        for (int c = 0; c < 3; ++c) copy_samples(src[c], dst[c]);
    }

    void normal_loop() {
        init_normals();
        cache_phi();
        const bool highboost = opt_.mode == SmoothMode::HighBoost;
        FaceWeight cond = FaceWeight::One;
        if (opt_.mode == SmoothMode::Anisotropic) {
            if (opt_.conductance_presmooth_steps > 0) {
                cond = FaceWeight::Frozen;
                copy_fields(n_, aux_);
                copy_fields(n_, n2_);
                for (int s = 0; s < opt_.conductance_presmooth_steps; ++s) {
                    poll();
                    normal_step(aux_, n2_, FaceWeight::One, true);
                    std::swap(aux_, n2_);
                }
                const float mu = conductance_scale(n_, aux_);
                conductance_from(aux_, mu);
                rep_.mu.push_back(mu);
            } else {
                rep_.mu.push_back(opt_.mu);
                cond = FaceWeight::Live;
            }
        }
        if (highboost) copy_fields(n_, aux_);
        copy_fields(n_, n2_);
        std::vector<double> gs;
        for (int s = 0; s < opt_.normal_steps; ++s) {
            gs.push_back(normal_step(n_, n2_, cond, true));
            std::swap(n_, n2_);
            tick(0.5 * double(s + 1) / opt_.normal_steps);
        }
        gs.push_back(normal_step(n_, n2_, cond, false));
        rep_.normal_energy_start.push_back(gs.front());
        rep_.normal_energy.push_back(gs.back());
        rep_.normal_energy_steps.push_back(std::move(gs));
        if (highboost) {
            const float a = opt_.alpha;
            for (std::size_t i = 0; i < n_[0].size(); ++i) {
                if (!mask_[i]) continue;
                float v[3];
                for (int c = 0; c < 3; ++c) v[c] = (1.0f + a) * aux_[c][i] - a * n_[c][i];
                const float len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                if (len > 1e-6f)
                    for (int c = 0; c < 3; ++c) n_[c][i] = v[c] / len;
                else
                    for (int c = 0; c < 3; ++c) n_[c][i] = aux_[c][i];
            }
        }
    }

    // ---------------------------------------------------------------- refit
    /// H_N = ∇·N (central differences, Eq. 53) [− T ∇·(G N), Eq. 39] over the active blocks.
    void target_curvature() {
        const bool second = opt_.second_order_term;
        const float inv2mu2 = inv2mu2_;
        const SmoothMode emode = opt_.mode == SmoothMode::Anisotropic ? SmoothMode::Anisotropic : SmoothMode::Isotropic;
        if (second) {
            // G per sample from the central-difference shape matrix of N, into phi2_
            std::vector<std::int32_t> all(nblocks());
            for (std::size_t b = 0; b < all.size(); ++b) all[b] = std::int32_t(b);
            for_blocks(all, 3, [&](std::size_t, std::int32_t b, Scratch& s) {
                const Neighbourhood& n = nbh_[std::size_t(b)];
                float* N[3] = {s.at(0), s.at(1), s.at(2)};
                gather_n(n, n_, N[0], N[1], N[2]);
                const std::size_t base = std::size_t(b) * kBlockVoxels;
                for (int z = 0; z < kBlockDim; ++z)
                    for (int y = 0; y < kBlockDim; ++y)
                        for (int x = 0; x < kBlockDim; ++x) {
                            const int q = lidx(x, y, z);
                            float dn2 = 0.0f, v2 = 0.0f;
                            for (int c = 0; c < 3; ++c) {
                                float vc = 0.0f;
                                for (int j = 0; j < 3; ++j) {
                                    const float d = 0.5f * (N[c][q + kStride[j]] - N[c][q - kStride[j]]);
                                    dn2 += d * d;
                                    vc += d * N[j][q];
                                }
                                v2 += vc * vc;
                            }
                            phi2_[base + std::size_t(bidx(x, y, z))] =
                                penalty(emode, std::max(dn2 - v2, 0.0f), inv2mu2);
                        }
            });
        }
        const float T = float(opt_.normal_steps) * std::min(opt_.normal_dt, kMaxDt);
        for_blocks(active_, second ? 4 : 3, [&](std::size_t, std::int32_t b, Scratch& s) {
            const Neighbourhood& n = nbh_[std::size_t(b)];
            float* N[3] = {s.at(0), s.at(1), s.at(2)};
            gather_n(n, n_, N[0], N[1], N[2]);
            float* Gv = nullptr;
            if (second) {
                Gv = s.at(3);
                gather(n, phi2_.data(), 0.0f, 0.0f, Gv);
            }
            const std::size_t base = std::size_t(b) * kBlockVoxels;
            for (int z = 0; z < kBlockDim; ++z)
                for (int y = 0; y < kBlockDim; ++y)
                    for (int x = 0; x < kBlockDim; ++x) {
                        const int q = lidx(x, y, z);
                        float h = 0.0f;
                        for (int a = 0; a < 3; ++a) h += 0.5f * (N[a][q + kStride[a]] - N[a][q - kStride[a]]);
                        if (second) {
                            float t = 0.0f;
                            for (int a = 0; a < 3; ++a)
                                t += 0.5f * (Gv[q + kStride[a]] * N[a][q + kStride[a]] -
                                             Gv[q - kStride[a]] * N[a][q - kStride[a]]);
                            h -= T * t;
                        }
                        hn_[base + std::size_t(bidx(x, y, z))] = h;
                    }
        });
    }

    /// One explicit step φ ← φ + dt |∇φ|_upwind (H_φ − hn) on the active samples (phi_ → phi2_,
    /// then swapped). Returns D(φ before the step) when with_energy.
    double refit_step(bool with_energy) {
        std::vector<double> energy(active_.size(), 0.0);
        std::atomic<bool> bad{false};
        const float dt = std::min(opt_.refit_dt, kMaxDt);
        for_blocks(active_, 1, [&](std::size_t k, std::int32_t b, Scratch& s) {
            const Neighbourhood& n = nbh_[std::size_t(b)];
            float* P = s.at(0);
            gather_phi(n, phi_, P);
            const std::size_t base = std::size_t(b) * kBlockVoxels;
            double e = 0.0;
            int nonfinite = 0;
            // The span of rows with active samples of each z plane in one call; a row in between
            // without any gets φ, which phi2_ already holds there (see refit_loop).
            const std::uint8_t* M = mask_.data() + base;
            for (int z = 0; z < kBlockDim; ++z) {
                const auto [y0, y1] = row_span(0, [&](int y) { return any_in_row(M + bidx(0, y, z)); });
                if (y1 < y0) continue;
                const std::size_t i0 = base + std::size_t(bidx(0, y0, z));
                nonfinite |= refit_row(P + lidx(0, y0, z), hn_.data() + i0, mask_.data() + i0, dt, y1 - y0 + 1,
                                       phi2_.data() + i0);
                if (with_energy)
                    for (int y = y0; y <= y1; ++y) {
                        const std::size_t i = base + std::size_t(bidx(0, y, z));
                        if (any_in_row(mask_.data() + i))
                            e += refit_energy_row(P + lidx(0, y, z), mask_.data() + i, n_[0].data() + i,
                                                  n_[1].data() + i, n_[2].data() + i);
                    }
            }
            if (nonfinite) bad = true;
            energy[k] = e;
        });
        if (bad) fail("phi in the refit");
        std::swap(phi_, phi2_);
        double sum = 0.0;
        for (const double e : energy) sum += e;
        return sum;
    }

    /// D of the current φ (no update).
    double refit_energy() {
        std::vector<double> energy(active_.size(), 0.0);
        for_blocks(active_, 1, [&](std::size_t k, std::int32_t b, Scratch& s) {
            float* P = s.at(0);
            gather_phi(nbh_[std::size_t(b)], phi_, P);
            const std::size_t base = std::size_t(b) * kBlockVoxels;
            double e = 0.0;
            for (int z = 0; z < kBlockDim; ++z)
                for (int y = 0; y < kBlockDim; ++y) {
                    const std::size_t i0 = base + std::size_t(bidx(0, y, z));
                    if (!any_in_row(mask_.data() + i0)) continue;
                    e += refit_energy_row(P + lidx(0, y, z), mask_.data() + i0, n_[0].data() + i0, n_[1].data() + i0,
                                          n_[2].data() + i0);
                }
            energy[k] = e;
        });
        double sum = 0.0;
        for (const double e : energy) sum += e;
        return sum;
    }

    /// Refit steps until D stops decreasing; φ ends as the iterate with the smallest D seen.
    /// Buffers: phi_ (current), phi2_ (written by the step), aux_[0] (the previous iterate, kept
    /// so that a step that raised D can be undone; the buffer the reinitialisation has already
    /// written, so no fresh pages are touched). Samples outside the active blocks are equal in
    /// all three (refit_step writes only the active blocks).
    void refit_loop() {
        target_curvature();  // may use phi2_ as scratch
        copy_samples(phi_, phi2_);
        Samples& prev_phi = aux_[0];
        copy_samples(phi_, prev_phi);
        std::vector<double> ds;  // D of each iterate evaluated
        int steps = 0;
        double prev = 0.0, d_end = 0.0;
        bool stopped = false;
        for (int s = 0; s < opt_.refit_max_steps; ++s) {
            std::swap(phi2_, prev_phi);  // prev_phi ← φ_{s−1}; phi2_ is overwritten by the step
            const double d = refit_step(true);  // D(φ_s); now phi2_ = φ_s, phi_ = φ_{s+1}
            ds.push_back(d);
            tick(0.5 + 0.5 * double(s + 1) / opt_.refit_max_steps);
            if (s > 0 && !(d < prev * (1.0 - opt_.refit_tolerance))) {
                if (d > prev) {
                    std::swap(phi_, prev_phi);  // φ_s raised D: back to φ_{s−1}
                    d_end = prev;
                    --steps;
                } else {
                    std::swap(phi_, phi2_);  // φ_s still (barely) lowered D: keep it
                    d_end = d;
                }
                stopped = true;
                break;
            }
            ++steps;
            prev = d;
        }
        if (!stopped) {
            d_end = refit_energy();
            ds.push_back(d_end);
        }
        rep_.refit_energy_start.push_back(ds.front());
        rep_.refit_energy.push_back(d_end);
        rep_.refit_energy_steps.push_back(std::move(ds));
        rep_.refit_steps.push_back(steps);
    }

    Grid grid_;
    SmoothOptions opt_;
    SmoothReport& rep_;
    Progress* progress_;
    float inv2mu2_ = 50.0f;
    int iteration_ = 0;
    float reinit_limit_ = 0.0f;  // limit of the last reinitialise(): φ is a distance below it

    std::array<int, 3> block_dims_{};
    std::vector<std::int32_t> table_;
    std::vector<std::array<int, 3>> coords_;
    Samples phi_, phi2_, hn_;
    Samples n_[3], n2_[3], aux_[3];
    Samples pad_phi_;  // per active block: φ with its halo (L³), during the normal loop
    std::vector<std::uint8_t> row_band_;  // per active block: which rows of faces touch the band (row_flag)
    std::vector<float, HugePageAllocator<float>> pad_g_[3];  // per active block: frozen conductance of the faces, pad_phi_'s layout
    std::vector<std::uint8_t, NoInitAllocator<std::uint8_t>> mask_;
    std::vector<Neighbourhood> nbh_;  // per allocated block, rebuilt when the band moves
    mutable tbb::enumerable_thread_specific<std::vector<float>> scratch_;
    std::vector<std::int32_t> active_;
    std::size_t active_voxels_ = 0;
};

void validate(const Volume& v, const SmoothOptions& opt) {
    auto bad = [](const std::string& m) { throw InvalidInput("smooth_volume: " + m); };
    if (opt.iterations < 0) bad("iterations must be >= 0 (0: the mode's default), got " + std::to_string(opt.iterations));
    if (opt.normal_steps < 1) bad("normal_steps must be >= 1, got " + std::to_string(opt.normal_steps));
    if (!(opt.mu > 0.0f) || !std::isfinite(opt.mu)) bad("mu must be > 0, got " + std::to_string(opt.mu));
    if (!(opt.alpha >= 0.0f) || !std::isfinite(opt.alpha)) bad("alpha must be >= 0, got " + std::to_string(opt.alpha));
    if (!(opt.normal_dt > 0.0f) || !std::isfinite(opt.normal_dt))
        bad("normal_dt must be > 0, got " + std::to_string(opt.normal_dt));
    if (!(opt.refit_dt > 0.0f) || !std::isfinite(opt.refit_dt))
        bad("refit_dt must be > 0, got " + std::to_string(opt.refit_dt));
    if (opt.refit_max_steps < 1) bad("refit_max_steps must be >= 1, got " + std::to_string(opt.refit_max_steps));
    if (!(opt.refit_tolerance >= 0.0)) bad("refit_tolerance must be >= 0");
    if (opt.conductance_presmooth_steps < 0) bad("conductance_presmooth_steps must be >= 0");
    if (!(opt.mu_robust >= 0.0f) || !std::isfinite(opt.mu_robust))
        bad("mu_robust must be >= 0, got " + std::to_string(opt.mu_robust));
    if (!(opt.active_band >= 1.5f && opt.active_band <= 5.0f))
        bad("active_band must be in [1.5, 5] voxels, got " + std::to_string(opt.active_band));
    if (opt.threads < 0) bad("threads must be >= 0, got " + std::to_string(opt.threads));
    if (!(v.grid.voxel_size > 0.0) || !std::isfinite(v.grid.voxel_size)) bad("volume voxel_size must be > 0");
    for (int a = 0; a < 3; ++a) {
        if (v.grid.dims[a] < 1) bad("volume dims must be >= 1");
        if (v.block_dims[a] != (v.grid.dims[a] + kBlockDim - 1) / kBlockDim) bad("volume block_dims do not match dims");
    }
    if (v.block_table.size() != std::size_t(v.block_dims[0]) * v.block_dims[1] * v.block_dims[2])
        bad("volume block_table has " + std::to_string(v.block_table.size()) + " entries, expected " +
            std::to_string(std::size_t(v.block_dims[0]) * v.block_dims[1] * v.block_dims[2]));
    if (v.values.size() != v.block_coords.size() * kBlockVoxels)
        bad("volume values has " + std::to_string(v.values.size()) + " samples, expected 512 per block");
    for (std::size_t b = 0; b < v.block_coords.size(); ++b) {
        const auto& c = v.block_coords[b];
        if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= v.block_dims[0] || c[1] >= v.block_dims[1] ||
            c[2] >= v.block_dims[2] || v.block_table[v.table_index(c[0], c[1], c[2])] != std::int32_t(b))
            bad("volume block " + std::to_string(b) + " does not match its block_table entry");
    }
    for (const float x : v.values)
        if (!std::isfinite(x)) throw NumericalError("smooth_volume: the input volume holds a NaN/Inf sample");
}

}  // namespace
}  // namespace detail

int default_iterations(SmoothMode mode) { return mode == SmoothMode::Anisotropic ? 16 : 8; }

SmoothReport smooth_volume(Volume& v, const SmoothOptions& opt, Progress* progress) {
    detail::validate(v, opt);
    SmoothReport rep;
    if (opt.normal_dt > detail::kMaxDt)
        rep.warnings.push_back("normal_dt " + std::to_string(opt.normal_dt) + " clamped to the stability bound 1/6");
    if (opt.refit_dt > detail::kMaxDt)
        rep.warnings.push_back("refit_dt " + std::to_string(opt.refit_dt) + " clamped to the stability bound 1/6");
    detail::begin(progress, "smooth");
    auto work = [&] {
        detail::LevelSetEngine engine(v, opt, rep, progress);
        if (!engine.has_surface()) {
            rep.warnings.push_back("the volume holds no surface (no sign change); returned unchanged");
            return;
        }
        engine.run();
        engine.write_back(v);
    };
    if (opt.threads > 0) {
        tbb::task_arena arena(opt.threads);
        arena.execute(work);
    } else {
        work();
    }
    return rep;
}

}  // namespace normalflow
