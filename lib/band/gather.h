#pragma once
/// \file gather.h
/// Gathers of one block with its halo from the band's per-sample arrays into the padded local
/// layout (layout.h): the first step of every stencil over the band.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "band/layout.h"

namespace normalflow::engine {

/// Copies K fields f[k] (with halo 1) into out[k]; unallocated blocks give t_in / t_out.
/// Row by row: the 8 interior samples of a row come from one block (one copy or fill); where
/// each row's samples come from is worked out once for all K fields.
template <int K>
inline void gather_k(const Neighbourhood& n, const float* const (&f)[K], float t_in, float t_out,
                     float* const (&out)[K]) {
    auto src = [&](std::int32_t s, int idx) -> std::ptrdiff_t {  // offset, or -1 / -2 for a tile
        return s >= 0 ? std::ptrdiff_t(s) * kBlockVoxels + idx : std::ptrdiff_t(s);
    };
    auto value = [&](const float* fk, std::ptrdiff_t o) { return o >= 0 ? fk[o] : (o == kBlockInside ? t_in : t_out); };
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

/// One field f with its halo into out; unallocated blocks give t_in / t_out.
inline void gather(const Neighbourhood& n, const float* f, float t_in, float t_out, float* out) {
    const float* fs[1] = {f};
    float* os[1] = {out};
    gather_k<1>(n, fs, t_in, t_out, os);
}

/// φ with its halo (unallocated blocks: ∓kHalfWidth by their sign).
inline void gather_phi(const Neighbourhood& n, const Samples& f, float* out) {
    gather(n, f.data(), -kHalfWidth, kHalfWidth, out);
}

/// The three components of a normal field with their halo (unallocated blocks: 0).
inline void gather_n(const Neighbourhood& n, const Field3& f, float* out0, float* out1, float* out2) {
    const float* fs[3] = {f[0].data(), f[1].data(), f[2].data()};
    float* os[3] = {out0, out1, out2};
    gather_k<3>(n, fs, 0.0f, 0.0f, os);
}

}  // namespace normalflow::engine
