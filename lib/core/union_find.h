#pragma once
/// \file union_find.h
/// Disjoint sets over 0..n-1 with path halving; the smaller index becomes the root, so the
/// representatives (and anything ordered by them) do not depend on the order of the unions.

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace normalflow::detail {

template <class Index>
struct UnionFind {
    std::vector<Index> parent;
    explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), Index(0)); }
    Index find(Index x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    }
    void unite(Index a, Index b) {
        a = find(a);
        b = find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
};

}  // namespace normalflow::detail
