#pragma once
/// \file mesh.h
/// The one mesh type of normalflow: an indexed triangle list (a polygon soup, possibly with
/// duplicate points, several components, holes, non-manifold edges and mixed orientation).
/// Half-edge structures (CGAL Surface_mesh, OpenMesh) live only inside io/ adapters.

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "core/vec.h"

namespace normalflow {

/// Three vertex indices, counter-clockwise seen from outside for a well-oriented closed mesh.
using Tri = std::array<std::uint32_t, 3>;

/// A vertex colour: red, green, blue, alpha, 8 bits each, as PLY and OBJ files store them (sRGB-encoded;
/// the glTF reader and writer convert to and from glTF's linear COLOR_0).
using Rgba8 = std::array<std::uint8_t, 4>;

/// A texture coordinate (u, v) with v pointing up, as OBJ and PLY store it (glTF's v points down and
/// is flipped by its reader and writer).
using TexCoord = std::array<float, 2>;

/// Indexed triangles in world units. positions: #V points; triangles: #F index triples into positions.
///
/// The per-vertex attributes are optional: each is empty or holds one entry per position, in the same
/// order. A stage that keeps the vertices (a fit, a smoothing that moves points) keeps colours and
/// texture coordinates and drops or recomputes normals; a stage that builds new vertices drops them
/// or transfers them, and says which in its documentation. check_mesh enforces the sizes.
struct Mesh {
    std::vector<Vec3f> positions;
    std::vector<Tri> triangles;
    std::vector<Vec3f> normals{};       ///< unit vertex normals (zero where undefined), or empty
    std::vector<Rgba8> colors{};        ///< vertex colours, or empty
    std::vector<TexCoord> texcoords{};  ///< vertex texture coordinates, or empty

    bool empty() const { return triangles.empty(); }
    bool has_normals() const { return !normals.empty(); }
    bool has_colors() const { return !colors.empty(); }
    bool has_texcoords() const { return !texcoords.empty(); }
    bool has_attributes() const { return has_normals() || has_colors() || has_texcoords(); }
    /// Removes normals, colours and texture coordinates (for stages that build new vertices).
    void clear_attributes() {
        normals.clear();
        colors.clear();
        texcoords.clear();
    }
};

/// Axis-aligned bounding box of the referenced and unreferenced points alike; min > max when empty.
struct Box3d {
    Vec3d min{1e300, 1e300, 1e300};
    Vec3d max{-1e300, -1e300, -1e300};
    bool empty() const { return min.x > max.x; }
    Vec3d size() const { return empty() ? Vec3d{} : max - min; }
    Vec3d center() const { return (min + max) * 0.5; }
    double diagonal() const { return empty() ? 0.0 : norm(max - min); }
    double longest_side() const {
        const Vec3d s = size();
        return s.x > s.y ? (s.x > s.z ? s.x : s.z) : (s.y > s.z ? s.y : s.z);
    }
    void extend(const Vec3d& p) {
        min = cwise_min(min, p);
        max = cwise_max(max, p);
    }
};

/// Checks the Mesh invariant that every stage relies on: every triangle index is below
/// positions.size(), every position (used by a triangle or not) is finite, and each attribute array is
/// empty or as long as positions, with finite normals and texture coordinates. An empty mesh passes
/// (stages that need triangles say so themselves). Indices are checked first.
/// \param who  message prefix naming the caller, e.g. "scan_convert"
/// \throw InvalidInput "who: triangle 3 has vertex index 9, expected < 8" or
///        "who: vertex 7 has a non-finite coordinate" or "who: 5 normals for 8 vertices".
/// Cost: one pass over the triangles and one over the positions; single-threaded.
void check_mesh(const Mesh& m, std::string_view who);

/// The connected component of each face (faces joined through shared vertex indices), numbered 0, 1, ... in the
/// order of their first face; with `only`, just the faces f with (*only)[f] != 0 are joined and numbered, the
/// others get kNoComponent. `count`, when given, receives the number of components.
/// Cost: O(F α(V)) (union-find over the vertices).
inline constexpr std::uint32_t kNoComponent = 0xffffffffu;
std::vector<std::uint32_t> face_components(const Mesh& m, const std::vector<char>* only = nullptr,
                                           std::size_t* count = nullptr);

/// What remove_extra_components removed.
struct ComponentsRemoved {
    std::size_t allowed = 0;           ///< the parts allowed (the input's)
    std::size_t components = 0;        ///< connected components before
    std::size_t removed = 0;           ///< of these, removed
    std::size_t faces = 0;             ///< faces removed
    double largest_area_fraction = 0;  ///< area of the largest removed, as a fraction of the total (0: none)
};

/// Removes from m the connected components (faces joined through shared vertex indices) beyond the `allowed`
/// largest, smallest area first, each only while its area is below max_area_fraction of m's: what a processing step
/// added to a surface that had `allowed` parts (a bubble where the sign of a volume was uncertain, a speck a
/// smoothing split off), not a part of the shape. Unreferenced vertices go, with their attributes.
/// Cost: O(F log F) (union-find over the faces, a sort of the components).
ComponentsRemoved remove_extra_components(Mesh& m, std::size_t allowed, double max_area_fraction);

/// Drops the vertices no triangle uses; the others keep their original order and their attributes,
/// and the triangles are renumbered. Cost: two passes over the triangles and one over the vertices.
void remove_unreferenced_vertices(Mesh& m);

/// Sets m.normals to unit vertex normals from its triangles, each face's normal weighted by its angle at the vertex
/// (Thürmer and Wüthrich 1998: independent of how the faces around a vertex are split). A vertex in no triangle of
/// positive area gets a zero normal, as Mesh::normals allows. For meshes whose stage dropped the normals, so that
/// the written file still shades smoothly. Cost: one pass over the triangles, one over the vertices.
void compute_vertex_normals(Mesh& m);

/// The key of the undirected edge {a, b}: (smaller << 32) | larger.
inline std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
    return a < b ? std::uint64_t(a) << 32 | b : std::uint64_t(b) << 32 | a;
}

/// Sorted keys (edge_key) of the edges of exactly one triangle of tris: a mesh's boundary, for triangles with welded
/// indices (degenerate edges {a, a} skipped).
std::vector<std::uint64_t> single_face_edges(const std::vector<Tri>& tris);

/// The caps over m's holes, which a volume scanned from m closes (its winding number changes across them): for each
/// run of boundary edges (edges of one triangle; runs joined where they share a vertex), the triangles from the run's
/// centroid to each of its edges. A fan, not a minimal surface: its area is at least the hole's. Cost: O(F log F).
std::vector<std::array<Vec3d, 3>> hole_caps(const Mesh& m);

/// Bounding box of all positions of m.
inline Box3d bounding_box(const Mesh& m) {
    Box3d b;
    for (const auto& p : m.positions) b.extend(Vec3d(p));
    return b;
}

/// Face normal (unnormalised: length = 2 × area) of triangle t.
inline Vec3d face_area_vector(const Mesh& m, const Tri& t) {
    const Vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
    return cross(b - a, c - a);
}

}  // namespace normalflow
