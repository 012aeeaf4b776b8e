// A SparseSystem's values as a full symmetric matrix of 3x3 node blocks in compressed rows:
// both triangles stored, so that a block Gauss-Seidel sweep reads a node's whole row in one
// place and a product streams each block once. Each block is kept as its three columns in
// node lanes (linalg/node_lanes.hpp), the form its products vectorise in.
#pragma once

#include "core/memory.hpp"
#include "linalg/node_lanes.hpp"
#include "linalg/sparse_system.hpp"

#include <cstdint>

namespace sh {

/// Full symmetric matrix over a SparseSystem's free nodes, in 3x3 blocks (three node-lane
/// columns each), rows in compressed form with ascending columns.
class BlockMatrix {
public:
    /// The pattern of system's node blocks and where each of its stored entries goes
    /// (allocates; on failure the matrix is as it was). Values are zero afterwards.
    void build_pattern(const SparseSystem& system);
    /// Copies system's current values; its pattern must be the one built (SH_ERR_INTERNAL).
    void load_values(const SparseSystem& system);
    /// True if the pattern was built from system's current pattern.
    bool matches(const SparseSystem& system) const { return pattern_id_ != 0 && pattern_id_ == system.pattern_id(); }

    int32_t node_count() const { return node_count_; }                                    ///< block rows
    int64_t block_count() const { return static_cast<int64_t>(column_.size()); }         ///< stored blocks
    const int32_t* row_start() const { return row_start_.data(); }                       ///< node_count() + 1
    const int32_t* column() const { return column_.data(); }                             ///< per block
    const Node4* block(int32_t k) const { return &columns_[3 * static_cast<size_t>(k)]; } ///< its 3 columns
    /// Entry (row, col) of block k (each 0..2).
    double entry(int32_t k, int row, int col) const { return columns_[3 * static_cast<size_t>(k) + col][row]; }
    int32_t diagonal(int32_t node) const { return diagonal_[static_cast<size_t>(node)]; } ///< its block's index

    /// y = A x (3 per node each; x and y must not overlap).
    void multiply(const double* x, double* y) const;
    /// y -= the sum of A_k x_j over the stored blocks first <= k < last (part of one row), x
    /// in node lanes.
    Node4 subtract_row_blocks(int32_t first, int32_t last, const Node4* x, Node4 y) const {
        const Node4* b = &columns_[3 * static_cast<size_t>(first)];
        for (int32_t k = first; k < last; ++k, b += 3) y -= block_times(b, x[column_[static_cast<size_t>(k)]]);
        return y;
    }

private:
    int32_t node_count_ = 0;
    uint64_t pattern_id_ = 0;
    vec<int32_t> row_start_, column_, diagonal_;
    vec<Node4> columns_;  // 3 per block
    // Per stored entry of the system's upper triangle, the two doubles of columns_ it fills:
    // its own block's and its mirror's (the same twice on a diagonal block's diagonal).
    vec<int32_t> slot_, mirror_;
};

}  // namespace sh
