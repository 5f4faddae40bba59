#include "normals/stages/surface_samples.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "band/iterate.h"

namespace normalflow::engine {

namespace {
constexpr float kFar = 1.0e9f;  // padding position: no query is within reach of it
}

void SurfaceSamples::build(const Band& band, const Field3& normals, float tau, float reach, float margin, int stride,
                           std::array<int, 3> origin) {
    stride_ = std::max(1, stride);
    origin_ = origin;
    tau_ = tau * float(stride_);
    tau = tau_;
    const std::size_t nb = band.nblocks();
    const Samples& phi = band.phi();
    const std::uint8_t* mask = band.mask();
    constexpr int kHalf = kBlockDim / 2;
    // the samples of octant k of a block, in z, y, x order
    const auto octant = [&](int k, auto&& f) {
        const int x0 = (k & 1) * kHalf, y0 = ((k >> 1) & 1) * kHalf, z0 = (k >> 2) * kHalf;
        for (int z = z0; z < z0 + kHalf; ++z)
            for (int y = y0; y < y0 + kHalf; ++y)
                for (int x = x0; x < x0 + kHalf; ++x) f(x, y, z);
    };
    // counts per run, then offsets (slot order), then fill: each block independently
    std::vector<std::int64_t> count(nb * kRuns, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            const std::size_t base = b * kBlockVoxels;
            for (int k = 0; k < kRuns; ++k) {
                std::int64_t n = 0;
                octant(k, [&](int x, int y, int z) {
                    const std::size_t i = base + std::size_t(bidx(x, y, z));
                    n += mask[i] && taken(band, b, x, y, z, phi[i]) ? 1 : 0;
                });
                count[b * kRuns + std::size_t(k)] = (n + 7) / 8 * 8;
            }
        }
    });
    off_.assign(nb * kRuns + 1, 0);
    for (std::size_t r = 0; r < nb * kRuns; ++r) off_[r + 1] = off_[r] + count[r];
    const std::size_t total = std::size_t(off_[nb * kRuns]);
    for (int c = 0; c < 3; ++c) {
        fit_samples(p[c], total);
        fit_samples(n[c], total);
    }
    index.resize(total);
    constexpr float kInf = std::numeric_limits<float>::infinity();
    box_lo_.assign(nb * (kRuns + 1), {kInf, kInf, kInf});
    box_hi_.assign(nb * (kRuns + 1), {-kInf, -kInf, -kInf});
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            const auto& bc = band.block_coord(b);
            const std::size_t base = b * kBlockVoxels;
            std::array<float, 3>& blo = box_lo_[b * (kRuns + 1) + kRuns];
            std::array<float, 3>& bhi = box_hi_[b * (kRuns + 1) + kRuns];
            for (int k = 0; k < kRuns; ++k) {
                std::size_t o = std::size_t(off_[b * kRuns + std::size_t(k)]);
                const std::size_t e = std::size_t(off_[b * kRuns + std::size_t(k) + 1]);
                std::array<float, 3>& lo = box_lo_[b * (kRuns + 1) + std::size_t(k)];
                std::array<float, 3>& hi = box_hi_[b * (kRuns + 1) + std::size_t(k)];
                octant(k, [&](int x, int y, int z) {
                    const std::size_t i = base + std::size_t(bidx(x, y, z));
                    if (!(mask[i] && taken(band, b, x, y, z, phi[i]))) return;
                    const float nx = normals[0][i], ny = normals[1][i], nz = normals[2][i];
                    p[0][o] = float(origin[0] + bc[0] * kBlockDim + x) - phi[i] * nx;
                    p[1][o] = float(origin[1] + bc[1] * kBlockDim + y) - phi[i] * ny;
                    p[2][o] = float(origin[2] + bc[2] * kBlockDim + z) - phi[i] * nz;
                    n[0][o] = nx;
                    n[1][o] = ny;
                    n[2][o] = nz;
                    index[o] = i;
                    for (std::size_t a = 0; a < 3; ++a) {
                        lo[a] = std::min(lo[a], p[a][o]);
                        hi[a] = std::max(hi[a], p[a][o]);
                    }
                    ++o;
                });
                for (; o < e; ++o) {
                    for (int c = 0; c < 3; ++c) {
                        p[c][o] = kFar;
                        n[c][o] = 0.0f;
                    }
                    index[o] = kPadding;
                }
                for (std::size_t a = 0; a < 3; ++a) {
                    blo[a] = std::min(blo[a], lo[a]);
                    bhi[a] = std::max(bhi[a], hi[a]);
                }
            }
        }
    });
    // blocks within reach: box distance between the blocks' sample boxes, widened by tau and margin
    near_.assign(nb, {});
    const float lim = reach + tau + margin;
    const int k = int(std::ceil(lim / float(kBlockDim)));
    const std::vector<std::int32_t>& act = band.active();
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, act.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t a = r.begin(); a != r.end(); ++a) {
                const std::int32_t b = act[a];
                const auto& bc = band.block_coord(std::size_t(b));
                std::vector<std::int32_t>& out = near_[std::size_t(b)];
                for (int dz = -k; dz <= k; ++dz)
                    for (int dy = -k; dy <= k; ++dy)
                        for (int dx = -k; dx <= k; ++dx) {
                            const std::int32_t s = band.block_at(bc[0] + dx, bc[1] + dy, bc[2] + dz);
                            if (s < 0 || off_[(std::size_t(s) + 1) * kRuns] == off_[std::size_t(s) * kRuns]) continue;
                            // gap between the two 8-sample boxes along each axis
                            const auto gap = [](int d) {
                                return float(std::max(0, std::abs(d) * kBlockDim - (kBlockDim - 1)));
                            };
                            const float gx = gap(dx), gy = gap(dy), gz = gap(dz);
                            if (gx * gx + gy * gy + gz * gz <= lim * lim) out.push_back(s);
                        }
            }
        });
}

}  // namespace normalflow::engine
