#pragma once
/// \file comparison_pictures.h
/// The pictures of `normalflow compare --report DIR`: every mesh from the same three viewpoints, shaded
/// and coloured by distance to the reference, plus a colour legend.

#include <span>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "io/render/render.h"
#include "sdf/closest_triangle.h"

namespace normalflow {

/// Unsigned distance from every vertex of m to the surface behind `reference` (its closest point on any
/// triangle), world units; #V values. Unreferenced vertices get their distance too.
/// Cost: one BVH query per vertex, TBB parallel, deterministic (each vertex writes its own slot).
std::vector<float> vertex_distances(const Mesh& m, const ClosestTriangleQuery& reference);

/// Options of write_comparison_pictures.
struct ComparisonPicturesOptions {
    RenderOptions render;  ///< image size, shading, colours (vertex_scalars and the range are set per picture)
    Projection projection = Projection::Orthographic;  ///< of the three cameras
    std::string subfolder = "pictures";  ///< under dir, where the PNG files go; "" puts them in dir itself
    /// Colour range of the distance pictures: [0, distance_max] world units. <= 0 (default): the largest
    /// vertex distance over all candidates, so the worst vertex gets the map's last colour.
    double distance_max = 0.0;
};

/// One mesh's pictures: paths relative to dir, one per view, in ComparisonPictures::views order.
struct MeshPictures {
    std::vector<std::string> shaded;    ///< grey Lambert shading
    std::vector<std::string> distance;  ///< coloured by vertex distance to the reference (viridis)
    double max_distance = 0.0;          ///< largest vertex distance of this mesh, world units (0 for the reference)
};

/// What write_comparison_pictures wrote.
struct ComparisonPictures {
    std::vector<std::string> views;    ///< "front", "side", "oblique"
    std::vector<MeshPictures> meshes;  ///< the reference first, then the candidates in order
    std::string legend;                ///< the legend bar PNG, relative to dir
    double distance_max = 0.0;         ///< top of the colour range, world units
    double seconds = 0.0;              ///< wall time
};

/// Renders the reference and every candidate from the same three viewpoints with cameras fitted to the
/// reference's bounding box (camera_from_box; views along −z "front", −x "side" and (−1, −1, −1)
/// "oblique", y up): a shaded picture and a picture coloured by vertex_distances to the reference
/// (ColorMap::Viridis over [0, distance_max]), plus legend.png. Files: <subfolder>/mesh<i>_<view>.png and
/// mesh<i>_<view>_distance.png with i = 0 for the reference, and <subfolder>/legend.png; each written
/// atomically. The folder is created if needed.
/// \throw InvalidInput if a mesh is invalid (check_mesh) or the reference has no triangles; IoError if
///        a file cannot be written.
/// Cost: one BVH over the reference, one query per candidate vertex, 6 renders and PNG encodes per mesh,
/// TBB parallel over pictures (each writes its own file, so the bytes do not depend on the thread count).
/// About 0.5 s for a reference and two candidates of 100k faces each on 2 cores.
ComparisonPictures write_comparison_pictures(const std::string& dir, const Mesh& reference,
                                             std::span<const Mesh> candidates,
                                             const ComparisonPicturesOptions& opt = {});

}  // namespace normalflow
