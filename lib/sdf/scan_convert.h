#pragma once
/// \file scan_convert.h
/// Scan conversion: any triangle mesh to a sparse narrow-band signed distance Volume.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"
#include "core/volume.h"
#include "sdf/closest_triangle.h"

namespace normalflow {

/// Options for scan_convert.
struct ScanConvertOptions {
    int resolution = 256;        ///< voxels along the longest bounding-box side, >= 1; ignored if voxel_size > 0
    double voxel_size = 0;       ///< h, world units; > 0 overrides resolution, 0 = use resolution
    float half_width = 3.0f;     ///< band half-width in voxels, >= 1 (the normal-map engine needs about 7)
    double shell_thickness = 0;  ///< world units, >= 0; > 0 treats the mesh as a thin shell: phi = d − T/2
    int threads = 0;             ///< worker threads, 0 = all, 1 = serial; the result does not depend on it
};

/// What scan_convert did.
struct ScanConvertReport {
    Grid grid;                         ///< the grid of the returned volume
    std::size_t band_voxels = 0;       ///< samples with |phi| < half_width · h
    std::size_t blocks = 0;            ///< allocated 8³ blocks
    std::size_t candidate_blocks = 0;  ///< blocks examined (near a triangle's bounding box)
    std::size_t uncertain_sign =
        0;  ///< band samples > 1e-3 h off the surface whose winding number was within 0.1 of 1/2
    std::size_t winding_evaluations = 0;   ///< winding number queries made
    std::size_t tile_conflict_blocks = 0;  ///< inside tiles next to outside tiles, allocated (see scan_convert)
    double seconds_distance = 0;           ///< wall time: distances, band and block signs
    double seconds_sign = 0;               ///< wall time: winding-number tree build and tile signs
    std::size_t memory_bytes = 0;          ///< bytes held by the returned volume
    std::vector<std::string> warnings;     ///< oddities handled (uncertain signs, ...)
    /// The one warning of warnings about an open mesh (holes or boundaries: the volume closed across them), so that
    /// a caller whose result keeps the openings can drop it; empty for a closed mesh.
    std::string open_mesh_warning;
};

/// Signed distance to m, negative inside, in world units, stored in a narrow band of
/// half_width voxels on each side of the surface (Volume; its background is half_width · h).
///
/// Method. Grid: the bounding box of the referenced vertices, sampled with h = voxel_size or
/// longest side / resolution, padded by ceil(half_width + 2 + T/(2h)) voxels on each side, so the
/// band never touches the border. Sparse: only 8³ blocks that a triangle's bounding box, dilated by
/// the band, touches (and whose centre is near enough to the triangle's plane) are examined; their
/// samples get exact unsigned distances d from q (with the previous sample's triangle as a hint and
/// the band as a search radius); blocks without a band sample are dropped. The sign is the
/// generalized winding number w (Jacobson et al. 2013; fast hierarchical evaluation of Barill et
/// al. 2018, see winding_number.h): inside where w > 1/2. Within a block the sign cannot change
/// between 6-neighbours p, q with max(d(p), d(q)) > h (the segment lies in an empty ball), so w is
/// evaluated at up to 4 spread samples per such connected set; if they disagree or any is within
/// 0.1 of 1/2, w is evaluated at every sample of the set. Unallocated blocks get their tile sign
/// (inside / outside) by a scan along x over block rows, starting outside at the grid border and
/// taking the sign of the last x-layer of each allocated block (adjacent samples farther than h
/// from the surface share a sign). Near the holes of an open mesh two neighbouring rows can disagree;
/// every inside tile that touches (26-neighbourhood) an outside tile or the grid border is then allocated, filled with
/// −background, so that extraction stays closed (report->tile_conflict_blocks, with a warning). Memory and time grow with the surface area (plus one int32 per
/// 512 grid samples for the block table), not with the bounding volume.
///
/// Accepted input: any triangle soup — holes, non-manifold edges, several components, nested shells,
/// self-intersections, duplicate and zero-area faces. The mesh is taken as given: w depends on the
/// orientation, so an inconsistently oriented soup should be oriented first (io/cgal repair); a mesh
/// oriented inside-out throws like an open sheet. Samples whose w is within 0.1 of 1/2 (near holes
/// and open boundaries) are counted in report->uncertain_sign and produce a warning.
/// Shell mode (shell_thickness T > 0): phi = d − T/2, no winding number; for open sheets.
///
/// \param q closest-triangle queries on m (make_bvh_query(m), or io/cgal make_aabb_query(m)).
/// \throw InvalidInput for an empty mesh, bad indices, non-finite coordinates, bad options, or
///        a mesh that encloses no volume (w > 1/2 nowhere: an open sheet) without shell_thickness;
///        OutOfMemory if the block table would exceed 2^31 entries; Cancelled via progress.
/// Threading: TBB parallel_for over blocks (opt.threads); the result is identical for any count.
Volume scan_convert(const Mesh& m, const ClosestTriangleQuery& q, const ScanConvertOptions& opt = {},
                    ScanConvertReport* report = nullptr, Progress* progress = nullptr);

/// The grid scan_convert samples m on: the bounding box of the referenced vertices with h = voxel_size or longest
/// side / resolution, padded as scan_convert says.
/// \throw InvalidInput for an empty mesh, bad options or a mesh of zero extent; OutOfMemory for a block table over
///        2^31 entries.
Grid scan_grid(const Mesh& m, const ScanConvertOptions& opt = {});

/// A box of 8³ blocks of a grid: blocks lo ≤ (bi, bj, bk) < hi along each axis.
struct BlockWindow {
    std::array<int, 3> lo{0, 0, 0};
    std::array<int, 3> hi{0, 0, 0};
};

/// The grid of a window of g: its origin at the window's first sample, its dims clipped to g's (a volume over it
/// has block (bi, bj, bk) where g has (bi + lo, ...)).
Grid window_grid(const Grid& g, const BlockWindow& w);

class WindingNumber;

/// scan_convert restricted to the blocks of a window of `grid` (scan_grid(m, opt)), for work done brick by brick:
/// the returned volume's grid is the window's (origin at its first sample, dims clipped to the grid's), its block
/// (bi, bj, bk) the grid's (bi + lo, ...). Its values are bit for bit those of scan_convert(m, q, opt) in the same
/// blocks, its tiles the same signs: samples are placed by `grid` itself, and a row of tiles that starts inside the
/// grid starts as the whole grid's row runs there (the sign the last block scan_convert keeps before the window
/// leaves, outside where it keeps none), open mesh or closed. A window holding no surface is all tiles. The
/// conflict blocks near an open mesh's holes (an inside tile beside an outside one, allocated) are scan_convert's
/// too, except on the window's outermost blocks, whose neighbours beyond it are not looked at: only the grid's own
/// border counts as a border.
/// \param wn the winding number of m (built once for all windows); may be null only with shell_thickness > 0.
/// The mesh is not checked (check it once, as scan_convert does). Memory and time grow with the surface inside the
/// window, plus two passes over the triangles and, for each row of blocks that starts unallocated, the blocks
/// before the window down to the first the whole scan keeps.
/// \throw InvalidInput for bad options or a window not within the grid's blocks.
Volume scan_convert_window(const Mesh& m, const ClosestTriangleQuery& q, const WindingNumber* wn, const Grid& grid,
                           const BlockWindow& window, const ScanConvertOptions& opt = {},
                           ScanConvertReport* report = nullptr, Progress* progress = nullptr);

}  // namespace normalflow
