#pragma once
/// \file mean_curvature.h
/// Mean curvature flow, the second-order baseline (Tasdizen et al. 2003, Eq. 9).

#include "normals/stages/stage.h"

namespace normalflow::engine {

/// normal_steps explicit steps of φ_t = |∇φ| H_φ on the active samples (the refit's step with
/// H_N = 0); reports progress. Uses work().hn and work().phi_next.
void mean_curvature_flow(StageContext& c);

}  // namespace normalflow::engine
