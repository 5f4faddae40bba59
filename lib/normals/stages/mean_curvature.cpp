#include "normals/stages/mean_curvature.h"

#include <algorithm>

#include "band/iterate.h"
#include "normals/stages/refit.h"

namespace normalflow::engine {

void mean_curvature_flow(StageContext& c) {
    WorkBuffers& w = c.band.work();
    std::fill(w.hn.begin(), w.hn.end(), 0.0f);
    copy_samples(c.band.phi(), w.phi_next);  // refit_step writes only the active blocks of phi_next
    for (int s = 0; s < c.opt.normal_steps; ++s) {
        refit_step(c, false);
        c.ctl.tick(double(s + 1) / c.opt.normal_steps);
    }
}

}  // namespace normalflow::engine
