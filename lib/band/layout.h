#pragma once
/// \file layout.h
/// The engine's block layout (lib/band): a block of 8³ samples is processed in a padded local
/// buffer of 10³ (the block and a halo of one sample), its samples are stored 512 apart in the
/// band's per-sample arrays. Constants, index functions, the per-sample array type and the
/// per-thread scratch the row kernels (lib/normals/kernels) and the stages share.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/band_memory.h"
#include "core/volume.h"

namespace normalflow::engine {

constexpr float kHalfWidth = 8.0f;     // engine band half width, voxels
constexpr float kMaxDt = 1.0f / 6.0f;  // explicit stability bound of the 3-D second-order operators
// Reinitialisation stops when no sample moved by more than this in a Jacobi pass (voxels). The
// passes reach the far end of the band within ~15 passes; after that the values creep by ~2e-5 per
// pass along chains of nearly equal distances (fandisk at 256: all 24 passes ran on 90% of the
// blocks before this tolerance). What is left is below 1e-3 voxel.
constexpr float kReinitTolerance = 1e-3f;
constexpr int L = 10;  // local buffer: 8 + 2 halo
constexpr int L2 = L * L;
constexpr int L3 = L * L * L;
constexpr int kStride[3] = {1, L, L2};

/// Index of block sample (x, y, z), x, y, z in [−1, 8], in the padded local buffer.
constexpr int lidx(int x, int y, int z) { return (z + 1) * L2 + (y + 1) * L + (x + 1); }
/// Rows of faces of one block, per axis a: (y, z) in [−1, 7]² (the faces x+½e_a, x = −1…7 or 0…7).
constexpr int kRowFlags = 3 * 9 * 9;
constexpr int row_flag(int a, int y, int z) { return (a * 9 + (z + 1)) * 9 + (y + 1); }
/// Index of sample (x, y, z) of a block in the band's per-sample arrays, relative to the block's first.
constexpr int bidx(int x, int y, int z) { return (z * kBlockDim + y) * kBlockDim + x; }

/// The engine's per-sample arrays (φ, the normals and their ping-pong buffers, H_N, the mask) are
/// written by every stage before it reads them after the band moved (see Band::update_band): their
/// allocator does not zero them on resize (zero-filling only cost a serial pass and its page faults
/// over the whole band, 0.2 s of the set-up at 256), and maps them in huge pages (core/band_memory.h).
using Samples = std::vector<float, detail::NoInitAllocator<float>>;
/// Three per-sample arrays: the components of a normal field.
using Field3 = Samples[3];

/// Where the halo of one block comes from: its 27 neighbour slots and, per axis and local
/// coordinate -1..8, which neighbour and which in-block coordinate (clamped at the grid border).
struct Neighbourhood {
    std::int32_t slot[27];
    std::uint8_t nb[3][L];
    std::uint8_t li[3][L];
    int ext[3];         // in-grid extent of the block itself
    bool contiguous_x;  // local x 0..7 read the block's own row unclamped (a memcpy)
};

/// Per-thread scratch of the kernels (a view into a thread-local buffer).
struct Scratch {
    float* buf;
    float* at(int k) { return buf + std::size_t(k) * L3; }
};

}  // namespace normalflow::engine
