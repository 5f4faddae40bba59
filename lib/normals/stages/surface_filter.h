#pragma once
/// \file surface_filter.h
/// The base of the filters of the normal map on the surface samples: bilateral (bilateral.cpp),
/// guided (guided.cpp) and total variation (total_variation.cpp). It takes the samples next to
/// the surface (SurfaceSamples: |φ| <= kShell, moved to their closest points) with the normals
/// made from φ, lets the filter work on them (filter_samples), measures the roughness it left,
/// and carries the result to the rest of the active band by closest point (the extension). The
/// filters' disc is given in the model's units (SmoothOptions::length_scale). It also holds the
/// rules the three share: their main iterations, their refit (a time in model units, the patient
/// stop), the volume constraint and the early stop.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "band/band.h"
#include "band/layout.h"
#include "normals/smooth.h"
#include "normals/stages/normal_filter.h"
#include "normals/stages/normal_loop.h"
#include "normals/stages/stage.h"
#include "normals/stages/surface_samples.h"

namespace normalflow::engine {

/// The sum of the eight lanes of a pair_sum accumulator, in a fixed order.
inline float lane_total(const float* acc) {
    return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

class SurfaceSampleFilter : public NormalFilter {
public:
    /// N from φ and its energy G; the surface samples and their normals into cur_; the filter's own
    /// work on them (filter_samples); the roughness it left (c.record().roughness); the extension
    /// of cur_ to work().normals; the normal energies (normal_energy).
    void filter_normals(StageContext& c) final;

    int default_iterations() const override { return kNeighbourhoodIterations; }
    /// A refit time of kNeighbourhoodRefitTime·ℓ² (ℓ = length_scale in voxels), at least 40 steps.
    int default_refit_steps(const SmoothOptions& opt) const override;
    /// The patient stop (their normal maps are not exactly integrable), in super steps.
    RefitRules refit_rules() const override { return {RefitPenalty::Quadratic, RefitSchedule::Patient}; }
    bool preserves_volume(const SmoothOptions& opt) const override { return opt.preserve_volume; }
    bool stops_when_smooth() const override { return true; }

protected:
    /// The filters' disc, voxels: the length scale ℓ, the spatial σ_s = sigma_spatial·ℓ, the disc's
    /// radius 2σ_s and its square, the weights' factors 1/(2σ_s²) and 1/(2σ_r²).
    struct Disc {
        float ell, sigma_s, radius, r2, ks, kr;
    };

    /// The filter's work on cur_ (the surface samples' normals, N on entry), the filtered normals
    /// left in cur_. next_ and consistency_ are sized to the samples and free to use.
    virtual void filter_samples(StageContext& c, const Disc& d) = 0;
    /// The range values of the filter passes and of the extension: cur_ (guided: its guidance).
    virtual const Field3& range() const { return cur_; }
    /// The stride of the samples (SurfaceSamples::build): every s-th shell sample along each axis,
    /// s = ⌊ℓ / kStrideLength⌋ with thin_samples (about as many per ℓ² at any resolution, so that
    /// a finer grid costs no more here), else 1.
    virtual int stride(const SmoothOptions& opt, float ell) const;
    /// SmoothIteration::normal_energy: G before the filter (g_before) and after the extension.
    virtual std::vector<double> normal_energy(StageContext& c, double g_before);

    /// normal_steps passes of filter_pass on cur_ (the range values range()), before_pass ahead of
    /// each; progress ticks to one half.
    void run_passes(StageContext& c, const Disc& d);
    /// What a filter does before each of run_passes' passes (guided: its guidance).
    virtual void before_pass(const Band&, const Disc&) {}
    /// One pass of the filter over the surface samples: out_i = normalised Σ_j w_ij cur_j, the
    /// range weight on `range`, cur_i where the weights vanish.
    void filter_pass(const Band& band, const Field3& range, const Disc& d, Field3& out);
    /// acc = Σ over the samples within √r2 of q (their blocks near b) of the pair weights
    /// (kernels/pair_sum), range values r, values v.
    void gather_near(std::int32_t b, const Field3& r, const Field3& v, const float q[3], const float rq[3], float ks,
                     float kr, float r2, float (&acc)[32]) const;
    NormalLoop loop_;
    SurfaceSamples S_;
    Samples cur_[3], next_[3];  ///< the samples' normals; the passes' output
    Samples consistency_;       ///< per sample: roughness's scratch (guided: its patches' consistency)

private:
    std::size_t nearest_sample(const Band& band, std::int32_t b, const float q[3], float best) const;
    float roughness(const Band& band, float ks, float r2);
    void extend(StageContext& c, const Disc& d);
};

}  // namespace normalflow::engine
