#pragma once
/// \file untangle.h
/// Heavy noise moves a mesh's vertices along its surface as well as across it, and folds its triangles over one
/// another; no filter of the normals undoes that, since each vertex only moves along its faces' normals. The volume
/// knows which way the surface faces: a face turned over against it is folded, and its vertices move along the
/// surface (the plane across the volume's gradient) toward the centre of their neighbours until no face is.
/// (FitOptions::relax_steps relaxes every vertex of a mesh fitted onto the volume; this moves only those around folds
/// and leaves the rest of the user's mesh as the filter left it.)

#include <cstddef>

#include "core/mesh.h"
#include "core/volume.h"

namespace normalflow {

/// untangle moves the folded faces' own vertices first; once this many passes in a row left no fewer folds than
/// the least so far, their neighbours too (a ring more each time, at most kUntangleRings), and then it stops.
inline constexpr int kUntanglePatience = 5;
inline constexpr int kUntangleRings = 2;

/// What untangle did.
struct UntangleReport {
    std::size_t folded_before = 0;  ///< faces turned over against the volume before (faces_against_volume)
    std::size_t folded_after = 0;   ///< and after
    std::size_t moved = 0;          ///< (welded) vertices moved
    int passes = 0;                 ///< passes run
    bool undone = false;            ///< the passes left no fewer folds, and every vertex went back
};

/// Moves the vertices of the faces of m turned over against v along the surface, each pass to the centre of its
/// neighbours in the plane across ∇φ but no farther than max_move (world units) from where it began, until none is
/// turned over or max_passes passes have run; where the folded faces' own vertices stop unfolding them, their
/// neighbours move too (kUntanglePatience, kUntangleRings). The positions kept are those of the pass that left the
/// fewest folds. The noise that folded the faces moved their
/// vertices by about its deviation σ: 3σ undoes it, and leaves a mesh whose folds are not the noise's (a coarse
/// model thinner than the volume's voxels) nearly where it was. If the passes leave no fewer folds, every vertex
/// goes back (the report's undone). The vertices, faces and their order stay; open-boundary vertices and those
/// outside v's band do not move.
/// \throw InvalidInput if m or v is invalid, max_move is not finite and >= 0 or max_passes < 0.
/// Cost: O(F) per pass, TBB-parallel; the result does not depend on the thread count.
UntangleReport untangle(Mesh& m, const Volume& v, double max_move, int max_passes = 50);

}  // namespace normalflow
