#pragma once
/// \file normal_filter.h
/// The normal filters of smooth_volume behind one interface (after OpenVDB's LevelSetFilter):
/// each makes the normal map N of the band's φ and filters it, leaving the filtered normals in
/// band.work().normals for the refit, and states its rules (its defaults, what the refit needs,
/// the volume constraint, the early stop), which smooth_volume and the refit ask it for instead of
/// switching on the mode. One filter per file (isotropic.cpp, anisotropic.cpp, highboost.cpp; on
/// the surface samples, surface_filter.h: bilateral.cpp, guided.cpp, total_variation.cpp); a new
/// filter is a new file, a make_ function here and a case in make_normal_filter.

#include <memory>

#include "normals/smooth.h"
#include "normals/stages/refit.h"
#include "normals/stages/stage.h"

namespace normalflow::engine {

/// The diffusions' defaults (and mean curvature flow's): main iterations, normal steps per main
/// iteration, refit steps per main iteration.
inline constexpr int kDiffusionIterations = 8;
inline constexpr int kDiffusionSteps = 50;
inline constexpr int kDiffusionRefitSteps = 40;

class NormalFilter {
public:
    virtual ~NormalFilter() = default;
    /// N from φ, then the filter's normal loop; the result in c.band.work().normals (the active
    /// samples filtered, the others N). Uses work().normals_next and work().normals_aux; reports
    /// the normal energies (and the anisotropic µ) to c.record().
    virtual void filter_normals(StageContext& c) = 0;

    /// The main iterations for SmoothOptions::iterations = 0 (default_iterations).
    virtual int default_iterations() const { return kDiffusionIterations; }
    /// The normal steps (filter passes, solver iterations) for normal_steps = 0 (default_normal_steps).
    virtual int default_normal_steps() const { return kDiffusionSteps; }
    /// The refit steps for refit_max_steps = 0 (default_refit_steps).
    virtual int default_refit_steps(const SmoothOptions&) const { return kDiffusionRefitSteps; }
    /// How the refit of this filter's normals runs and stops.
    virtual RefitRules refit_rules() const { return {}; }
    /// Whether each refit is followed by the shift that restores the enclosed volume (restore_volume).
    virtual bool preserves_volume(const SmoothOptions&) const { return false; }
    /// Whether a run with iterations = 0 stops after a main iteration whose filter left a roughness
    /// (SmoothIteration::roughness) below kNeighbourhoodRoughness.
    virtual bool stops_when_smooth() const { return false; }
};

std::unique_ptr<NormalFilter> make_isotropic_filter();        ///< G(κ²) = κ² (Eq. 15)
std::unique_ptr<NormalFilter> make_anisotropic_filter();      ///< Perona–Malik (Eq. 20), see SmoothOptions
std::unique_ptr<NormalFilter> make_highboost_filter();        ///< isotropic, then Eq. 21–22
std::unique_ptr<NormalFilter> make_bilateral_filter();        ///< bilateral.cpp
std::unique_ptr<NormalFilter> make_guided_filter();           ///< guided.cpp: bilateral, guided range
std::unique_ptr<NormalFilter> make_total_variation_filter();  ///< total_variation.cpp, total_variation.h

/// The filter of a mode; nullptr for MeanCurvature (no normals).
std::unique_ptr<NormalFilter> make_normal_filter(SmoothMode mode);

}  // namespace normalflow::engine
