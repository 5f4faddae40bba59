#pragma once
/// \file stage.h
/// What a stage of smooth_volume works on: the band, the options, the report and the run control.

#include "band/band.h"
#include "band/run_control.h"
#include "normals/smooth.h"

namespace normalflow::engine {

struct StageContext {
    Band& band;
    const SmoothOptions& opt;  ///< iterations resolved (default_iterations)
    SmoothReport& rep;
    RunControl& ctl;

    /// The record of the main iteration that runs now (smooth_volume adds it before the stages).
    SmoothIteration& record() { return rep.iterations.back(); }
    /// The record of the main iteration before this one; nullptr in the first.
    const SmoothIteration* previous() const {
        return rep.iterations.size() >= 2 ? &rep.iterations[rep.iterations.size() - 2] : nullptr;
    }
};

}  // namespace normalflow::engine
