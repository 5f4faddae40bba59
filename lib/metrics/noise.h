#pragma once
/// \file noise.h
/// Synthetic noise for denoising experiments, defined as the mesh denoising literature defines it
/// (e.g. Zheng et al. 2011; Zhang et al. 2015, whose GuidedDenoising code made shared/data/pairs_gnf):
/// σ is a multiple of the mean edge length.

#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh.h"

namespace normalflow {

/// Distribution of the displacement.
enum class NoiseKind {
    Gaussian,  ///< every vertex moves by a length drawn from N(0, σ²)
    Impulsive  ///< a random subset (NoiseOptions::impulsive_fraction) of the vertices moves by N(0, σ²)
};

/// Direction of the displacement.
enum class NoiseDirection {
    Normal,  ///< along the area-weighted vertex normal (signed length)
    Random   ///< along a uniformly random unit direction (signed length)
};

/// Options of add_noise.
struct NoiseOptions {
    double sigma = 0.2;      ///< standard deviation of the displacement length, as a multiple of the
                             ///< mean edge length (unitless, >= 0; 0.1 to 0.7 is the usual range)
    std::uint64_t seed = 1;  ///< random seed; the same seed gives the same mesh on every platform
    NoiseKind kind = NoiseKind::Gaussian;
    NoiseDirection direction = NoiseDirection::Normal;
    double impulsive_fraction = 0.1;  ///< fraction of the vertices displaced by Impulsive noise, in [0, 1]
};

/// What add_noise did.
struct NoiseReport {
    double mean_edge_length = 0.0;  ///< over the distinct edges of the welded mesh, world units
    double sigma_world = 0.0;       ///< σ in world units (sigma × mean_edge_length)
    std::size_t vertices = 0;       ///< welded referenced vertices
    std::size_t displaced = 0;      ///< vertices displaced
    double rms_displacement = 0.0;  ///< RMS displacement over the displaced vertices, world units
};

/// Adds random displacements to the vertices of m, modified in place (the triangles are unchanged).
/// Method: positions with identical coordinates are welded first, so every copy of a point moves
/// together and the surface does not crack; unreferenced points do not move. For each welded
/// referenced vertex, in index order, a displacement of length t·σ·ℓ (t ~ N(0, 1), ℓ = mean edge
/// length) is drawn along its normal or a random direction. The random numbers come from
/// std::mt19937_64 with a hand-written Box–Muller transform (std::normal_distribution differs between
/// standard libraries), so a seed gives the same result everywhere. Impulsive noise picks
/// round(fraction · #V) vertices by a partial Fisher–Yates shuffle.
/// Accepts any triangle soup with at least one triangle (open, non-manifold, many components); a
/// vertex whose faces have zero total area gets a random direction in Normal mode.
/// \throw InvalidInput for a mesh without triangles, out-of-range indices, non-finite positions,
///        sigma < 0 or a fraction outside [0, 1].
/// Colours and texture coordinates stay; normals, when m has them, are recomputed from the noisy faces.
/// Cost: O(V log V + F log F), single-threaded (the random stream is sequential).
NoiseReport add_noise(Mesh& m, const NoiseOptions& opt = {});

/// Mean length of the distinct undirected edges of m after exact welding (world units); 0 if none.
/// \throw InvalidInput for out-of-range indices or non-finite positions.
double mean_edge_length(const Mesh& m);

/// What estimate_noise measured.
struct NoiseEstimate {
    double sigma = 0.0;           ///< the noise's standard deviation along the normal, world units; 0 if unknown
    std::size_t vertices = 0;     ///< vertices measured (they and their neighbours interior, 3 or more neighbours)
    double mean_edge_length = 0;  ///< of the welded mesh, world units (to express sigma in edges)
};

/// Unit vertex normals that the noise barely tilts: each vertex's area-weighted normal (area_normal[v],
/// any length; zero where unknown), then twice replaced by the normalised sum of its own and its edge
/// neighbours' (edges: each undirected edge once, indices below area_normal.size()). A vertex's own
/// normal turns with its neighbours' noise (by about the noise over an edge); averaged over two rings it
/// turns several times less, which the offsets of estimate_noise and the risk of filter_faces are
/// measured along. Zero where the sum is zero. Cost: O(V + E), single-threaded, deterministic.
std::vector<Vec3d> steady_vertex_normals(const std::vector<Vec3d>& area_normal,
                                         const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges);

/// steady_vertex_normals of m's positions as its triangles index them (not welded), one per position.
/// \throw InvalidInput for out-of-range indices.
std::vector<Vec3d> steady_vertex_normals(const Mesh& m);

/// The normals estimate_noise measures the offsets along.
enum class NoiseNormals {
    Own,    ///< each vertex's area-weighted normal, which the noise it measures tilts
    Steady  ///< steady_vertex_normals: reads heavy noise (0.5-0.7 edges) 2-4% low where Own reads it 10-17% low
};

/// Estimates how far noise moved m's vertices off its surface, from m alone. Each interior vertex's
/// offset δ_v from the centroid of its neighbours, along its normal (NoiseNormals), is its noise less the
/// mean of its neighbours' plus the surface's curvature (about ℓ²κ/4 for edges ℓ), which varies slowly
/// from vertex to vertex; the second difference Δ_v = δ_v − mean of the neighbours' δ keeps the noise and
/// cancels most of the curvature. σ² = Σ Δ_v² / Σ c_v, where c_v is Δ_v's response to unit white noise on
/// m's own connectivity (the sum of the squared coefficients of row v of (I − A)², A the neighbour mean;
/// exact, no sampling). On add_noise's Gaussian noise along the normals it recovers σ within a few
/// percent; impulsive noise counts with its energy (a fraction f of vertices moved by σ reads as about
/// σ·√f); a clean mesh reads small: a sphere's curvature alone at about 1/16 of ℓ²κ/4, a scan's detail
/// at 0.01–0.03 edges, creases more (fandisk 0.08 edges).
/// Accepts any triangle soup (welded exactly first; vertices on or next to an open boundary are skipped).
/// \throw InvalidInput for out-of-range indices or non-finite positions.
/// Cost: O(V k² + F log F) for valence k, single-threaded, deterministic.
NoiseEstimate estimate_noise(const Mesh& m, NoiseNormals along = NoiseNormals::Own);

namespace detail {
/// The deterministic standard normal generator used by add_noise (mt19937_64 + Box–Muller, both values used).
class NormalRng {
public:
    explicit NormalRng(std::uint64_t seed);
    double normal();                       ///< N(0, 1)
    double uniform();                      ///< [0, 1), 53 random bits
    std::uint64_t below(std::uint64_t n);  ///< uniform in [0, n), n > 0 (rejection sampling, unbiased)

private:
    std::mt19937_64 engine_;  // fully specified by the standard: the same stream everywhere
    bool has_spare_ = false;
    double spare_ = 0.0;
};
}  // namespace detail

}  // namespace normalflow
