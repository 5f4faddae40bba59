#pragma once
/// \file pair_sum.h
/// The inner loop of the band's neighbourhood filters (stages/surface_filter.h): weighted sums of the
/// values of a run of surface samples around a query point.

#include <cstdint>

namespace normalflow::engine {

/// Surface samples as a struct of arrays: positions p, range values r (what the range weight
/// compares), values v (what is averaged), all indexed alike.
struct PairArrays {
    const float* p[3];
    const float* r[3];
    const float* v[3];
};

/// A run of samples [begin, begin + n), n a multiple of 8; padding samples lie far away (their
/// weight is 0).
struct PairSpan {
    std::int64_t begin;
    std::int64_t n;
};

/// For each sample j of the spans[0 … count) of a: w_j = exp(−ks·|p_j − q|² − kr·|r_j − rq|²) when
/// |p_j − q|² <= r2, else 0; adds w_j·v_j to acc[0..7] (x), acc[8..15] (y), acc[16..23] (z) and
/// w_j to acc[24..31], lane j mod 8 of its span. Each lane sums its samples in order, so the result
/// is the same on every thread and at every vector width (the caller adds the lanes in a fixed
/// order). A query's spans in one call pay the set-up once.
void pair_sum(const PairArrays& a, const PairSpan* spans, int count, const float q[3], const float rq[3], float ks,
              float kr, float r2, float* __restrict acc);

}  // namespace normalflow::engine
