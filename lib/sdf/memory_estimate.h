#pragma once
/// \file memory_estimate.h
/// How much memory a run will need, estimated from the surface area and the voxel size before
/// anything big is allocated, so that a run that cannot fit is refused with a clear message
/// instead of being killed by the system half way.

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "core/mesh.h"
#include "core/volume.h"

namespace normalflow {

/// What a run of the pipeline is expected to hold at its peak, in bytes.
struct MemoryEstimate {
    double surface_blocks = 0;  ///< 8³ blocks the surface passes through (area / (8h)², times 1.5 for folds)
    double grid_samples = 0;    ///< samples of the bounding grid (the block table holds one int per 512)
    double scan_bytes = 0;      ///< scan conversion: band blocks, block table, mesh and search trees
    double smooth_bytes = 0;    ///< the engine: 8-voxel band blocks and their 26 neighbours, ~17 floats each
    double total(bool smoothing) const { return smoothing ? std::max(scan_bytes, smooth_bytes) : scan_bytes; }
};

/// Estimate for scan-converting m with voxel size h (world units) and a band of half_width voxels,
/// and for smoothing it afterwards. Calibrated on examples/noisy_part.ply (within a factor 1.5 of
/// the measured peak); errs on the high side for meshes with overlapping components (their areas add).
inline MemoryEstimate estimate_memory(const Mesh& m, double h, float half_width) {
    MemoryEstimate e;
    double area = 0;
    for (const Tri& t : m.triangles) {
        const Vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        area += 0.5 * norm(cross(b - a, c - a));
    }
    const Box3d box = bounding_box(m);
    double samples = 1;
    for (int k = 0; k < 3; ++k) samples *= (box.max[k] - box.min[k]) / h + 2 * (half_width + 3);
    e.grid_samples = samples;
    const double block_side = 8 * h;
    e.surface_blocks = 1.5 * area / (block_side * block_side) + 1;
    const double band_layers = 1 + std::ceil((2 * half_width + 1) / 8.0);  // blocks across the band
    const double mesh_bytes = double(m.positions.size()) * 12 + double(m.triangles.size()) * 160;
    e.scan_bytes = e.surface_blocks * band_layers * 512 * 4 + samples / 512 * 4 + mesh_bytes;
    e.smooth_bytes = e.surface_blocks * 4 * 512 * 17 * 4 + samples / 512 * 4;
    return e;
}

}  // namespace normalflow
