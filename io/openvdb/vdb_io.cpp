#include "io/openvdb/vdb_io.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetRebuild.h>
#include <openvdb/tools/Prune.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <mutex>
#include <string>

#include "core/errors.h"
#include "io/formats/atomic_file.h"

namespace normalflow {

namespace {

void init_openvdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

const char* kDimsKey = "normalflow_dims";
const char* kHalfWidthKey = "normalflow_half_width";

openvdb::FloatGrid::Ptr read_first_float_grid(const std::string& path, const std::string& who) {
    {
        std::FILE* f = std::fopen(path.c_str(), "rb");
        if (!f) throw IoError(who + ": cannot open (" + std::strerror(errno) + ")");
        const int c = std::fgetc(f);
        std::fclose(f);
        if (c == EOF) throw InvalidInput(who + ": empty file");
    }
    try {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        openvdb::GridBase::Ptr found;
        for (auto it = file.beginName(); it != file.endName(); ++it) {
            const openvdb::GridBase::ConstPtr meta = file.readGridMetadata(it.gridName());
            if (meta && meta->isType<openvdb::FloatGrid>()) {
                found = file.readGrid(it.gridName());
                break;
            }
        }
        file.close();
        if (!found) throw InvalidInput(who + ": no float grid in the file");
        return openvdb::gridPtrCast<openvdb::FloatGrid>(found);
    } catch (const InvalidInput&) {
        throw;
    } catch (const std::exception& e) {
        throw InvalidInput(who + ": not a valid VDB file (" + e.what() + ")");
    }
}

}  // namespace

Volume read_vdb(const std::string& path) {
    init_openvdb();
    const std::string who = "read_vdb: " + path;
    openvdb::FloatGrid::Ptr grid = read_first_float_grid(path, who);

    // Transform: linear, axis-aligned, uniform positive scale.
    const openvdb::math::Transform& xf = grid->transform();
    if (!xf.isLinear()) throw InvalidInput(who + ": grid transform is not linear");
    const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
    const double h = (xf.indexToWorld(openvdb::Vec3d(1, 0, 0)) - o)[0];
    if (!(h > 0) || !std::isfinite(h)) throw InvalidInput(who + ": grid transform has a non-positive scale");
    for (int a = 0; a < 3; ++a) {
        openvdb::Vec3d e(0, 0, 0);
        e[a] = 1;
        const openvdb::Vec3d d = xf.indexToWorld(e) - o;
        for (int b = 0; b < 3; ++b) {
            const double want = a == b ? h : 0.0;
            if (std::abs(d[b] - want) > 1e-6 * h)
                throw InvalidInput(who + ": grid transform is not an axis-aligned uniform scale (voxel " +
                                   std::to_string(a) + " axis maps to (" + std::to_string(d[0]) + ", " +
                                   std::to_string(d[1]) + ", " + std::to_string(d[2]) + "))");
        }
    }

    try {
        if (grid->getGridClass() == openvdb::GRID_FOG_VOLUME) {
            // Density, larger inside: negate so inside is below the iso-value, then rebuild.
            openvdb::FloatGrid::Ptr neg = grid->deepCopy();
            for (auto it = neg->beginValueAll(); it; ++it) it.setValue(-*it);
            grid = openvdb::tools::levelSetRebuild(*neg, -0.5f, 3.0f, 3.0f, &xf);
        }
        grid->tree().voxelizeActiveTiles();
    } catch (const std::exception& e) {
        throw InvalidInput(who + ": cannot convert the grid (" + e.what() + ")");
    }

    const float background = grid->background();
    if (!(background > 0) || !std::isfinite(background))
        throw InvalidInput(who + ": background " + std::to_string(background) + " is not positive (not a level set?)");

    // Extent.
    openvdb::CoordBBox bb;
    bool have_dims = false;
    if (const auto meta = grid->getMetadata<openvdb::Vec3IMetadata>(kDimsKey)) {
        const openvdb::Vec3i d = meta->value();
        if (d[0] > 0 && d[1] > 0 && d[2] > 0) {
            bb = openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(d[0] - 1, d[1] - 1, d[2] - 1));
            have_dims = true;
        }
    }
    if (!have_dims) {
        grid->tree().evalLeafBoundingBox(bb);
        openvdb::CoordBBox active;
        if (grid->tree().evalActiveVoxelBoundingBox(active)) bb.expand(active);
        if (bb.empty()) throw InvalidInput(who + ": the float grid is empty (no leaves, no active values)");
        for (int a = 0; a < 3; ++a) bb.min()[a] = (bb.min()[a] >> kBlockLog2) << kBlockLog2;
    }
    Grid g;
    std::uint64_t blocks = 1;
    for (int a = 0; a < 3; ++a) {
        const std::int64_t n = std::int64_t(bb.max()[a]) - bb.min()[a] + 1;
        if (n < 1 || n > (std::int64_t(1) << 30))
            throw InvalidInput(who + ": grid extent " + std::to_string(n) + " along axis " + std::to_string(a) + " is too large");
        g.dims[a] = int(n);
        blocks *= std::uint64_t((n + kBlockDim - 1) / kBlockDim);
    }
    if (blocks > (std::uint64_t(1) << 31))
        throw InvalidInput(who + ": grid extent of " + std::to_string(blocks) + " blocks is too large");
    const openvdb::Vec3d wo = xf.indexToWorld(bb.min());
    g.origin = {wo[0], wo[1], wo[2]};
    g.voxel_size = h;

