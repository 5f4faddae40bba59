// The high-boost normal filter (Tasdizen et al. 2003, Eq. 21–22): the isotropic normal loop takes
// Nⁿ to Nⁿ⁺¹, then N' = normalize((1 + α)Nⁿ − αNⁿ⁺¹) at the active samples.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "band/iterate.h"
#include "normals/stages/normal_filter.h"
#include "normals/stages/normal_loop.h"

namespace normalflow::engine {
namespace {

class HighBoostFilter final : public NormalFilter {
public:
    void filter_normals(StageContext& c) override {
        WorkBuffers& w = c.band.work();
        loop_.prepare(c);
        copy_fields(w.normals, w.normals_aux);  // Nⁿ
        loop_.run(c, FaceWeight::One);
        const float a = c.opt.alpha;
        const std::uint8_t* mask = c.band.mask();
        Field3& n = w.normals;
        const Field3& prev = w.normals_aux;
        for (std::size_t i = 0; i < n[0].size(); ++i) {
            if (!mask[i]) continue;
            float v[3];
            for (int k = 0; k < 3; ++k) v[k] = (1.0f + a) * prev[k][i] - a * n[k][i];
            const float len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if (len > 1e-6f)
                for (int k = 0; k < 3; ++k) n[k][i] = v[k] / len;
            else
                for (int k = 0; k < 3; ++k) n[k][i] = prev[k][i];
        }
    }

private:
    NormalLoop loop_;
};

}  // namespace

std::unique_ptr<NormalFilter> make_highboost_filter() { return std::make_unique<HighBoostFilter>(); }

}  // namespace normalflow::engine
