#pragma once
// The option sets the engine's benchmarks name (bench_normals, nf_ab_engine).
#include <string>

#include "normals/smooth.h"

namespace normalflow::bench {

/// "isotropic" and "anisotropic" are the defaults (anisotropic: 25 conductance pre-smoothing steps
/// + 50 normal steps); "paper25" is the definition of a main iteration, anisotropic with the
/// paper's 25 normal steps and no pre-smoothing. Any other name gives the defaults (anisotropic).
inline SmoothOptions options_for(const std::string& variant) {
    SmoothOptions o;
    if (variant == "isotropic") {
        o.mode = SmoothMode::Isotropic;
    } else if (variant == "paper25") {
        o.mode = SmoothMode::Anisotropic;
        o.normal_steps = 25;
        o.conductance_presmooth_steps = 0;
    }
    return o;
}

}  // namespace normalflow::bench
