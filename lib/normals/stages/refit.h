#pragma once
/// \file refit.h
/// The refit of φ to the filtered normals (Tasdizen et al. 2003, Eq. 17, 53–54, Appendix A):
/// ∂φ/∂t = |∇φ|(H_φ − H_N), upwind |∇φ| (Osher & Sethian 1988), until D = Σ(|∇φ| − ∇φ·N) stops
/// decreasing.

#include "normals/stages/stage.h"

namespace normalflow::engine {

/// H_N = ∇·N of band.work().normals [− T ∇·(G N), SmoothOptions::second_order_term] into
/// work().hn, then refit steps until D stops decreasing; φ ends as the iterate with the smallest D
/// seen. Reports D and the steps kept to c.record(). Uses work().phi_next and work().spare().
void refit_to_normals(StageContext& c);

/// One explicit step φ ← φ + dt |∇φ|_upwind (H_φ − work().hn) on the active samples (φ →
/// work().phi_next, then swapped), dt = refit_dt (at most 1/6). Returns D(φ before the step) when
/// with_energy. work().phi_next must hold φ outside the active samples (the step writes only those
/// rows). Also the step of mean curvature flow (hn = 0).
double refit_step(StageContext& c, bool with_energy);

}  // namespace normalflow::engine
