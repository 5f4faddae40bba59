#include "io/openvdb/vdb_io.h"
#include "io/openvdb/vdb_adapters.h"

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetRebuild.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/ValueAccessor.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <new>
#include <string>
#include <vector>

#include <sys/resource.h>
#include <unistd.h>

#include "core/errors.h"
#include "io/util/atomic_file.h"
#include "io/util/isolate.h"
#include "sdf/image_to_volume.h"

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
        // Read through our own stream with exceptions on: the first read past the end of a truncated
        // or corrupt file throws at once. (io::File's own stream does not, and OpenVDB then keeps
        // going with stale length fields: a 4 KB fuzz input looped through gigabytes of allocations.)
        std::ifstream in(path, std::ios::binary);
        if (!in) throw IoError(who + ": cannot open (" + std::strerror(errno) + ")");
        in.exceptions(std::ios::failbit | std::ios::badbit);
        openvdb::io::Stream stream(in, /*delayLoad=*/false);
        openvdb::GridBase::Ptr found;
        if (const openvdb::GridPtrVecPtr grids = stream.getGrids())
            for (const openvdb::GridBase::Ptr& g : *grids)
                if (g && g->isType<openvdb::FloatGrid>()) {
                    found = g;
                    break;
                }
        if (!found) throw InvalidInput(who + ": no float grid in the file");
        return openvdb::gridPtrCast<openvdb::FloatGrid>(found);
    } catch (const InvalidInput&) {
        throw;
    } catch (const IoError&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw;  // the caller says how much was allowed
    } catch (const std::exception& e) {
        throw InvalidInput(who + ": not a valid VDB file (" + e.what() + ")");
    }
}

/// The frame of a linear transform with a uniform scale h: the world directions of its index axes.
struct Frame {
    double h = 0;
    std::array<Vec3d, 3> rotation{};  ///< unit columns
    Vec3d origin;                     ///< world position of index (0, 0, 0)
};

/// Checks that xf is linear with a uniform positive scale and orthogonal axes (any rotation or reflection);
/// returns its frame.
Frame check_transform(const openvdb::math::Transform& xf, const std::string& who) {
    if (!xf.isLinear()) throw InvalidInput(who + ": grid transform is not linear");
    const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
    if (!is_finite(Vec3d{o[0], o[1], o[2]})) throw InvalidInput(who + ": grid transform has a non-finite origin");
    Frame f;
    f.origin = {o[0], o[1], o[2]};
    std::array<Vec3d, 3> d{};
    for (int a = 0; a < 3; ++a) {
        openvdb::Vec3d e(0, 0, 0);
        e[a] = 1;
        const openvdb::Vec3d w = xf.indexToWorld(e) - o;
        d[a] = {w[0], w[1], w[2]};
    }
    f.h = norm(d[0]);
    if (!(f.h > 0) || !std::isfinite(f.h)) throw InvalidInput(who + ": grid transform has a non-positive scale");
    for (int a = 0; a < 3; ++a) {
        if (!is_finite(d[a]) || std::abs(norm(d[a]) - f.h) > 1e-6 * f.h)
            throw InvalidInput(who + ": grid transform is not a uniform scale (voxel axis " + std::to_string(a) +
                               " has length " + std::to_string(norm(d[a])) + ", axis 0 " + std::to_string(f.h) + ")");
        for (int b = 0; b < a; ++b)
            if (std::abs(dot(d[a], d[b])) > 1e-6 * f.h * f.h)
                throw InvalidInput(who + ": grid transform is sheared (voxel axes " + std::to_string(b) + " and " +
                                   std::to_string(a) + " are not orthogonal)");
    }
    f.rotation = placement_from_axes(d, f.origin).rotation;  // orthonormal to rounding
    return f;
}

/// A linear transform: index (i, j, k) to origin + h · (i R0 + j R1 + k R2).
openvdb::math::Transform::Ptr make_transform(double h, const std::array<Vec3d, 3>& rotation, const Vec3d& origin) {
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();  // row vectors: world = index · m
    for (int a = 0; a < 3; ++a) {
        m(a, 0) = h * rotation[a].x;
        m(a, 1) = h * rotation[a].y;
        m(a, 2) = h * rotation[a].z;
    }
    m(3, 0) = origin.x;
    m(3, 1) = origin.y;
    m(3, 2) = origin.z;
    return openvdb::math::Transform::createLinearTransform(m);
}

