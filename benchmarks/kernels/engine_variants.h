#pragma once
// The option sets the engine's benchmarks name (bench_normals, nf_ab_engine).
#include <string>

#include "normals/smooth.h"

namespace normalflow::bench {

/// The variants by name: "isotropic" and "anisotropic" are the defaults (anisotropic: 25 conductance
/// pre-smoothing steps + robust µ schedule + 50 normal steps); "paper25" is the definition
/// of a main iteration, anisotropic with the paper's 25 normal steps and no pre-smoothing (the live
/// conductance g of the current normals; such a run stops after one main iteration,
/// SmoothReport::stopped_unchanged, when its refit keeps no step); "highboost" and "mcf" are those
/// modes with their defaults; "second_order" is the anisotropic default plus Appendix A's second
/// term in the refit (SmoothOptions::second_order_term). Together they take every path of the engine.
inline constexpr const char* kVariants[] = {"isotropic", "anisotropic", "paper25", "highboost", "mcf", "second_order"};

/// Whether name is one of kVariants.
inline bool is_variant(const std::string& name) {
    for (const char* v : kVariants)
        if (name == v) return true;
    return false;
}

/// The options of a variant (see kVariants). Any other name gives the defaults (anisotropic).
inline SmoothOptions options_for(const std::string& variant) {
    SmoothOptions o;
    if (variant == "isotropic") {
        o.mode = SmoothMode::Isotropic;
    } else if (variant == "paper25") {
        o.mode = SmoothMode::Anisotropic;
        o.normal_steps = 25;
        o.conductance_presmooth_steps = 0;
    } else if (variant == "highboost") {
        o.mode = SmoothMode::HighBoost;
    } else if (variant == "mcf") {
        o.mode = SmoothMode::MeanCurvature;
    } else if (variant == "second_order") {
        o.mode = SmoothMode::Anisotropic;
        o.second_order_term = true;
    }
    return o;
}

}  // namespace normalflow::bench
