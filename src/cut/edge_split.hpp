// Splitting a tet along some of its edges: the one operation both the cut and the refinement
// ahead of it make meshes with.
#pragma once

#include "core/memory.hpp"

#include <array>
#include <cstdint>

namespace sh {

/// An edge (its end nodes lo and hi) split at a new node, middle.
struct EdgeSplit {
    int32_t lo, hi, middle;
};

/// Splits tet along splits[0..count) (edges of tet, in that order), each split halving every
/// piece made so far that has the edge; appends the pieces to pieces (4 nodes each, oriented
/// as tet is), tet's own first. Tets that share an edge stay conforming when every one of
/// them is split along its edges in one global order.
void split_tet(const int32_t tet[4], const EdgeSplit* splits, int count, vec<std::array<int32_t, 4>>& pieces);

}  // namespace sh
