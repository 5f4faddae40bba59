#include "normals/stages/normal_filter.h"

namespace normalflow::engine {

std::unique_ptr<NormalFilter> make_normal_filter(SmoothMode mode) {
    switch (mode) {
        case SmoothMode::Isotropic: return make_isotropic_filter();
        case SmoothMode::Anisotropic: return make_anisotropic_filter();
        case SmoothMode::HighBoost: return make_highboost_filter();
        case SmoothMode::Bilateral: return make_bilateral_filter();
        case SmoothMode::Guided: return make_guided_filter();
        case SmoothMode::TotalVariation: return make_total_variation_filter();
        case SmoothMode::MeanCurvature: return nullptr;
    }
    return nullptr;
}

}  // namespace normalflow::engine
