// The engine's band allocators (core/band_memory.h): large arrays mapped aligned to 2 MiB and
// advised for transparent huge pages, small ones from std::allocator, contents kept across growth.
#include "core/band_memory.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <limits>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

using namespace normalflow::detail;

namespace {

/// The VmFlags line of the mapping of /proc/self/smaps that contains address p ("" if none).
std::string vm_flags_of(const void* p) {
    std::ifstream f("/proc/self/smaps");
    const auto a = reinterpret_cast<std::uintptr_t>(p);
    std::string line;
    bool inside = false;
    while (std::getline(f, line)) {
        std::uintptr_t lo = 0, hi = 0;
        char dash = 0;
        std::istringstream s(line);
        if (s >> std::hex >> lo >> dash >> hi && dash == '-') {
            inside = lo <= a && a < hi;
            continue;
        }
        if (inside && line.rfind("VmFlags:", 0) == 0) return line;
    }
    return "";
}

bool thp_advice_possible() {
    std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string s;
    std::getline(f, s);
    return s.find("[madvise]") != std::string::npos || s.find("[always]") != std::string::npos;
}

}  // namespace

TEST(BandMemory, LargeArraysAreMappedAlignedToHugePagesAndAdvised) {
    if (!maps_huge_pages()) GTEST_SKIP() << "this system has no huge-page mapping";
    std::vector<float, HugePageAllocator<float>> v(3 * (kHugePageBytes / sizeof(float)) + 5, 1.5f);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % kHugePageBytes, 0u);
    for (const float x : v) ASSERT_EQ(x, 1.5f);  // value-initialised as asked
    if (thp_advice_possible()) {
        const std::string flags = vm_flags_of(v.data());
        ASSERT_FALSE(flags.empty()) << "no mapping holds the array";
        EXPECT_NE(flags.find(" hg"), std::string::npos) << "not advised for huge pages: " << flags;
    }
}

TEST(BandMemory, SmallArraysComeFromTheHeap) {
    std::vector<float, HugePageAllocator<float>> v(1000, 2.0f);
    // below one huge page: std::allocator, not a mapping of its own, so not advised
    if (maps_huge_pages() && thp_advice_possible()) {
        EXPECT_EQ(vm_flags_of(v.data()).find(" hg"), std::string::npos);
    }
    EXPECT_EQ(std::accumulate(v.begin(), v.end(), 0.0f), 2000.0f);
}

TEST(BandMemory, NoInitArraysStartAtZeroEvenInReusedHeapMemory) {
    // Memory freed by other data (here NaN bit patterns) and handed out again by malloc must not reach
    // the engine: a stage that reads an unwritten sample with a zero weight would turn it into NaN.
    using Vec = std::vector<float, NoInitAllocator<float>>;
    for (const std::size_t n : {std::size_t(16), std::size_t(4000), std::size_t(60000)}) {
        for (int round = 0; round < 4; ++round) {
            { std::vector<float> junk(n, std::numeric_limits<float>::quiet_NaN()); }
            Vec v(n);
            for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(v[i], 0.0f) << "n " << n << ", element " << i;
        }
    }
    Vec big(2 * (kHugePageBytes / sizeof(float)));  // a fresh mapping: zeros too
    EXPECT_EQ(std::accumulate(big.begin(), big.end(), 0.0f), 0.0f);
}

TEST(BandMemory, NoInitKeepsContentsWhenGrowingAndCopies) {
    using Vec = std::vector<float, NoInitAllocator<float>>;
    Vec v(1000);
    std::iota(v.begin(), v.end(), 0.0f);
    v.resize(2 * (kHugePageBytes / sizeof(float)));  // from the heap to a mapping: the values move along
    for (int i = 0; i < 1000; ++i) ASSERT_EQ(v[std::size_t(i)], float(i));
    Vec w = v;
    w.resize(5 * (kHugePageBytes / sizeof(float)));
    for (int i = 0; i < 1000; ++i) ASSERT_EQ(w[std::size_t(i)], float(i));
    w.resize(10);  // shrinking keeps the mapping until the vector goes
    w.shrink_to_fit();
    EXPECT_EQ(w.size(), 10u);
    EXPECT_EQ(w[9], 9.0f);
    Vec e(4, 7.0f);  // explicit values are still written
    for (const float x : e) EXPECT_EQ(x, 7.0f);
}
