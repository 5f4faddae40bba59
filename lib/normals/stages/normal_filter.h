#pragma once
/// \file normal_filter.h
/// The normal filters of smooth_volume behind one interface (after OpenVDB's LevelSetFilter):
/// each makes the normal map N of the band's φ and filters it, leaving the filtered normals in
/// band.work().normals for the refit. One filter per file (isotropic.cpp, anisotropic.cpp,
/// highboost.cpp); a new filter is a new file, a make_ function here and a case in
/// make_normal_filter.

#include <memory>

#include "normals/smooth.h"
#include "normals/stages/stage.h"

namespace normalflow::engine {

class NormalFilter {
public:
    virtual ~NormalFilter() = default;
    /// N from φ, then the filter's normal loop; the result in c.band.work().normals (the active
    /// samples filtered, the others N). Uses work().normals_next and work().normals_aux; reports
    /// the normal energies (and the anisotropic µ) to c.record().
    virtual void filter_normals(StageContext& c) = 0;
};

std::unique_ptr<NormalFilter> make_isotropic_filter();        ///< G(κ²) = κ² (Eq. 15)
std::unique_ptr<NormalFilter> make_anisotropic_filter();      ///< Perona–Malik (Eq. 20), see SmoothOptions
std::unique_ptr<NormalFilter> make_highboost_filter();        ///< isotropic, then Eq. 21–22
std::unique_ptr<NormalFilter> make_bilateral_filter();        ///< bilateral.cpp
std::unique_ptr<NormalFilter> make_guided_filter();           ///< bilateral.cpp, guided range
std::unique_ptr<NormalFilter> make_total_variation_filter();  ///< bilateral.cpp, total_variation.h

/// The filter of a mode; nullptr for MeanCurvature (no normals).
std::unique_ptr<NormalFilter> make_normal_filter(SmoothMode mode);

}  // namespace normalflow::engine
