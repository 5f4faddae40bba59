// The isotropic normal filter: isotropic normal diffusion, G(κ²) = κ² (Tasdizen et al. 2003, Eq. 15).
#include <memory>

#include "normals/stages/normal_filter.h"
#include "normals/stages/normal_loop.h"

namespace normalflow::engine {
namespace {

class IsotropicFilter final : public NormalFilter {
public:
    void filter_normals(StageContext& c) override {
        loop_.prepare(c);
        loop_.run(c, FaceWeight::One);
    }

private:
    NormalLoop loop_;
};

}  // namespace

std::unique_ptr<NormalFilter> make_isotropic_filter() { return std::make_unique<IsotropicFilter>(); }

}  // namespace normalflow::engine
