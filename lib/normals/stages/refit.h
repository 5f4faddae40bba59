#pragma once
/// \file refit.h
/// The refit of φ to the filtered normals (Tasdizen et al. 2003, Eq. 17, 53–54, Appendix A):
/// ∂φ/∂t = |∇φ|(H_φ − H_N), upwind |∇φ| (Osher & Sethian 1988), until D = Σ(|∇φ| − ∇φ·N) stops
/// decreasing.

#include "normals/stages/stage.h"

namespace normalflow::engine {

/// The penalty G(κ²) of the filter's normal energy, for the second-order term ∇·(G N).
enum class RefitPenalty {
    Quadratic,    ///< G = κ² (isotropic, high-boost, the surface-sample filters)
    PeronaMalik,  ///< G = (1 − exp(−κ²/(2µ²)))·2µ² (anisotropic, Eq. 20)
};

/// How the refit runs and when it stops.
enum class RefitSchedule {
    /// Explicit steps of refit_dt until D decreases by less than refit_tolerance of itself (the
    /// diffusions): a step that raised D is undone.
    FirstRise,
    /// The surface-sample filters' normal maps are not exactly integrable: D wanders a little on
    /// its way down. The refit stops when D has not reached a new low for max(5, refit_max_steps/20)
    /// steps, or rose to twice its low; in refit_super_steps super steps when that is > 0.
    Patient,
};

/// What the refit takes from the filter whose normals it fits (NormalFilter::refit_rules).
struct RefitRules {
    RefitPenalty penalty = RefitPenalty::Quadratic;
    RefitSchedule schedule = RefitSchedule::FirstRise;
};

/// H_N = ∇·N of band.work().normals [− T ∇·(G N), SmoothOptions::second_order_term, G by
/// rules.penalty] into work().hn, then refit steps until D stops decreasing (rules.schedule); φ
/// ends as the iterate with the smallest D seen. Reports D and the steps kept to c.record(). Uses
/// work().phi_next and work().spare().
void refit_to_normals(StageContext& c, const RefitRules& rules);

/// One explicit step φ ← φ + dt |∇φ|_upwind (H_φ − work().hn) on the active samples (φ →
/// work().phi_next, then swapped), dt = refit_dt (at most 1/6). Returns D(φ before the step) when
/// with_energy. work().phi_next must hold φ outside the active samples (the step writes only those
/// rows). Also the step of mean curvature flow (hn = 0).
double refit_step(StageContext& c, bool with_energy);

}  // namespace normalflow::engine