/// The transform of a grid: index (i, j, k) at placement.point(origin + h · (i, j, k)).
openvdb::math::Transform::Ptr to_openvdb_transform(const Grid& g) {
    if (g.placement.is_identity()) {
        openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(g.voxel_size);
        xf->postTranslate(openvdb::Vec3d(g.origin.x, g.origin.y, g.origin.z));
        return xf;
    }
    return make_transform(g.voxel_size, g.placement.rotation, g.placement.point(g.origin));
}

bool axis_aligned(const std::array<Vec3d, 3>& r) {
    return norm(r[0] - Vec3d{1, 0, 0}) < 1e-9 && norm(r[1] - Vec3d{0, 1, 0}) < 1e-9 &&
           norm(r[2] - Vec3d{0, 0, 1}) < 1e-9;
}

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

/// Bytes of this process's data segment and private mappings (VmData), 0 if unknown.
std::uint64_t data_segment_bytes() {
    std::ifstream in("/proc/self/status");
    std::string key;
    while (in >> key) {
        if (key == "VmData:") {
            std::uint64_t kib = 0;
            in >> kib;
            return kib * 1024;
        }
        in.ignore(1 << 20, '\n');
    }
    return 0;
}

}  // namespace
}  // namespace normalflow

// Set only when a sanitizer runtime is linked (weak: null otherwise); <sanitizer/allocator_interface.h>
// is not shipped with GCC.
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*, std::size_t),
                                                         void (*free_hook)(const volatile void*)) __attribute__((weak));
extern "C" std::size_t __sanitizer_get_allocated_size(const volatile void* p) __attribute__((weak));

