#pragma once
/// \file surface_attributes.h
/// Per-vertex attributes of a processed surface (see Mesh): vertex normals from the volume or from the
/// faces, and colours carried over from the input to a re-meshed surface.

#include <vector>

#include "core/mesh.h"
#include "core/volume.h"
#include "sdf/closest_triangle.h"

namespace normalflow {

/// Sets m.normals to the unit gradient of φ at each vertex (trilinear, as fit_mesh_to_volume samples
/// it): the normal of the processed surface itself, outward (φ < 0 inside), continuous across
/// triangles, so a viewer shades the surface smooth. Zero where the gradient vanishes or the vertex
/// lies outside the band.
/// \throw InvalidInput if m or v is invalid.
/// Cost: 64 samples per vertex, TBB parallel over vertices; the result does not depend on the thread
/// count.
void set_volume_normals(Mesh& m, const Volume& v);

/// Sets m.normals to the area-weighted mean of the normals of the faces around each vertex, with
/// coincident positions (a texture seam) sharing one normal. For a mesh whose positions moved (a
/// mesh-side smoothing). Zero for a vertex in no face of non-zero area.
/// \throw InvalidInput if m is invalid.
/// Cost: O(V log V + F), single-threaded.
void set_face_normals(Mesh& m);

/// Which faces of m point against the volume: 1 where the face's normal (its area vector) and ∇φ at its centroid
/// make more than 90°, the face turned over against the surface the volume holds; 0 elsewhere, and for faces
/// without area or whose centroid is outside the band. How a kept mesh's fit is checked for faces it flipped
/// (count them on the input and on the result, against the same volume).
/// \throw InvalidInput if m or v is invalid.
/// Cost: one trilinear gradient per face, TBB parallel; independent of the thread count.
std::vector<char> faces_against_volume(const Mesh& m, const Volume& v);

/// Sets m.colors to the colours of `source` at the points of `source` closest to m's vertices (the
/// barycentric blend of the closest triangle's vertex colours, rounded): how a re-meshed surface gets
/// the input's colours. q answers closest-triangle queries on source (make_bvh_query(source)).
/// Does nothing if source has no colours.
/// \throw InvalidInput if m or source is invalid.
/// Cost: one closest-point query per vertex, TBB parallel; independent of the thread count.
void transfer_colors(Mesh& m, const Mesh& source, const ClosestTriangleQuery& q);

}  // namespace normalflow
