// Tests for lib/core/volume.h: Volume::check accepts valid volumes and refuses each broken invariant
// with a message naming the caller and the problem.
#include "core/volume.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <string>

#include "core/errors.h"

namespace normalflow {
namespace {

/// 20 x 12 x 9 samples (3 x 2 x 2 blocks), two allocated blocks and one inside tile.
Volume small_volume() {
    Grid g;
    g.origin = {1, 2, 3};
    g.voxel_size = 0.5;
    g.dims = {20, 12, 9};
    Volume v(g, 3.0f);
    v.set(0, 0, 0, -0.25f);
    v.set(19, 11, 8, 0.75f);
    v.block_table[v.table_index(1, 0, 0)] = kBlockInside;
    return v;
}

template <class E>
void expect_refused(const std::function<void(Volume&)>& corrupt, const std::string& expected) {
    Volume v = small_volume();
    corrupt(v);
    try {
        v.check("who");
        FAIL() << "no exception, expected " << expected;
    } catch (const E& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind("who: volume ", 0), 0u) << m;
        EXPECT_NE(m.find(expected), std::string::npos) << m;
    }
}

TEST(VolumeCheck, ValidVolumesPass) {
    EXPECT_NO_THROW(small_volume().check("who"));
    Grid g;
    g.dims = {1, 1, 1};
    EXPECT_NO_THROW(Volume(g, 1.5f).check("who"));  // one sample, no block allocated
}

TEST(VolumeCheck, BadGrid) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    expect_refused<InvalidInput>([](Volume& v) { v.grid.voxel_size = 0; }, "voxel_size must be finite and > 0");
    expect_refused<InvalidInput>([&](Volume& v) { v.grid.voxel_size = nan; }, "voxel_size");
    expect_refused<InvalidInput>([](Volume& v) { v.grid.voxel_size = -1; }, "voxel_size");
    expect_refused<InvalidInput>([&](Volume& v) { v.grid.origin.y = nan; }, "origin is not finite");
    expect_refused<InvalidInput>([](Volume& v) { v.grid.dims[1] = 0; }, "dims must be >= 1, got 20 x 0 x 9");
    Volume empty;  // default: no samples at all
    EXPECT_THROW(empty.check("who"), InvalidInput);
}

TEST(VolumeCheck, BadBackgroundOrHalfWidth) {
    expect_refused<InvalidInput>([](Volume& v) { v.background = 0; }, "background must be finite and > 0");
    expect_refused<InvalidInput>([](Volume& v) { v.background = std::numeric_limits<float>::infinity(); },
                                 "background");
    expect_refused<InvalidInput>([](Volume& v) { v.half_width = -3; }, "half_width must be finite and > 0");
    expect_refused<InvalidInput>([](Volume& v) { v.half_width = std::numeric_limits<float>::quiet_NaN(); },
                                 "half_width");
}

TEST(VolumeCheck, BadBlockLayout) {
    expect_refused<InvalidInput>([](Volume& v) { v.block_dims[0] = 2; },
                                 "block_dims 2 x 2 x 2 do not match dims 20 x 12 x 9");
    expect_refused<InvalidInput>([](Volume& v) { v.block_table.pop_back(); },
                                 "block_table has 11 entries, expected 12");
    expect_refused<InvalidInput>([](Volume& v) { v.values.resize(v.values.size() - 1); },
                                 "values has 1023 samples, expected 512 per block");
    expect_refused<InvalidInput>(
        [](Volume& v) {
            v.block_coords[1] = {3, 0, 0};
        },
        "block 1 has coordinates (3, 0, 0) outside");
    expect_refused<InvalidInput>(
        [](Volume& v) {
            v.block_coords[1] = {0, -1, 0};
        },
        "block 1 has coordinates (0, -1, 0)");
    // Two blocks swapped in the table.
    expect_refused<InvalidInput>(
        [](Volume& v) {
            v.block_table[v.table_index(0, 0, 0)] = 1;
            v.block_table[v.table_index(2, 1, 1)] = 0;
        },
        "block 0 does not match its block_table entry");
    // A table entry outside [0, block count) that is not a tile code.
    expect_refused<InvalidInput>([](Volume& v) { v.block_table[v.table_index(0, 1, 0)] = 2; },
                                 "block_table entry 3 is 2, expected a block index < 2 or a tile code (-1, -2)");
    expect_refused<InvalidInput>([](Volume& v) { v.block_table[v.table_index(0, 1, 0)] = -7; },
                                 "block_table entry 3 is -7");
    // A second table entry pointing at an allocated block.
    expect_refused<InvalidInput>([](Volume& v) { v.block_table[v.table_index(0, 1, 0)] = 1; },
                                 "block_table refers to 3 blocks, but 2 are allocated");
}

TEST(VolumeCheck, NonFiniteSampleIsANumericalError) {
    expect_refused<NumericalError>([](Volume& v) { v.values[512 + 7] = std::numeric_limits<float>::quiet_NaN(); },
                                   "sample 7 of block 1 is NaN or infinite");
    expect_refused<NumericalError>([](Volume& v) { v.values[3] = -std::numeric_limits<float>::infinity(); },
                                   "sample 3 of block 0 is NaN or infinite");
}

}  // namespace
}  // namespace normalflow
