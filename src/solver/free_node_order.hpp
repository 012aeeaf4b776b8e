// The order of a body's free nodes in its Newton matrix. Meshes come numbered in any order (the
// raptor's tets span a median of 3,877 of its 5,992 node numbers); the matrix's columns, the
// tangent's scatter and the multigrid's Gauss-Seidel sweeps follow the free order, so the free
// nodes are numbered along a Z-order (Morton) curve through their rest positions: nodes close
// in space get close numbers, whatever the file's order.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <cstdint>

namespace sh {

/// Per node of body: its index among the free nodes (is_free) in Z-order of their rest
/// positions (ties by node number), or -1; returns the free nodes' count. Allocates.
int32_t number_free_nodes(const Body& body, vec<int32_t>& index);

}  // namespace sh
