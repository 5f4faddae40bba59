#pragma once
/// \file run_control.h
/// What the engine's stages report to while smooth_volume runs: progress ticks, cancellation and
/// the main iteration a numerical failure is reported at.

#include <algorithm>
#include <string>

#include "core/errors.h"
#include "core/progress.h"

namespace normalflow::engine {

class RunControl {
public:
    RunControl(Progress* progress, int iterations) : progress_(progress), iterations_(iterations) {}

    /// The main iteration running (0-based); smooth_volume sets it.
    int iteration = 0;

    /// Honours a stop request between passes of work that reports no progress of its own
    /// (reinitialisation sweeps, conductance pre-smoothing), so cancelling stays prompt.
    void poll() const {
        if (progress_ && progress_->should_stop()) throw Cancelled("smooth_volume: cancelled");
    }

    /// Progress: frac_in_iteration of the current main iteration done.
    void tick(double frac_in_iteration) const {
        const double f = (iteration + std::clamp(frac_in_iteration, 0.0, 1.0)) / iterations_;
        detail::tick(progress_, f, "smooth_volume");
    }

    /// Progress: all done (a run that stops early).
    void finish() const { detail::tick(progress_, 1.0, "smooth_volume"); }

    [[noreturn]] void fail(const char* what) const {
        throw NumericalError(std::string("smooth_volume: non-finite ") + what + " at main iteration " +
                             std::to_string(iteration + 1));
    }

private:
    Progress* progress_;
    int iterations_;
};

}  // namespace normalflow::engine
