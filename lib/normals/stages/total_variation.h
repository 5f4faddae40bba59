#pragma once
/// \file total_variation.h
/// Total variation of the normal map on the surface samples (SmoothMode::TotalVariation), the
/// filter the paper names as its next step (section 6): the minimiser of
///
///     E(N) = Σ_i |G_i(N)|_F + (α/2) Σ_i |N_i − F_i|²,   |N_i| = 1,
///
/// over the surface samples i, G_i(N) = [D_x N, D_y N, D_z N]_i (I − n_i n_iᵀ) the tangential part
/// of the forward differences of N to the grid neighbours that are surface samples too (a missing
/// neighbour gives a zero difference), n_i the level set's normal and F the normals to stay near.
/// |∇N| instead of the diffusions' |∇N|² makes the normals piecewise constant: planar faces that
/// meet at sharp creases. 1/α is a length: a patch of radius r whose normals differ by a chord δ
/// from those around it is removed when 1/α >= δr/2 (the ROF disc), larger facets lose 2/(αR) of
/// their contrast.
///
/// Solved by the accelerated primal–dual algorithm of Chambolle & Pock (2011, Algorithm 2: the
/// fidelity is α-strongly convex), each primal step followed by the projection onto the unit
/// sphere. Every update reads the previous iterate only, in a fixed order: the result does not
/// depend on the threads.

#include <cstdint>
#include <vector>

#include "band/band.h"
#include "band/layout.h"
#include "normals/stages/surface_samples.h"

namespace normalflow::engine {

class TotalVariation {
public:
    /// The grid neighbours of the samples of S (which must have been built on `band`).
    void build(const Band& band, const SurfaceSamples& S);

    /// Filters N in place (arrays of S.size(), unit vectors; padding is left alone): `steps`
    /// primal–dual iterations from N, with F = N on entry and fidelity weight alpha (1/voxel).
    /// `poll` is called between iterations (it may throw to cancel).
    template <class Poll>
    void solve(const Band& band, Samples (&N)[3], float alpha, int steps, Poll&& poll) {
        start(N);
        initial_ = energy(band, N, alpha);
        for (int k = 0; k < steps; ++k) {
            poll();
            iterate(band, N, alpha);
        }
    }

    /// The energy E of N against the F of the last solve (for the tests and the reports).
    double energy(const Band& band, const Samples (&N)[3], float alpha) const;
    /// E at the start of the last solve, N = F: the total variation of F.
    double initial_energy() const { return initial_; }

private:
    void start(const Samples (&N)[3]);
    void iterate(const Band& band, Samples (&N)[3], float alpha);

    const SurfaceSamples* S_ = nullptr;
    std::vector<std::int32_t> fwd_[3], bwd_[3];  ///< neighbour along +axis / −axis, −1: none
    Samples f_[3], bar_[3], next_[3];            ///< F, the extrapolated N̄, the new N
    Samples y_[9];                               ///< the dual variable, 3×3 per sample (row c, column a)
    float tau_ = 0, sigma_ = 0;
    double initial_ = 0;
};

}  // namespace normalflow::engine
