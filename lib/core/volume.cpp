#include "core/volume.h"

#include <cmath>
#include <string>

#include "core/errors.h"

namespace normalflow {

namespace {

std::string dims_text(const std::array<int, 3>& d) {
    return std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " + std::to_string(d[2]);
}

}  // namespace

void Volume::check(std::string_view who) const {
    auto bad = [&](const std::string& what) { throw InvalidInput(std::string(who) + ": volume " + what); };
    if (!(grid.voxel_size > 0.0) || !std::isfinite(grid.voxel_size))
        bad("voxel_size must be finite and > 0, got " + std::to_string(grid.voxel_size));
    if (!is_finite(grid.origin)) bad("origin is not finite");
    {
        const Placement& pl = grid.placement;
        bool ok = is_finite(pl.translation);
        for (int a = 0; a < 3 && ok; ++a)
            for (int b = 0; b < 3 && ok; ++b)
                ok = is_finite(pl.rotation[a]) &&
                     std::abs(dot(pl.rotation[a], pl.rotation[b]) - (a == b ? 1.0 : 0.0)) <= 1e-6;
        if (!ok) bad("placement is not a finite rotation (orthonormal columns) and translation");
    }
    for (int a = 0; a < 3; ++a)
        if (grid.dims[a] < 1) bad("dims must be >= 1, got " + dims_text(grid.dims));
    if (!(background > 0.0f) || !std::isfinite(background))
        bad("background must be finite and > 0, got " + std::to_string(background));
    if (!(half_width > 0.0f) || !std::isfinite(half_width))
        bad("half_width must be finite and > 0 voxels, got " + std::to_string(half_width));
    for (int a = 0; a < 3; ++a)
        if (block_dims[a] != (grid.dims[a] + kBlockDim - 1) / kBlockDim)
            bad("block_dims " + dims_text(block_dims) + " do not match dims " + dims_text(grid.dims));
    const std::size_t table = std::size_t(block_dims[0]) * std::size_t(block_dims[1]) * std::size_t(block_dims[2]);
    if (block_table.size() != table)
        bad("block_table has " + std::to_string(block_table.size()) + " entries, expected " + std::to_string(table));
    if (values.size() != block_coords.size() * kBlockVoxels)
        bad("values has " + std::to_string(values.size()) + " samples, expected 512 per block (" +
            std::to_string(block_coords.size()) + " blocks)");
    for (std::size_t b = 0; b < block_coords.size(); ++b) {
        const auto& c = block_coords[b];
        if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= block_dims[0] || c[1] >= block_dims[1] || c[2] >= block_dims[2])
            bad("block " + std::to_string(b) + " has coordinates (" + std::to_string(c[0]) + ", " +
                std::to_string(c[1]) + ", " + std::to_string(c[2]) + ") outside block_dims " + dims_text(block_dims));
        if (block_table[table_index(c[0], c[1], c[2])] != std::int32_t(b))
            bad("block " + std::to_string(b) + " does not match its block_table entry");
    }
    // Every allocated entry was matched above by exactly one block iff the counts agree.
    std::size_t allocated = 0;
    for (std::size_t t = 0; t < block_table.size(); ++t) {
        const std::int32_t e = block_table[t];
        if (e >= 0 && std::size_t(e) < block_coords.size())
            ++allocated;
        else if (e != kBlockOutside && e != kBlockInside)
            bad("block_table entry " + std::to_string(t) + " is " + std::to_string(e) + ", expected a block index < " +
                std::to_string(block_coords.size()) + " or a tile code (" + std::to_string(kBlockOutside) + ", " +
                std::to_string(kBlockInside) + ")");
    }
    if (allocated != block_coords.size())
        bad("block_table refers to " + std::to_string(allocated) + " blocks, but " +
            std::to_string(block_coords.size()) + " are allocated");
    for (std::size_t i = 0; i < values.size(); ++i)
        if (!std::isfinite(values[i]))
            throw NumericalError(std::string(who) + ": volume sample " + std::to_string(i % kBlockVoxels) +
                                 " of block " + std::to_string(i / kBlockVoxels) + " is NaN or infinite");
}

}  // namespace normalflow
