#pragma once
/// \file normal_loop.h
/// The normal loop the normal filters share: the normal map from φ, the cache of φ of the active
/// blocks, and the explicit steps ∂N/∂t = (I − NNᵀ)∇·[g ∇N(I − P)] with Appendix B's staggered
/// fluxes (Eq. 43–52) and renormalisation, weighted by a FaceWeight.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "band/layout.h"
#include "core/band_memory.h"
#include "normals/kernels/face_row.h"
#include "normals/stages/stage.h"

namespace normalflow::engine {

/// Per active block, a value per face in the padded layout (L³), one array per axis: the frozen
/// conductance of the anisotropic filter.
using PaddedFaces = std::vector<float, detail::HugePageAllocator<float>>;

class NormalLoop {
public:
    /// N = ∇φ/|∇φ| (central differences, Eq. 41–42) into c.band.work().normals on every allocated
    /// block; φ of every active block with its halo and which rows of faces touch the band, held
    /// for the whole loop (φ does not change there): the steps read it instead of gathering it.
    void prepare(StageContext& c);

    /// One step of the normal loop on src → dst over the active blocks; returns G(src).
    /// update == false: only the energy. g: the frozen conductance per axis when w is Frozen.
    /// dst must hold src outside the active samples (the step writes only those rows).
    double step(StageContext& c, Field3& src, Field3& dst, FaceWeight w, bool update, const PaddedFaces* g = nullptr);

    /// normal_steps steps on work().normals (ping-pong with work().normals_next), the energy G
    /// before each and after the last into c.record().
    void run(StageContext& c, FaceWeight w, const PaddedFaces* g = nullptr);

    /// φ of active block k (its index in band.active()) with its halo, after prepare.
    const float* padded_phi(std::size_t k) const { return pad_phi_.data() + k * L3; }

private:
    void init_normals(StageContext& c);
    void cache_phi(StageContext& c);

    Samples pad_phi_;                     // per active block: φ with its halo (L³), during the normal loop
    std::vector<std::uint8_t> row_band_;  // per active block: which rows of faces touch the band (row_flag)
};

}  // namespace normalflow::engine
