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
    /// Colour range of the distance pictures: [0, distance_max] world units. <= 0 (default): the
    /// distance_percentile-th percentile of the vertex distances of all candidates together, so that one far
    /// vertex does not turn every candidate the map's first colour; farther vertices are clipped and drawn in
    /// over_color.
    double distance_max = 0.0;
    double distance_percentile = 99.0;  ///< in (0, 100]; 100: the largest vertex distance
    Rgb8 over_color{255, 0, 255};       ///< distances above the range (magenta: not in viridis)
    /// Names of the pictures' files, the reference first then one per candidate (typically the input files'
    /// names): each is reduced to its stem, characters other than letters, digits, '.', '-' and '_' become '_', and
    /// a repeated stem gets "_2", "_3", ...; the reference's is prefixed "reference_". Empty: mesh0, mesh1, ...
    std::vector<std::string> names;
};

/// One mesh's pictures: paths relative to dir, one per view, in ComparisonPictures::views order.
struct MeshPictures {
    std::vector<std::string> shaded;    ///< grey Lambert shading
    std::vector<std::string> distance;  ///< coloured by vertex distance to the reference (viridis)
    double max_distance = 0.0;          ///< largest vertex distance of this mesh, world units (0 for the reference)
    double clipped_fraction = 0.0;      ///< fraction of its vertices farther than the colour range (over_color)
};

/// What write_comparison_pictures wrote.
struct ComparisonPictures {
    std::vector<std::string> views;    ///< "front", "side", "oblique"
    std::vector<MeshPictures> meshes;  ///< the reference first, then the candidates in order
    std::string legend;                ///< the legend bar PNG, relative to dir
    double distance_max = 0.0;         ///< top of the colour range, world units
    double percentile = 0.0;           ///< the percentile distance_max is (0 when the options gave distance_max)
    double seconds = 0.0;              ///< wall time
};

/// Renders the reference and every candidate from the same three viewpoints with cameras fitted to the
/// reference's bounding box (camera_from_box; views along −z "front", −x "side" and (−1, −1, −1)
/// "oblique", y up): a shaded picture and a picture coloured by vertex_distances to the reference
/// (ColorMap::Viridis over [0, distance_max], over_color above it), plus legend.png with the over-range swatch.
/// Files: <subfolder>/<name>_<view>.png and <name>_<view>_distance.png for each mesh's name (see
/// ComparisonPicturesOptions::names), and <subfolder>/legend.png; each written atomically. The folder is created if
/// needed.
/// \throw InvalidInput if a mesh is invalid (check_mesh), the reference has no triangles, names has a size other
///        than 1 + candidates or the percentile is out of range; IoError if a file cannot be written.
/// Cost: one BVH over the reference, one query per candidate vertex, 6 renders and PNG encodes per mesh,
/// TBB parallel over pictures (each writes its own file, so the bytes do not depend on the thread count).
/// About 0.5 s for a reference and two candidates of 100k faces each on 2 cores.
ComparisonPictures write_comparison_pictures(const std::string& dir, const Mesh& reference,
                                             std::span<const Mesh> candidates,
                                             const ComparisonPicturesOptions& opt = {});

}  // namespace normalflow