    Volume vol(g, float(background / h));
    vol.background = background;
    const openvdb::Coord mn = bb.min();
    for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf) {
        const openvdb::Coord lo = leaf->origin() - mn;
        const int bi = lo[0] >> kBlockLog2, bj = lo[1] >> kBlockLog2, bk = lo[2] >> kBlockLog2;
        if (bi < 0 || bj < 0 || bk < 0 || bi >= vol.block_dims[0] || bj >= vol.block_dims[1] || bk >= vol.block_dims[2])
            continue;  // outside the recorded extent
        const std::int32_t b = vol.allocate_block(bi, bj, bk);
        float* dst = vol.block_values(b);
        for (openvdb::Index n = 0; n < openvdb::FloatTree::LeafNodeType::SIZE; ++n) {
            const float x = leaf->getValue(n);
            if (!std::isfinite(x))
                {
                const openvdb::Coord c = leaf->offsetToGlobalCoord(n);
                throw InvalidInput(who + ": value at voxel (" + std::to_string(c[0]) + ", " + std::to_string(c[1]) +
                                   ", " + std::to_string(c[2]) + ") is not finite");
            }
            const openvdb::Coord l = openvdb::FloatTree::LeafNodeType::offsetToLocalCoord(n);
            dst[Volume::local_index(l[0], l[1], l[2])] = x;
        }
    }
    const auto acc = grid->getConstAccessor();
    for (int bk = 0; bk < vol.block_dims[2]; ++bk)
        for (int bj = 0; bj < vol.block_dims[1]; ++bj)
            for (int bi = 0; bi < vol.block_dims[0]; ++bi) {
                std::int32_t& slot = vol.block_table[vol.table_index(bi, bj, bk)];
                if (slot >= 0) continue;
                const float x = acc.getValue(mn + openvdb::Coord(bi * kBlockDim, bj * kBlockDim, bk * kBlockDim));
                slot = x < 0 ? kBlockInside : kBlockOutside;
            }
    return vol;
}

void write_vdb(const std::string& path, const Volume& v) {
    init_openvdb();
    const std::string who = "write_vdb: " + path;
    const Grid& g = v.grid;
    if (g.dims[0] <= 0 || g.dims[1] <= 0 || g.dims[2] <= 0) throw InvalidInput(who + ": empty grid");
    if (!(g.voxel_size > 0) || !std::isfinite(g.voxel_size)) throw InvalidInput(who + ": voxel size is not positive");
    if (!(v.background > 0) || !std::isfinite(v.background)) throw InvalidInput(who + ": background is not positive");
    if (!is_finite(g.origin)) throw InvalidInput(who + ": grid origin is not finite");

    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(v.background);
    openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(g.voxel_size);
    xf->postTranslate(openvdb::Vec3d(g.origin.x, g.origin.y, g.origin.z));
    grid->setTransform(xf);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName("surface");
    grid->insertMeta(kDimsKey, openvdb::Vec3IMetadata(openvdb::Vec3i(g.dims[0], g.dims[1], g.dims[2])));
    grid->insertMeta(kHalfWidthKey, openvdb::FloatMetadata(v.half_width));
    auto& tree = grid->tree();
    for (std::size_t b = 0; b < v.block_count(); ++b) {
        const auto& bc = v.block_coords[b];
        const openvdb::Coord o(bc[0] * kBlockDim, bc[1] * kBlockDim, bc[2] * kBlockDim);
        auto* leaf = tree.touchLeaf(o);
        const float* src = v.block_values(std::int32_t(b));
        for (int lk = 0; lk < kBlockDim; ++lk)
            for (int lj = 0; lj < kBlockDim; ++lj)
                for (int li = 0; li < kBlockDim; ++li) {
                    const float x = src[Volume::local_index(li, lj, lk)];
                    const openvdb::Index n = openvdb::FloatTree::LeafNodeType::coordToOffset(openvdb::Coord(li, lj, lk));
                    leaf->setValueOnly(n, x);
                    leaf->setActiveState(n, std::abs(x) < v.background);
                }
    }
    for (int bk = 0; bk < v.block_dims[2]; ++bk)
        for (int bj = 0; bj < v.block_dims[1]; ++bj)
            for (int bi = 0; bi < v.block_dims[0]; ++bi)
                if (v.block_table[v.table_index(bi, bj, bk)] == kBlockInside)
                    tree.addTile(1, openvdb::Coord(bi * kBlockDim, bj * kBlockDim, bk * kBlockDim), -v.background, false);
    openvdb::tools::prune(tree);

    AtomicFile out(path, "write_vdb");
    try {
        openvdb::io::File file(out.temp_path());
        file.write(openvdb::GridPtrVec{grid});
        file.close();
    } catch (const std::exception& e) {
        throw IoError(who + ": write failed (" + e.what() + ")");
    }
    out.commit();
}

}  // namespace normalflow
