#pragma once
// Options shared by the smooth_volume tests (test_smooth.cpp, test_smooth_run.cpp).

#include "normals/smooth.h"

namespace normalflow::test {

/// Default options with the paper's 25 normal steps per main iteration (fast tests).
inline SmoothOptions options(SmoothMode mode, int iterations) {
    SmoothOptions o;
    o.mode = mode;
    o.iterations = iterations;
    o.normal_steps = 25;
    return o;
}

}  // namespace normalflow::test
