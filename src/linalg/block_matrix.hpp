// A SparseSystem's values as a full symmetric matrix of 3x3 node blocks in compressed rows:
// both triangles stored, so that a block Gauss-Seidel sweep reads a node's whole row in one
// place and a product streams each block once.
#pragma once

#include "core/memory.hpp"
#include "linalg/sparse_system.hpp"

#include <cstdint>

namespace sh {

/// Full symmetric matrix over a SparseSystem's free nodes, in 3x3 blocks (row-major), rows in
/// compressed form with ascending columns.
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
    const double* block(int32_t k) const { return &values_[9 * static_cast<size_t>(k)]; } ///< 9, row-major
    int32_t diagonal(int32_t node) const { return diagonal_[static_cast<size_t>(node)]; } ///< its block's index

    /// y = A x (3 per node each; x and y must not overlap).
    void multiply(const double* x, double* y) const;

private:
    int32_t node_count_ = 0;
    uint64_t pattern_id_ = 0;
    vec<int32_t> row_start_, column_, diagonal_;
    vec<double> values_;
    // Per stored entry of the system's upper triangle, the two value slots it fills: its own
    // block's and its mirror's (the same slot twice on a diagonal block's diagonal).
    vec<int32_t> slot_, mirror_;
};

}  // namespace sh
