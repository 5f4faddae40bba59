#include "normals/stages/surface_samples.h"

#include <algorithm>
#include <cmath>

#include "band/iterate.h"

namespace normalflow::engine {

namespace {
constexpr float kFar = 1.0e9f;  // padding position: no query is within reach of it
}

void SurfaceSamples::build(const Band& band, const Field3& normals, float tau, float reach, float margin) {
    band_ = &band;
    tau_ = tau;
    const std::size_t nb = band.nblocks();
    const Samples& phi = band.phi();
    const std::uint8_t* mask = band.mask();
    // counts per block, then offsets (slot order), then fill: each block independently
    std::vector<std::int64_t> count(nb, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            std::int64_t k = 0;
            const std::size_t base = b * kBlockVoxels;
            for (std::size_t i = base; i < base + kBlockVoxels; ++i) k += (mask[i] && std::abs(phi[i]) <= tau) ? 1 : 0;
            count[b] = (k + 7) / 8 * 8;
        }
    });
    off_.assign(nb + 1, 0);
    for (std::size_t b = 0; b < nb; ++b) off_[b + 1] = off_[b] + count[b];
    const std::size_t total = std::size_t(off_[nb]);
    for (int c = 0; c < 3; ++c) {
        fit_samples(p[c], total);
        fit_samples(n[c], total);
    }
    index.resize(total);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            std::size_t o = std::size_t(off_[b]);
            const std::size_t e = std::size_t(off_[b + 1]);
            const auto& bc = band.block_coord(b);
            const std::size_t base = b * kBlockVoxels;
            for (int z = 0; z < kBlockDim; ++z)
                for (int y = 0; y < kBlockDim; ++y)
                    for (int x = 0; x < kBlockDim; ++x) {
                        const std::size_t i = base + std::size_t(bidx(x, y, z));
                        if (!(mask[i] && std::abs(phi[i]) <= tau)) continue;
                        const float nx = normals[0][i], ny = normals[1][i], nz = normals[2][i];
                        p[0][o] = float(bc[0] * kBlockDim + x) - phi[i] * nx;
                        p[1][o] = float(bc[1] * kBlockDim + y) - phi[i] * ny;
                        p[2][o] = float(bc[2] * kBlockDim + z) - phi[i] * nz;
                        n[0][o] = nx;
                        n[1][o] = ny;
                        n[2][o] = nz;
                        index[o] = i;
                        ++o;
                    }
            for (; o < e; ++o) {
                for (int c = 0; c < 3; ++c) {
                    p[c][o] = kFar;
                    n[c][o] = 0.0f;
                }
                index[o] = kPadding;
            }
        }
    });
    // blocks within reach: box distance between the blocks' sample boxes, widened by tau and margin
    near_.assign(nb, {});
    const float lim = reach + tau + margin;
    const int k = int(std::ceil(lim / float(kBlockDim)));
    const std::vector<std::int32_t>& act = band.active();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, act.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t a = r.begin(); a != r.end(); ++a) {
            const std::int32_t b = act[a];
            const auto& bc = band.block_coord(std::size_t(b));
            std::vector<std::int32_t>& out = near_[std::size_t(b)];
            for (int dz = -k; dz <= k; ++dz)
                for (int dy = -k; dy <= k; ++dy)
                    for (int dx = -k; dx <= k; ++dx) {
                        const std::int32_t s = band.block_at(bc[0] + dx, bc[1] + dy, bc[2] + dz);
                        if (s < 0 || off_[std::size_t(s) + 1] == off_[std::size_t(s)]) continue;
                        // gap between the two 8-sample boxes along each axis
                        const auto gap = [](int d) { return float(std::max(0, std::abs(d) * kBlockDim - (kBlockDim - 1))); };
                        const float gx = gap(dx), gy = gap(dy), gz = gap(dz);
                        if (gx * gx + gy * gy + gz * gz <= lim * lim) out.push_back(s);
                    }
            std::sort(out.begin(), out.end());
        }
    });
}

float SurfaceSamples::box_distance2(std::int32_t b, const float q[3]) const {
    const auto& bc = band_->block_coord(std::size_t(b));
    float d2 = 0.0f;
    for (int a = 0; a < 3; ++a) {
        const float lo = float(bc[a] * kBlockDim) - tau_, hi = float(bc[a] * kBlockDim + kBlockDim - 1) + tau_;
        const float d = q[a] < lo ? lo - q[a] : (q[a] > hi ? q[a] - hi : 0.0f);
        d2 += d * d;
    }
    return d2;
}

}  // namespace normalflow::engine
