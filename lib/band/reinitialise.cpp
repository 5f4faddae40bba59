#include "band/band.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "band/gather.h"
#include "band/iterate.h"
#include "normals/kernels/eikonal_block.h"

namespace normalflow::engine {

void Band::reinitialise(float limit, const RunControl& ctl) {
    reinit_limit_ = limit;
    const std::size_t nb = nblocks();
    const std::vector<std::int32_t> all = all_blocks();
    Samples& u = work_.phi_next;  // unsigned distance
    Samples& u2 = work_.spare();  // ping-pong buffer
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
    if (bad) ctl.fail("distance during reinitialisation");
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
        ctl.poll();
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
        std::swap(u, u2);  // the buffers, not the references: u stays work_.phi_next
    }
    // after the swaps the newest distances are in u (work_.phi_next)
    for_samples(phi_.size(), [&](std::size_t i) {
        const float d = std::min(u[i], kHalfWidth);
        phi_[i] = phi_[i] < 0.0f ? -d : d;
    });
}

}  // namespace normalflow::engine
