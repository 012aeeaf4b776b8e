// Disjoint sets over the indices of a parent array (union-find, halving each path it walks): the
// connected parts of a cut node's star, of bodies in contact, of the fine nodes a coarse grid
// node holds. parent[i] == i marks a root; start with every index its own.
#pragma once

#include "core/memory.hpp"

#include <cstddef>

namespace sh {

/// The root of i's set, halving the path from i on the way.
template <class Index>
Index union_root(vec<Index>& parent, Index i) {
    while (parent[static_cast<size_t>(i)] != i) {
        Index& up = parent[static_cast<size_t>(i)];
        up = parent[static_cast<size_t>(up)];
        i = up;
    }
    return i;
}

/// Joins the sets of a and b (b's root becomes the root of both).
template <class Index>
void union_join(vec<Index>& parent, Index a, Index b) {
    parent[static_cast<size_t>(union_root(parent, a))] = union_root(parent, b);
}

}  // namespace sh
