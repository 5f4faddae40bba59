#pragma once
/// \file exp_nonpositive.h

#include <algorithm>
#include <bit>
#include <cstdint>

namespace normalflow::engine {

/// e^x for x <= 0, branch-free so that the loops calling it vectorise (expf is a library call
/// per element): x = n ln2 + r with |r| <= ln2/2, e^r by Cephes' expf polynomial (1 + r + r²/2 + …,
/// degree 7), 2ⁿ from the exponent bits. Within 1 ulp of expf on [−87, 0] (relative error < 8e−8,
/// checked on every 32nd float of the range, tests/normals/kernels/test_exp_nonpositive.cpp); below
/// −87 it returns e^−87 ≈ 1.6e−38 (where expf gives a denormal or 0). Plain float operations, no
/// contraction: the same value at every vector width and on every thread.
inline float exp_nonpositive(float x) {
    x = std::max(x, -87.0f);
    const float t = x * 1.44269504088896341f + 12582912.0f;  // 1.5·2²³: rounds x·log₂e to an integer
    const float n = t - 12582912.0f;
    const std::int32_t ni = std::bit_cast<std::int32_t>(t) - 0x4B400000;
    const float r = (x - n * 0.693359375f) + n * 2.12194440e-4f;  // ln2 = 0.693359375 − 2.12194440e−4
    const float r2 = r * r;
    float p = 1.9875691500e-4f;
    p = p * r + 1.3981999507e-3f;
    p = p * r + 8.3334519073e-3f;
    p = p * r + 4.1665795894e-2f;
    p = p * r + 1.6666665459e-1f;
    p = p * r + 5.0000001201e-1f;
    const float er = p * r2 + r + 1.0f;
    return er * std::bit_cast<float>((ni + 127) << 23);
}

}  // namespace normalflow::engine