namespace normalflow {
namespace {

/// Exit status of the isolated .vdb child that went over its heap cap under AddressSanitizer.
constexpr int kHeapCapExit = 86;
std::uint64_t g_heap_cap = 0;   // the child's cap under ASan, bytes (0: none)
std::uint64_t g_heap_live = 0;  // bytes allocated and not freed since the hooks went in (child only)

void heap_cap_malloc_hook(const volatile void*, std::size_t size) {
    g_heap_live += size;
    if (g_heap_cap && g_heap_live > g_heap_cap) ::_exit(kHeapCapExit);  // allocates nothing
}
void heap_cap_free_hook(const volatile void* p) {  // installed only where the runtime has the function
    g_heap_live -= std::min<std::uint64_t>(g_heap_live, __sanitizer_get_allocated_size(p));
}

/// Caps the heap of the isolated child that reads a .vdb. A corrupt file can state a string length of
/// gigabytes, which OpenVDB allocates before it notices that the file is short (a 4 KB fuzz input made
/// it take 5 GB and 26 s); no real file of `file_bytes` bytes needs more than about 64 times its size
/// plus the tree's fixed node overhead. Normally RLIMIT_DATA (allocations fail: std::bad_alloc).
/// Under AddressSanitizer, whose shadow memory RLIMIT_DATA would count, the child counts the bytes it
/// allocates instead (sanitizer malloc hooks) and leaves with status 86 when they exceed the cap (a
/// fuzz input made the instrumented child allocate for 15 s without it).
std::uint64_t cap_child_heap(std::uint64_t file_bytes) {
    const std::uint64_t budget = (std::uint64_t(512) << 20) + 64 * file_bytes;
    if (kAddressSanitizer) {
        if (!__sanitizer_install_malloc_and_free_hooks || !__sanitizer_get_allocated_size) return 0;
        g_heap_cap = budget;
        g_heap_live = 0;
        return __sanitizer_install_malloc_and_free_hooks(heap_cap_malloc_hook, heap_cap_free_hook) ? budget : 0;
    }
    const std::uint64_t limit = data_segment_bytes() + budget;
    const rlimit rl{limit, limit};
    return setrlimit(RLIMIT_DATA, &rl) == 0 ? limit : 0;
}

using LeafT = openvdb::FloatTree::LeafNodeType;

/// One tile of the tree above the leaves (level 1..3), as the child ships it.
struct Tile {
    std::int32_t level, x, y, z;
    float value;
    std::uint32_t active;
};

/// Reads the first float grid of the file in a forked child (io/util/isolate.h), so that a crash or
/// undefined behaviour inside OpenVDB's reader on a corrupt file becomes an IoError (fuzz finding
/// vdb-9f74bbba), and rebuilds it here from plain arrays: transform (checked in the child), class,
/// background, normalflow_dims metadata, tiles that differ from inactive background, and leaves.
/// The child runs single-threaded code only (file reading and iteration, no TBB algorithms).
/// (A grid that fails half-way through reading is freed in the child; Tree::clear then runs a
/// tbb::parallel_for there, which the calling thread completes alone.)
openvdb::FloatGrid::Ptr read_grid_isolated(const std::string& path, const std::string& who) {
    const std::string bytes = run_isolated(who, [&] {
        // Deliberately never freed: the child ends with _exit, and Tree's destructor frees nodes with
        // tbb::parallel_for, which must not run in a forked child.
        std::error_code ec;
        const std::uint64_t cap = isolation_disabled() ? 0 : cap_child_heap(std::filesystem::file_size(path, ec));
        const openvdb::FloatGrid::Ptr* keep = nullptr;
        try {
            keep = new openvdb::FloatGrid::Ptr(read_first_float_grid(path, who));
        } catch (const std::bad_alloc&) {
            if (cap == 0) throw;
            throw InvalidInput(who + ": not a valid VDB file (reading it needs more than " + std::to_string(cap >> 20) +
                               " MiB, far more than a file of this size can hold)");
        }
        const openvdb::FloatGrid::Ptr& grid = *keep;
        const Frame frame = check_transform(grid->transform(), who);
        ByteWriter w;
        w.put(frame.h);
        w.put(frame.origin);
        w.put(frame.rotation);
        w.put(std::int32_t(grid->getGridClass()));
        const float background = grid->background();
        w.put(background);
        openvdb::Vec3i dims(0, 0, 0);
        if (const auto meta = grid->getMetadata<openvdb::Vec3IMetadata>(kDimsKey)) dims = meta->value();
        w.put(std::array<std::int32_t, 3>{dims[0], dims[1], dims[2]});
        std::vector<Tile> tiles;
        auto it = grid->tree().cbeginValueAll();
        it.setMaxDepth(openvdb::FloatTree::ValueAllCIter::LEAF_DEPTH - 1);  // tiles only, no leaf voxels
        for (; it; ++it) {
            const bool on = it.isValueOn();
            const float v = *it;
            if (!on && (v == background || (std::isnan(v) && std::isnan(background)))) continue;
            const openvdb::Coord c = it.getCoord();
            tiles.push_back({std::int32_t(it.getLevel()), c[0], c[1], c[2], v, on ? 1u : 0u});
        }
        w.put_array(tiles);
        std::vector<std::array<std::int32_t, 3>> origins;
        std::vector<float> values;
        std::vector<std::uint64_t> masks;
        for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf) {
            const openvdb::Coord c = leaf->origin();
            origins.push_back({c[0], c[1], c[2]});
            const float* v = leaf->buffer().data();
            if (!v) throw InvalidInput(who + ": a leaf has no data");
            values.insert(values.end(), v, v + LeafT::SIZE);
            const auto& mask = leaf->getValueMask();
            for (openvdb::Index word = 0; word < LeafT::NodeMaskType::WORD_COUNT; ++word)
                masks.push_back(mask.template getWord<std::uint64_t>(word));
        }
        w.put_array(origins);
        w.put_array(values);
        w.put_array(masks);
        return w.take();
    });

