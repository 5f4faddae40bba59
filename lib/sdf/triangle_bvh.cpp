#include "sdf/triangle_bvh.h"

#include <algorithm>
#include <string>

#include <tbb/task_group.h>

#include "core/errors.h"

namespace normalflow::detail {
namespace {

/// A triangle as the split sees it: its centroid beside its index, so that the median search and the centroid
/// bounds read contiguous memory (an index into a separate centroid array made each comparison a cache miss: 3.1 s
/// for a 5.1 M-face extraction).
struct Item {
    Vec3d centroid;
    std::uint32_t triangle;
};

struct Builder {
    std::vector<BvhNode>& nodes;
    std::vector<std::uint32_t>& order;
    std::vector<Item>& items;
    const std::vector<Vec3d>& lo;
    const std::vector<Vec3d>& hi;
    std::size_t leaf;

    // Number of nodes a subtree over n triangles uses (splits are always at n / 2).
    std::size_t count_nodes(std::size_t n) const {
        return n <= leaf ? 1 : 1 + count_nodes(n / 2) + count_nodes(n - n / 2);
    }

    void build(std::size_t node, std::size_t begin, std::size_t end) {
        BvhNode& nd = nodes[node];
        const std::size_t n = end - begin;
        if (n <= leaf) {
            Vec3d blo{1e300, 1e300, 1e300}, bhi{-1e300, -1e300, -1e300};
            for (std::size_t i = begin; i < end; ++i) {
                const std::uint32_t t = items[i].triangle;
                order[i] = t;
                blo = cwise_min(blo, lo[t]);
                bhi = cwise_max(bhi, hi[t]);
            }
            nd.lo = blo;
            nd.hi = bhi;
            nd.first = std::uint32_t(begin);
            nd.count = std::uint32_t(n);
            return;
        }
        Vec3d clo{1e300, 1e300, 1e300}, chi{-1e300, -1e300, -1e300};
        for (std::size_t i = begin; i < end; ++i) {
            clo = cwise_min(clo, items[i].centroid);
            chi = cwise_max(chi, items[i].centroid);
        }
        const Vec3d ext = chi - clo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const std::size_t mid = begin + n / 2;
        std::nth_element(items.begin() + std::ptrdiff_t(begin), items.begin() + std::ptrdiff_t(mid),
                         items.begin() + std::ptrdiff_t(end), [&](const Item& a, const Item& b) {
                             const double ca = a.centroid[axis], cb = b.centroid[axis];
                             return ca < cb || (ca == cb && a.triangle < b.triangle);
                         });
        const std::size_t left = node + 1;
        const std::size_t right = left + count_nodes(n / 2);
        nd.count = 0;
        nd.first = std::uint32_t(right);
        if (n > 20000) {
            tbb::task_group g;
            g.run([&] { build(left, begin, mid); });
            build(right, mid, end);
            g.wait();
        } else {
            build(left, begin, mid);
            build(right, mid, end);
        }
        // the box of the triangles below: the children's
        nd.lo = cwise_min(nodes[left].lo, nodes[right].lo);
        nd.hi = cwise_max(nodes[left].hi, nodes[right].hi);
    }
};

}  // namespace

void TriangleBvh::build(const Mesh& m, int leaf_size) {
    const std::size_t nf = m.triangles.size();
    std::vector<Vec3d> lo(nf), hi(nf);
    std::vector<Item> items(nf);
    for (std::size_t f = 0; f < nf; ++f) {
        const Tri& t = m.triangles[f];
        const Vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        lo[f] = cwise_min(a, cwise_min(b, c));
        hi[f] = cwise_max(a, cwise_max(b, c));
        items[f] = {(a + b + c) / 3.0, std::uint32_t(f)};
    }
    order.resize(nf);
    nodes.clear();
    if (nf == 0) return;
    Builder b{nodes, order, items, lo, hi, std::size_t(std::max(1, leaf_size))};
    nodes.resize(b.count_nodes(nf));
    b.build(0, 0, nf);
}

}  // namespace normalflow::detail
