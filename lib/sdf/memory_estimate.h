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

/// Bytes the engine holds per sample of an allocated block: φ and its twin, three normal fields of three components
/// and H_N (12 floats, engine::WorkBuffers in lib/band/band.h), and the mask's byte.
inline constexpr double kEngineBytesPerSample = 12 * 4 + 1;
/// Bytes a window that is only reinitialised (a run in bricks closing) holds per sample: the window as a volume, φ,
/// its twin and the spare the reinitialisation writes (floats), and the mask's byte.
inline constexpr double kReinitialiseBytesPerSample = 4 * 4 + 1;
/// Arrays the engine maps in huge pages (the 12 floats and the mask), each rounded up to 2 MiB.
inline constexpr double kEngineRoundingBytes = 13.0 * (2 << 20);
/// What a run holds per input triangle besides the volume, at its peak: the mesh as read and as repaired, the closest
/// triangle search's tree and the winding number's. Measured as the resident size of `smooth --resolution 16` less
/// that of `normalflow --version` (the libraries): 13.1 MB on fandisk_n0.3 (12,946 triangles), 20.4 MB on fertility_n3
/// (27,954), 44.6 MB on julius_n0.2 (71,912) and 50.7 MB on vaselion_n3 (77,452), 582 bytes per triangle beyond
/// 5.6 MB (2026-12-07; the estimate counted 160 before, a quarter of it).
inline constexpr double kMeshBytesPerTriangle = 600;

/// What a run of the pipeline is expected to hold at its peak, in bytes.
struct MemoryEstimate {
    double surface_blocks = 0;  ///< 8³ blocks the surface passes through: Σ area · (|n_x| + |n_y| + |n_z|) / (8h)²
    double engine_blocks = 0;   ///< blocks the engine allocates: those and their 26 neighbours, 3 · surface_blocks
    double grid_samples = 0;    ///< samples of the bounding grid (the block table holds one int per 512)
    double mesh_bytes = 0;      ///< the mesh with its search trees
    double scan_bytes = 0;      ///< scan conversion: band blocks, block table, mesh and search trees
    double engine_bytes = 0;    ///< the engine's band arrays: engine_blocks · 512 · kEngineBytesPerSample, rounded
    double smooth_bytes = 0;    ///< the engine's run: its arrays, the scanned volume it starts from (scan_bytes)
    double total(bool smoothing) const { return smoothing ? std::max(scan_bytes, smooth_bytes) : scan_bytes; }
};

/// Estimate for scan-converting m with voxel size h (world units) and a band of half_width voxels (for a run of the
/// engine, the band it starts from), and for smoothing it afterwards. A plane of unit normal n crosses
/// (|n_x| + |n_y| + |n_z|) / b² blocks of side b per unit of area; the engine allocates the blocks the surface passes
/// through and their 26 neighbours, at most three times as many (a layer on either side along every axis the plane
/// crosses). On the study's noisy inputs at resolutions 256 and 512 the engine allocated 2.0 to 2.8 times the blocks
/// crossed, and the estimate of the whole run came within 0.98 to 1.25 of its measured peak
/// (docs/history/benchmarks-2026.md, "The memory estimate"). Errs on the high side for meshes with overlapping
/// components (their areas add).
/// An open mesh's volume closes its holes (`closes_holes`: a scan that is not a shell), so its surface there is the
/// caps' (hole_caps): the bottom of a scanned object is often missing, and a cap as large as the rest of the surface
/// (real_scans/iron.ply) left the estimate at 0.64 of the peak at 1024 when only the triangles counted.
inline MemoryEstimate estimate_memory(const Mesh& m, double h, float half_width, bool closes_holes = true) {
    MemoryEstimate e;
    double crossing = 0;
    const auto add = [&](const Vec3d& a, const Vec3d& b, const Vec3d& c) {
        const Vec3d n = cross(b - a, c - a);
        crossing += 0.5 * (std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2]));
    };
    for (const Tri& t : m.triangles) add(Vec3d(m.positions[t[0]]), Vec3d(m.positions[t[1]]), Vec3d(m.positions[t[2]]));
    if (closes_holes)
        for (const auto& cap : hole_caps(m)) add(cap[0], cap[1], cap[2]);
    const Box3d box = bounding_box(m);
    double samples = 1;
    for (int k = 0; k < 3; ++k) samples *= (box.max[k] - box.min[k]) / h + 2 * (half_width + 3);
    e.grid_samples = samples;
    const double block_side = 8 * h;
    e.surface_blocks = crossing / (block_side * block_side) + 1;
    e.engine_blocks = 3 * e.surface_blocks;
    const double band_layers = 1 + std::ceil((2 * half_width + 1) / 8.0);  // blocks across the band
    const double table_bytes = samples / 512 * 4;
    e.mesh_bytes = double(m.positions.size()) * 12 + double(m.triangles.size()) * kMeshBytesPerTriangle;
    e.scan_bytes = e.surface_blocks * band_layers * 512 * 4 + table_bytes + e.mesh_bytes;
    e.engine_bytes = e.engine_blocks * 512 * kEngineBytesPerSample + kEngineRoundingBytes + table_bytes;
    e.smooth_bytes = e.engine_bytes + e.scan_bytes;
    return e;
}

}  // namespace normalflow
