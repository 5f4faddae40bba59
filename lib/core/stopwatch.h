#pragma once
/// \file stopwatch.h
/// Wall-clock seconds of a stage, for the reports (steady clock, so not affected by clock changes).

#include <chrono>

namespace normalflow {

/// Wall-clock stopwatch in seconds.
class Stopwatch {
public:
    Stopwatch() : t0_(std::chrono::steady_clock::now()) {}
    /// Seconds since construction or the last lap().
    double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count(); }
    /// Seconds since construction or the last lap(), and restart.
    double lap() {
        const auto t = std::chrono::steady_clock::now();
        const double s = std::chrono::duration<double>(t - t0_).count();
        t0_ = t;
        return s;
    }

private:
    std::chrono::steady_clock::time_point t0_;
};

}  // namespace normalflow
