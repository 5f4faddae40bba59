#pragma once
/// \file iterate.h
/// Parallel elementwise passes over the band's per-sample arrays (the per-block iteration,
/// for_blocks, is Band's: it hands out the band's per-thread scratch).

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstring>

#include "band/layout.h"

namespace normalflow::engine {

/// body(lo, hi) over [0, n) in chunks of 64 Ki samples, in parallel: elementwise passes over the
/// whole band, whose first writes to a fresh buffer cost page faults that one thread would take
/// one after another.
template <class Body>
void for_chunks(std::size_t n, Body&& body) {
    constexpr std::size_t kChunk = std::size_t(1) << 16;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, (n + kChunk - 1) / kChunk),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t c = r.begin(); c != r.end(); ++c)
                              body(c * kChunk, std::min(n, (c + 1) * kChunk));
                      });
}

/// body(i) for every i in [0, n), in parallel (for_chunks).
template <class Body>
void for_samples(std::size_t n, Body&& body) {
    for_chunks(n, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) body(i);
    });
}

/// Resizes a work array to n elements, reallocating with a quarter of headroom when it must grow.
template <class V>
void fit_samples(V& v, std::size_t n) {
    if (v.capacity() < n) {
        v = {};
        v.reserve(n + n / 4);
    }
    v.resize(n);
}

/// dst = src, in parallel (see for_samples).
inline void copy_samples(const Samples& src, Samples& dst) {
    fit_samples(dst, src.size());
    for_chunks(src.size(), [&](std::size_t lo, std::size_t hi) {
        std::memcpy(dst.data() + lo, src.data() + lo, sizeof(float) * (hi - lo));
    });
}

/// dst = src for the three components.
inline void copy_fields(const Field3& src, Field3& dst) {
    for (int c = 0; c < 3; ++c) copy_samples(src[c], dst[c]);
}

}  // namespace normalflow::engine