    ByteReader r(bytes, who);
    const auto h = r.get<double>();
    const auto o = r.get<Vec3d>();
    const auto rotation = r.get<std::array<Vec3d, 3>>();
    const auto cls = r.get<std::int32_t>();
    const auto background = r.get<float>();
    const auto dims = r.get<std::array<std::int32_t, 3>>();
    const auto tiles = r.get_array<Tile>();
    const auto origins = r.get_array<std::array<std::int32_t, 3>>();
    const auto values = r.get_array<float>();
    const auto masks = r.get_array<std::uint64_t>();
    constexpr std::size_t kWords = LeafT::NodeMaskType::WORD_COUNT;
    if (values.size() != origins.size() * LeafT::SIZE || masks.size() != origins.size() * kWords)
        throw IoError(who + ": the isolated process sent inconsistent leaf data");

    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
    grid->setTransform(make_transform(h, rotation, o));
    grid->setGridClass(cls >= 0 && cls < openvdb::NUM_GRID_CLASSES ? openvdb::GridClass(cls) : openvdb::GRID_UNKNOWN);
    if (dims[0] != 0 || dims[1] != 0 || dims[2] != 0)
        grid->insertMeta(kDimsKey, openvdb::Vec3IMetadata(openvdb::Vec3i(dims[0], dims[1], dims[2])));
    auto& tree = grid->tree();
    for (const Tile& t : tiles) {
        if (t.level < 1 || t.level > int(openvdb::FloatTree::RootNodeType::LEVEL))
            throw IoError(who + ": the isolated process sent a tile at level " + std::to_string(t.level));
        tree.addTile(openvdb::Index(t.level), openvdb::Coord(t.x, t.y, t.z), t.value, t.active != 0);
    }
    for (std::size_t l = 0; l < origins.size(); ++l) {
        LeafT* leaf = tree.touchLeaf(openvdb::Coord(origins[l][0], origins[l][1], origins[l][2]));
        LeafT::NodeMaskType mask;
        for (openvdb::Index n = 0; n < LeafT::SIZE; ++n) {
            leaf->setValueOnly(n, values[l * LeafT::SIZE + n]);
            if ((masks[l * kWords + n / 64] >> (n % 64)) & 1u) mask.setOn(n);
        }
        leaf->setValueMask(mask);
    }
    return grid;
}

}  // namespace

namespace {

/// from_openvdb on a grid it may change (tiles voxelized, a fog volume replaced by its level set).
Volume volume_from_grid(openvdb::FloatGrid::Ptr grid, const std::string& who) {
    // A copy: the fog branch below replaces grid.
    const openvdb::math::Transform xf = grid->transform();
    const Frame frame = check_transform(xf, who);
    const double h = frame.h;

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
            throw InvalidInput(who + ": grid extent " + std::to_string(n) + " along axis " + std::to_string(a) +
                               " is too large");
        g.dims[a] = int(n);
        blocks *= std::uint64_t((n + kBlockDim - 1) / kBlockDim);
    }
    if (blocks > (std::uint64_t(1) << 31))
        throw InvalidInput(who + ": grid extent of " + std::to_string(blocks) + " blocks is too large");
    if (axis_aligned(frame.rotation)) {
        const openvdb::Vec3d wo = xf.indexToWorld(bb.min());
        g.origin = {wo[0], wo[1], wo[2]};
    } else {
        // the grid's frame: index (0, 0, 0) at its origin, the transform's axes as the placement
        g.origin = Vec3d{double(bb.min()[0]), double(bb.min()[1]), double(bb.min()[2])} * h;
        g.placement.rotation = frame.rotation;
        g.placement.translation = frame.origin;
    }
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
            if (!std::isfinite(x)) {
                const openvdb::Coord c = leaf->offsetToGlobalCoord(n);
                throw InvalidInput(who + ": value at voxel (" + std::to_string(c[0]) + ", " + std::to_string(c[1]) +
                                   ", " + std::to_string(c[2]) + ") is not finite");
            }
            const openvdb::Coord l = openvdb::FloatTree::LeafNodeType::offsetToLocalCoord(n);
            dst[Volume::local_index(l[0], l[1], l[2])] = x;
        }
    }
    // An unregistered accessor (IsSafe = false): registering one in the tree's accessor registry makes
    // the tree's destructor iterate oneTBB's concurrent_hash_map, whose iterator has undefined
    // behaviour (misaligned downcast of its rehash flag; oneTBB issues #908, #1601) that UBSan reports.
    const openvdb::tree::ValueAccessor<const openvdb::FloatTree, /*IsSafe=*/false> acc(grid->tree());
    for (int bk = 0; bk < vol.block_dims[2]; ++bk)
        for (int bj = 0; bj < vol.block_dims[1]; ++bj)
            for (int bi = 0; bi < vol.block_dims[0]; ++bi) {
                std::int32_t& slot = vol.block_table[vol.table_index(bi, bj, bk)];
                if (slot >= 0) continue;
                const float x = acc.getValue(mn + openvdb::Coord(bi * kBlockDim, bj * kBlockDim, bk * kBlockDim));
                slot = x < 0 ? kBlockInside : kBlockOutside;
            }
    vol.check(who);
    return vol;
}

}  // namespace

Volume from_openvdb(const openvdb::FloatGrid& grid, const std::string& who) {
    init_openvdb();
    return volume_from_grid(grid.deepCopy(), who);
}

Volume read_vdb(const std::string& path) {
    init_openvdb();
    const std::string who = "read_vdb: " + path;
    return volume_from_grid(read_grid_isolated(path, who), who);  // its transform checked in the child too
}

