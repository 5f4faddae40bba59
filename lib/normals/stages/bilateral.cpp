// The bilateral filter of the normal map on the surface samples (surface_filter.h), the band's
// counterpart of bilateral normal filtering (Zheng, Fu, Au & Tai 2011): normal_steps passes of
// N_i ← normalize(Σ_j W_s(|p_i − p_j|) W_r(|N_i − N_j|) N_j) over a disc in the model's units.
#include <memory>

#include "normals/smooth.h"
#include "normals/stages/normal_filter.h"
#include "normals/stages/surface_filter.h"

namespace normalflow::engine {
namespace {

class BilateralFilter final : public SurfaceSampleFilter {
public:
    int default_normal_steps() const override { return kNeighbourhoodPasses; }

private:
    void filter_samples(StageContext& c, const Disc& d) override { run_passes(c, d); }
};

}  // namespace

std::unique_ptr<NormalFilter> make_bilateral_filter() { return std::make_unique<BilateralFilter>(); }

}  // namespace normalflow::engine
