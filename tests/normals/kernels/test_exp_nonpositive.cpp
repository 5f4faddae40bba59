// exp_nonpositive (lib/normals/kernels/exp_nonpositive.h) against std::exp.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>

#include "normals/kernels/exp_nonpositive.h"

namespace normalflow::engine {
namespace {

/// Distance in units in the last place of two positive finite floats.
std::int64_t ulps(float a, float b) {
    return std::abs(std::int64_t(std::bit_cast<std::int32_t>(a)) - std::int64_t(std::bit_cast<std::int32_t>(b)));
}

// Every 32nd float of [−87, 0] (about 35 million; the header claims 1 ulp on every 256th).
TEST(ExpNonpositive, WithinOneUlpOfStdExpOnMinus87To0) {
    const std::int32_t lo = std::bit_cast<std::int32_t>(-0.0f), hi = std::bit_cast<std::int32_t>(-87.0f);
    std::int64_t worst = 0, count = 0;
    float worst_x = 0.0f;
    for (std::int64_t b = lo; b <= hi; b += 32) {
        const float x = std::bit_cast<float>(std::int32_t(b));
        const std::int64_t u = ulps(exp_nonpositive(x), std::exp(x));
        if (u > worst) {
            worst = u;
            worst_x = x;
        }
        ++count;
    }
    EXPECT_GT(count, 30'000'000);
    EXPECT_LE(worst, 1) << "at x = " << worst_x;
}

TEST(ExpNonpositive, EndsAndBelowRange) {
    EXPECT_EQ(exp_nonpositive(0.0f), 1.0f);
    EXPECT_EQ(exp_nonpositive(-0.0f), 1.0f);
    EXPECT_LE(ulps(exp_nonpositive(-87.0f), std::exp(-87.0f)), 1);
    // below −87 it returns e^−87 (no denormals, no 0)
    EXPECT_EQ(exp_nonpositive(-100.0f), exp_nonpositive(-87.0f));
    EXPECT_EQ(exp_nonpositive(-1e30f), exp_nonpositive(-87.0f));
    EXPECT_GT(exp_nonpositive(-1e30f), 0.0f);
}

}  // namespace
}  // namespace normalflow::engine
