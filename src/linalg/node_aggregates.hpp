// The multigrid's aggregates: groups of neighbouring free nodes, each of which becomes one
// coarse node (its rigid motions). The greedy aggregation of Vanek, Mandel and Brezina (1996):
// a node whose neighbours are all still free founds an aggregate of itself and them; each
// node left over joins an aggregate a neighbour founded (it has one: a node the founding pass
// left over had a neighbour already taken, and every node taken then is a founder's or its
// neighbour's). An aggregate is connected by elements,
// so parts that share none (a cut, legs side by side) never share one; founders' aggregates hold
// a whole neighbourhood (in a tet mesh, a tet: never flat), about 15 nodes in the interior of a
// tet mesh.
#pragma once

#include "core/memory.hpp"
#include "linalg/block_rows.hpp"

#include <cstdint>

namespace sh {

/// Assigns each of rows' nodes its aggregate (see the file comment) into aggregate
/// (node_count entries, numbered in order of foundation); returns the aggregates' count.
/// Visits the nodes in their order, so that an order along a space-filling curve (the free
/// nodes') founds aggregates across the body in sweeps. Allocates; aggregate is overwritten
/// first.
int32_t aggregate_nodes(const BlockRows& rows, vec<int32_t>& aggregate);

}  // namespace sh
