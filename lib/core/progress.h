#pragma once
/// \file progress.h
/// Progress reporting and cancellation: one optional pointer to this tiny interface is passed to
/// long-running stages. Stages call it once per iteration or per slab, never per voxel.

#include <string_view>

#include "core/errors.h"

namespace normalflow {

/// Receives progress from long-running stages; may request cancellation.
/// Implementations must be callable from the thread that runs the stage (not from workers).
class Progress {
public:
    virtual ~Progress() = default;
    /// A new stage starts (e.g. "voxelize", "normals", "refit").
    virtual void begin(std::string_view /*stage*/) {}
    /// Fraction done of the current stage, in [0, 1].
    virtual void progress(double /*fraction*/) {}
    /// Return true to stop; the stage then throws Cancelled.
    virtual bool should_stop() { return false; }
};

namespace detail {
/// Calls p->progress(f) and throws Cancelled if p asks to stop. p may be null.
inline void tick(Progress* p, double fraction, const char* who) {
    if (!p) return;
    p->progress(fraction);
    if (p->should_stop()) throw Cancelled(std::string(who) + ": cancelled");
}
inline void begin(Progress* p, std::string_view stage) {
    if (p) p->begin(stage);
}
}  // namespace detail

}  // namespace normalflow