namespace {

/// The level set of v (checked by the caller).
openvdb::FloatGrid::Ptr grid_from_volume(const Volume& v) {
    const Grid& g = v.grid;
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(v.background);
    grid->setTransform(to_openvdb_transform(g));
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
                    const openvdb::Index n =
                        openvdb::FloatTree::LeafNodeType::coordToOffset(openvdb::Coord(li, lj, lk));
                    leaf->setValueOnly(n, x);
                    leaf->setActiveState(n, std::abs(x) < v.background);
                }
    }
    for (int bk = 0; bk < v.block_dims[2]; ++bk)
        for (int bj = 0; bj < v.block_dims[1]; ++bj)
            for (int bi = 0; bi < v.block_dims[0]; ++bi)
                if (v.block_table[v.table_index(bi, bj, bk)] == kBlockInside)
                    tree.addTile(1, openvdb::Coord(bi * kBlockDim, bj * kBlockDim, bk * kBlockDim), -v.background,
                                 false);
    openvdb::tools::prune(tree);
    return grid;
}

/// Checks that a normal map lies on v's grid and passes Volume::check.
void check_normal_map(const NormalMap& normals, const Volume& v, const std::string& who) {
    for (const Volume& c : normals) {
        c.check(who + ": normal map");
        if (c.grid.dims != v.grid.dims || c.grid.voxel_size != v.grid.voxel_size || !(c.grid.origin == v.grid.origin))
            throw InvalidInput(who + ": the normal map is not on the volume's grid");
    }
}

/// The normal map as a vector grid (checked by the caller).
openvdb::Vec3SGrid::Ptr grid_from_normals(const NormalMap& normals, const Volume& v) {
    const Grid& g = v.grid;
    // Unit vectors in world space where the engine defined them, active there; v's transform.
    openvdb::Vec3SGrid::Ptr ng = openvdb::Vec3SGrid::create(openvdb::Vec3f(0, 0, 0));
    ng->setTransform(to_openvdb_transform(g));
    ng->setName("normals");
    ng->setVectorType(openvdb::VEC_COVARIANT_NORMALIZE);
    ng->setIsInWorldSpace(true);
    auto acc = ng->getAccessor();
    const Volume& nx = normals[0];
    for (std::size_t b = 0; b < nx.block_count(); ++b) {
        const auto& bc = nx.block_coords[b];
        for (int lk = 0; lk < kBlockDim; ++lk)
            for (int lj = 0; lj < kBlockDim; ++lj)
                for (int li = 0; li < kBlockDim; ++li) {
                    const int i = bc[0] * kBlockDim + li, j = bc[1] * kBlockDim + lj, k = bc[2] * kBlockDim + lk;
                    const Vec3d n{nx.value(i, j, k), normals[1].value(i, j, k), normals[2].value(i, j, k)};
                    if (n.x == kNoNormal || n.y == kNoNormal || n.z == kNoNormal || !g.contains(i, j, k)) continue;
                    const Vec3d w = g.placement.direction(n);
                    acc.setValueOn(openvdb::Coord(i, j, k), openvdb::Vec3f(float(w.x), float(w.y), float(w.z)));
                }
    }
    return ng;
}

}  // namespace

openvdb::FloatGrid::Ptr to_openvdb(const Volume& v) {
    init_openvdb();
    v.check("to_openvdb");
    return grid_from_volume(v);
}

openvdb::Vec3SGrid::Ptr to_openvdb(const NormalMap& normals, const Volume& v) {
    init_openvdb();
    v.check("to_openvdb");
    check_normal_map(normals, v, "to_openvdb");
    return grid_from_normals(normals, v);
}

void write_vdb(const std::string& path, const Volume& v, const NormalMap* normals) {
    init_openvdb();
    const std::string who = "write_vdb: " + path;
    v.check(who);
    if (normals) check_normal_map(*normals, v, who);
    openvdb::GridPtrVec grids{grid_from_volume(v)};
    if (normals) grids.push_back(grid_from_normals(*normals, v));

    AtomicFile out(path, "write_vdb");
    try {
        openvdb::io::File file(out.temp_path());
        file.write(grids);
        file.close();
    } catch (const std::exception& e) {
        throw IoError(who + ": write failed (" + e.what() + ")");
    }
    out.commit();
}

}  // namespace normalflow
