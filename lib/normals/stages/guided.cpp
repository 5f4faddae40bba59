// The guided filter of the normal map on the surface samples (surface_filter.h): the bilateral
// filter with its range weight taken on a guidance field of patch normals (after Zhang, Deng,
// Zhang, Bouaziz & Liu 2015), so that creases stay sharp under heavy noise.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "band/iterate.h"
#include "normals/smooth.h"
#include "normals/stages/normal_filter.h"
#include "normals/stages/surface_filter.h"

namespace normalflow::engine {
namespace {

class GuidedFilter final : public SurfaceSampleFilter {
public:
    int default_normal_steps() const override { return kNeighbourhoodPasses; }

private:
    void filter_samples(StageContext& c, const Disc& d) override {
        const std::size_t n = S_.size();
        for (int k = 0; k < 3; ++k) {
            fit_samples(guide_[k], n);
            fit_samples(mean_[k], n);
        }
        run_passes(c, d);
    }

    /// The passes' and the extension's range values: the guidance of the last pass.
    const Field3& range() const override { return guide_; }

    void before_pass(const Band& band, const Disc& d) override { guidance(band, d.radius); }

    /// The guidance of each surface sample: the mean normal of the most consistent patch (the
    /// samples within `patch` of a centre) among the patches centred within `patch` of it;
    /// consistency = |Σ N| / count, 1 for a patch of equal normals. A patch on one side of a
    /// crease is more consistent than one across it, so the guidance keeps the crease sharp
    /// while the noise, averaged over the patch, leaves it.
    void guidance(const Band& band, float radius) {
        const float patch = 0.5f * radius;
        const float p2 = patch * patch;
        const std::vector<std::int32_t>& act = band.active();
        band.for_blocks(act, 0, [&](std::size_t, std::int32_t b, Scratch&) {
            float acc[32];
            for (std::size_t i = S_.begin(b); i < S_.end(b); ++i) {
                if (S_.index[i] == SurfaceSamples::kPadding) {
                    consistency_[i] = -1.0f;
                    continue;
                }
                const float q[3] = {S_.p[0][i], S_.p[1][i], S_.p[2][i]};
                const float rq[3] = {0, 0, 0};
                gather_near(b, cur_, cur_, q, rq, 0.0f, 0.0f, p2, acc);
                const float x = lane_total(acc), y = lane_total(acc + 8), z = lane_total(acc + 16);
                const float cnt = lane_total(acc + 24);
                const float len = std::sqrt((x * x + y * y) + z * z);
                consistency_[i] = cnt > 0.0f ? len / cnt : 0.0f;
                const float inv = len > 1e-12f ? 1.0f / len : 0.0f;
                mean_[0][i] = x * inv;
                mean_[1][i] = y * inv;
                mean_[2][i] = z * inv;
            }
        });
        band.for_blocks(act, 0, [&](std::size_t, std::int32_t b, Scratch&) {
            for (std::size_t i = S_.begin(b); i < S_.end(b); ++i) {
                if (S_.index[i] == SurfaceSamples::kPadding) continue;
                const float q[3] = {S_.p[0][i], S_.p[1][i], S_.p[2][i]};
                float best = -1.0f;
                std::size_t at = i;
                for (std::int32_t b2 : S_.near(b)) {
                    if (S_.box_distance2(b2, q) > p2) continue;
                    for (std::size_t j = S_.begin(b2); j < S_.end(b2); ++j) {
                        const float dx = S_.p[0][j] - q[0], dy = S_.p[1][j] - q[1], dz = S_.p[2][j] - q[2];
                        if ((dx * dx + dy * dy) + dz * dz <= p2 && consistency_[j] > best) {
                            best = consistency_[j];
                            at = j;
                        }
                    }
                }
                for (int k = 0; k < 3; ++k) guide_[k][i] = mean_[k][at];
            }
        });
    }

    Samples guide_[3], mean_[3];  ///< the guidance; each sample's patch mean
};

}  // namespace

std::unique_ptr<NormalFilter> make_guided_filter() { return std::make_unique<GuidedFilter>(); }

}  // namespace normalflow::engine
