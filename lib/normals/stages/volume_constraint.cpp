#include "normals/stages/volume_constraint.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "band/iterate.h"

namespace normalflow::engine {

namespace {

/// Σ over the active samples of clamp(0.5 − φ − shift, 0, 1), and the count of those with
/// |φ + shift| < 0.5 (the derivative of the sum in −shift), per block then in block order.
void volume_and_slope(const Band& band, float shift, double& volume, double& slope,
                      const std::array<int, 3>* lo = nullptr, const std::array<int, 3>* hi = nullptr) {
    const std::vector<std::int32_t>& act = band.active();
    std::vector<double> v(act.size()), a(act.size());
    const Samples& phi = band.phi();
    const std::uint8_t* mask = band.mask();
    band.for_blocks(act, 0, [&](std::size_t k, std::int32_t b, Scratch&) {
        const std::size_t base = std::size_t(b) * kBlockVoxels;
        float sv = 0.0f, sa = 0.0f;
        if (lo) {
            const auto& bc = band.block_coord(std::size_t(b));
            for (int d = 0; d < 3; ++d)
                if (bc[d] < (*lo)[d] || bc[d] >= (*hi)[d]) {
                    v[k] = a[k] = 0.0;
                    return;
                }
        }
        for (std::size_t i = base; i < base + kBlockVoxels; ++i) {
            if (!mask[i]) continue;
            const float f = phi[i] + shift;
            sv += inside_share(f);
            sa += on_slope(f) ? 1.0f : 0.0f;
        }
        v[k] = sv;
        a[k] = sa;
    });
    volume = slope = 0.0;
    for (std::size_t k = 0; k < act.size(); ++k) {
        volume += v[k];
        slope += a[k];
    }
}

}  // namespace

double active_volume(const Band& band) {
    double v, a;
    volume_and_slope(band, 0.0f, v, a);
    return v;
}

void window_volume(const Band& band, const std::array<int, 3>& lo, const std::array<int, 3>& hi, double& volume,
                   double& slope) {
    volume_and_slope(band, 0.0f, volume, slope, &lo, &hi);
}

float restore_volume(Band& band, double target) {
    float shift = 0.0f;  // φ ← φ + shift; the volume falls as shift grows
    for (int it = 0; it < kVolumeNewtonSteps; ++it) {
        double v, a;
        volume_and_slope(band, shift, v, a);
        if (!(a > 0.0)) break;
        shift += float((v - target) / a);
    }
    if (shift == 0.0f) return 0.0f;
    Samples& phi = band.phi();
    for_samples(phi.size(), [&](std::size_t i) { phi[i] += shift; });
    return -shift;
}

}  // namespace normalflow::engine
