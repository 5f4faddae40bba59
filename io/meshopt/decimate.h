#pragma once
/// \file decimate.h
/// Decimation to a face count with meshoptimizer's simplifier (Kapoulkine; MIT): quadric-error edge
/// collapses onto existing vertices that never flip a triangle and keep the topology, about a
/// million triangles a second. Free of GPL code. It does not promise a manifold result or one
/// free of self-intersections: callers that need those check them (the pipeline does, and falls
/// back to io/cgal's edge collapse).

#include <cstddef>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace normalflow::meshopt {

/// Options of decimate_mesh.
struct DecimateOptions {
    /// Faces to keep at most, >= 4. The simplifier stops short of it when no collapse is left that
    /// keeps the topology (a closed component keeps at least a tetrahedron; locked borders stay).
    std::size_t target_faces = 0;
    /// Keep the vertices of open borders where they are (an open scan keeps its outline).
    bool lock_border = true;
};

/// What decimate_mesh did.
struct DecimateReport {
    std::size_t faces_before = 0;
    std::size_t faces_after = 0;
    std::size_t vertices_before = 0;
    std::size_t vertices_after = 0;
    /// The simplifier's own estimate of the largest deviation, world units (a quadric bound, not a
    /// measured distance).
    double error = 0.0;
    bool reached_target = false;  ///< faces_after <= target_faces
    double seconds = 0.0;
};

/// Decimates m in place to at most opt.target_faces faces (see DecimateReport::reached_target).
/// The kept vertices keep their positions and their attributes (normals, colours, texture
/// coordinates), in their original order; unreferenced vertices are dropped. Deterministic and
/// single-threaded. A mesh with no more than target_faces faces is left as it is (its unreferenced
/// vertices dropped).
/// \throw InvalidInput if m breaks the Mesh invariant (check_mesh) or target_faces < 4.
/// Cost: O(F log F); fandisk extracted at resolution 256 (1.1 M faces) to 20,000 in about a second.
DecimateReport decimate_mesh(Mesh& m, const DecimateOptions& opt);

}  // namespace normalflow::meshopt
