#pragma once
/// \file trim_to_footprint.h
/// Open in, open out: the surface extracted from the volume of an open mesh, less what the volume
/// added to close it.

#include <cstddef>

#include "core/mesh.h"
#include "sdf/closest_triangle.h"

namespace normalflow {

/// What trim_to_footprint removed.
struct TrimReport {
    std::size_t faces_removed = 0;       ///< beyond the input's open boundary, or spikes and islands left by the cut
    std::size_t components_removed = 0;  ///< small pieces cut off from the rest
};

/// Removes from m, a surface extracted from the (closed) volume of the open mesh `input`, the part
/// that lies beyond input's open boundary: the cap that closed the volume. A vertex of m is beyond it
/// when its distance to input exceeds max_distance, or when its closest point on input lies on an
/// open-boundary edge of input (an edge of one face, once coincident positions are welded) and is
/// farther than `tolerance`: the surface's own points lie near the input and project into the interior
/// of its faces; the cap lies away from it, or projects onto the rim. Faces with such a vertex go. Each
/// removed patch opens the boundary loops of input that its vertices project onto; where a loop has
/// several patches, only the largest stays removed (the others are holes punched where the surface near
/// the rim strays a little, and come back), so each loop of input opens once; a patch that touches no
/// loop and has fewer than 1% of the faces (where the smoothing moved the surface away from the input)
/// comes back too; then faces left with two boundary edges (spikes on the cut) are removed,
/// repeatedly, and so are kept pieces with fewer than 1% of the kept faces (bits of the cap near the
/// surface; an open input made of many small parts loses those too). Unreferenced vertices are removed
/// and the attributes follow the vertices.
/// \param q  closest-triangle queries on input (make_bvh_query(input))
/// \param tolerance  world units, > 0: how far past the rim a vertex may lie (a voxel is a good choice)
/// \param max_distance  world units, >= tolerance: how far from input a vertex may lie (a few voxels, and
///        more than the noise the smoothing removed)
/// \throw InvalidInput if m or input is invalid or the distances are not as above.
/// Cost: one closest-point query per vertex of m (TBB parallel; independent of the thread count) and
/// O(F log F) for the clean-up.
TrimReport trim_to_footprint(Mesh& m, const Mesh& input, const ClosestTriangleQuery& q, double tolerance,
                             double max_distance);

}  // namespace normalflow
