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
};

}  // namespace normalflow::engine
