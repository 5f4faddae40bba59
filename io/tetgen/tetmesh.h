#pragma once
/// \file tetmesh.h
/// Tetrahedral meshing of a closed surface with TetGen 1.5 (Si 2015; AGPL-3.0-or-later: linking it
/// makes the binary AGPL), and writers for Medit .mesh, VTK .vtu (ASCII XML) and TetGen .node/.ele.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace normalflow {

/// Options of tetrahedralize.
struct TetmeshOptions {
    double radius_edge = 1.414;  ///< quality bound: largest radius-edge ratio (TetGen -q), >= 1.0 (1.414 default)
    double max_volume = 0.0;     ///< largest tetrahedron volume, world units cubed (TetGen -a); 0 = no bound
    /// Smallest dihedral angle TetGen's refinement aims for, degrees (TetGen -q<radius_edge>/<deg>), in
    /// [0, 70); 0 = no dihedral bound (radius-edge only, which leaves slivers). TetGen tries but does not
    /// guarantee it: with the surface kept (-Y) it may not split a tetrahedron whose circumcentre
    /// encroaches on the surface, so the slivers at the surface are left to the optimiser
    /// (max_dihedral_deg). 15 with max_dihedral_deg 150 gave at least 12.5° on every evenly remeshed
    /// fandisk surface tried (18 of them) where 10 with TetGen's own 165 gave 7.3–9.5° on all of them
    /// (docs/history/benchmarks-2026.md, "Tetrahedra fit for simulation"); 20 did not finish in two minutes.
    double min_dihedral_deg = 15.0;
    /// Largest dihedral angle TetGen's optimiser aims for, degrees (the third -q field, TetGen's
    /// optmaxdihedral; its own default is 165), in (90, 180). The optimiser only works on tetrahedra
    /// with a dihedral angle above it: the slivers at a kept surface have their largest angle at
    /// 159–167°, so TetGen's 165 leaves most of them alone, and 150 brings them into its flips.
    double max_dihedral_deg = 150.0;
    /// TetGen's mesh optimisation level (-O<level>; flips and vertex smoothing that raise the smallest
    /// dihedral angle), 0 (none) .. 9 (TetGen reads one digit); TetGen's default is 2.
    int optimize_level = 2;
    /// Whether the input triangles stay the boundary faces (TetGen -Y): the tetrahedra then meet the
    /// surface in exactly its triangles and Steiner points go only inside. Keep: the surface users
    /// pass has been extracted, cleaned and decimated on purpose, and without Y TetGen 1.5 either
    /// aborts on such surfaces (it merges nearly coplanar neighbours into non-planar facets) or splits
    /// them far beyond need (fandisk, 20k faces: 1.52 M tetrahedra in 65 s, 54 k in 6 s with Y).
    /// Split: TetGen may split boundary faces to meet the quality and volume bounds there too; a run
    /// that fails is retried with Y (TetmeshReport::switches says which ran). Auto (default): Keep,
    /// or Split when max_volume > 0, because with Y TetGen leaves tetrahedra at the surface as large
    /// as the surface triangles make them (a cube of 12 triangles stays 6 tetrahedra).
    enum class Surface { Auto, Keep, Split };
    Surface surface = Surface::Auto;
};

/// A tetrahedral mesh: points and tetrahedra (4 point indices, positive orientation as TetGen writes).
struct TetMesh {
    std::vector<Vec3d> points;
    std::vector<std::array<std::uint32_t, 4>> tets;
};

/// What tetrahedralize produced.
struct TetmeshReport {
    std::size_t tetrahedra = 0;
    std::size_t points = 0;
    double min_dihedral_deg = 0.0;  ///< smallest dihedral angle over all tetrahedra, degrees
    double volume = 0.0;            ///< sum of tetrahedron volumes, world units cubed
    double surface_volume = 0.0;    ///< volume enclosed by the input surface (divergence theorem)
    /// The smallest angle, degrees, between two adjacent surface faces measured through the volume (90 on a
    /// cube's edges): a tetrahedron at that edge can have no larger dihedral angle, whatever TetGen does.
    double surface_min_angle_deg = 0.0;
    std::string switches;  ///< the TetGen switches of the run that succeeded ("pzYq..." after a retry)
    double seconds = 0.0;
};

/// Tetrahedralizes the volume enclosed by the closed surface m (TetGen switches
/// "pzq<radius_edge>/<min_dihedral_deg>/<max_dihedral_deg>O<optimize_level>Q", plus "a<max_volume>" when set). When that
/// run fails (TetGen 1.5.0 aborts on nearly coplanar adjacent faces, which extracted surfaces have by
/// the thousand), it runs again with "Y" added ("pzYq..."): the input triangles are kept as the
/// boundary faces, and max_volume then bounds only tetrahedra that can be split without touching them.
/// The surface is validated BEFORE TetGen sees it (TetGen 1.5 crashes on its own error path): it must
/// be closed, manifold, free of degenerate faces and, in builds with CGAL, free of self-intersections.
/// \throw InvalidInput for an empty, open, non-manifold, degenerate or self-intersecting surface, or
///        options out of range; NumericalError if TetGen produces no tetrahedra.
/// Cost: TetGen's Delaunay refinement, about 0.3 s for 36k tetrahedra. Single-threaded.
TetMesh tetrahedralize(const Mesh& m, const TetmeshOptions& opt = {}, TetmeshReport* report = nullptr);

/// Writes t by path's extension: .mesh (Medit, version 2, Vertices + Tetrahedra), .vtu (VTK
/// UnstructuredGrid, ASCII XML) or .node (writes path and the .ele beside it). Atomic writes.
/// \throw InvalidInput for another extension or an empty mesh; IoError if a file cannot be written.
void write_tetmesh(const std::string& path, const TetMesh& t);

}  // namespace normalflow
