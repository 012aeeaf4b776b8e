// A symmetric SparseSystem's 3x3 node blocks row by row, both triangles: the form the
// multigrid's setup reads (a node's neighbours for the aggregates, a row's blocks for the
// coarse matrix). The stored upper triangle (UpperBlocks) gives each block once; a row's walk over
// its neighbours needs the lower ones too, so this copies them out once per setup.
#pragma once

#include "core/memory.hpp"
#include "linalg/sparse_system.hpp"
#include "linalg/upper_blocks.hpp"

#include <Eigen/Dense>

#include <cstdint>

namespace sh {

/// The node blocks of a symmetric system by rows (see the file comment).
struct BlockRows {
    vec<int32_t> first;             ///< per node, its row's first entry (node_count() + 1)
    vec<int32_t> column;            ///< per entry, its column node; each row's diagonal entry first
    vec<Eigen::Matrix3d> block;     ///< per entry, the 3x3 block A_IJ

    /// Copies system's blocks (blocks built from its pattern). Allocates; on failure it is as
    /// it was.
    void build(const SparseSystem& system, const UpperBlocks& blocks);
    /// Free nodes (0 before build).
    int32_t node_count() const { return first.empty() ? 0 : static_cast<int32_t>(first.size()) - 1; }
};

}  // namespace sh
