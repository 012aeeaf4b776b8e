// A SparseSystem's stored upper triangle read by 3x3 node blocks, in place. Column node J of
// the system holds the blocks (I, J), I < J, in DOF columns 3J, 3J + 1 and 3J + 2, three
// contiguous rows each: block (I, J)'s column c is three values in a row. So each stored block
// serves both triangles without a copy: as A_IJ times a node (its columns, pushed into row I)
// and as A_JI = A_IJ^T times a node (dot products with its columns, pulled into row J). A block
// Gauss-Seidel sweep that visits the nodes in order pulls row J's left part from these blocks
// and pushes its new value into the rows it meets, reading each stored block once per sweep
// where a full copy of the matrix is read twice (the cycle's passes stream 2.5 MB instead of
// 6.5 MB at 20 k tets, from cache).
#pragma once

#include "core/memory.hpp"
#include "linalg/node_lanes.hpp"
#include "linalg/sparse_system.hpp"

#include <cstdint>

namespace sh {

/// The node blocks of a SparseSystem's pattern (see the file comment); each call reads the
/// values and column starts of the system it is given, which must have the pattern built from.
class UpperBlocks {
public:
    /// The block structure of system's pattern (allocates; on failure it is as it was).
    void build(const SparseSystem& system);
    /// True if built from system's current pattern.
    bool matches(const SparseSystem& system) const { return pattern_id_ != 0 && pattern_id_ == system.pattern_id(); }

    int32_t node_count() const { return node_count_; }                                  ///< free nodes
    int64_t block_count() const { return static_cast<int64_t>(row_node_.size()); }     ///< blocks (I, J), I < J
    const int32_t* first_block() const { return first_block_.data(); }                 ///< per column node J, node_count() + 1
    const int32_t* row_node() const { return row_node_.data(); }                       ///< I of each block

    /// Entry (row, col) of block b of column node J (each 0..2).
    double entry(const SparseSystem& a, int32_t node, int32_t b, int row, int col) const {
        return a.values()[static_cast<size_t>(a.column_starts()[3 * static_cast<size_t>(node) + static_cast<size_t>(col)]) +
                          3 * static_cast<size_t>(b - first_block_[static_cast<size_t>(node)]) + static_cast<size_t>(row)];
    }
    /// Node J's diagonal block (both triangles), read from its three columns' last entries.
    void diagonal_block(const SparseSystem& a, int32_t node, double (&out)[3][3]) const;

    /// The sum over node J's blocks of A_JI x_I (x in node lanes; their fourth lanes are not
    /// read), its fourth lane 0.
    Node4 pull(const SparseSystem& a, int32_t node, const Node4* x) const {
        Node4 dot[3] = {};
        const int32_t begin = first_block_[static_cast<size_t>(node)], end = first_block_[static_cast<size_t>(node) + 1];
        const double* column[3];
        columns(a, node, column);
        for (int32_t b = begin; b < end; ++b) {
            const Node4 xi = x[row_node_[static_cast<size_t>(b)]];
            const size_t at = 3 * static_cast<size_t>(b - begin);
            for (int c = 0; c < 3; ++c) dot[c] += load_column(column[c] + at) * xi;
        }
        return Node4{lane_sum3(dot[0]), lane_sum3(dot[1]), lane_sum3(dot[2]), 0.0};
    }
    /// out_I += A_IJ u over node J's blocks (the fourth lanes of out take what the columns'
    /// next entries give: read them as three values).
    void push(const SparseSystem& a, int32_t node, Node4 u, Node4* out) const {
        const int32_t begin = first_block_[static_cast<size_t>(node)], end = first_block_[static_cast<size_t>(node) + 1];
        const double* column[3];
        columns(a, node, column);
        for (int32_t b = begin; b < end; ++b) {
            const size_t at = 3 * static_cast<size_t>(b - begin);
            out[row_node_[static_cast<size_t>(b)]] +=
                load_column(column[0] + at) * u[0] + load_column(column[1] + at) * u[1] + load_column(column[2] + at) * u[2];
        }
    }
    /// Node J's diagonal block times x (node lanes).
    Node4 diagonal_times(const SparseSystem& a, int32_t node, Node4 x) const {
        double d[3][3];
        diagonal_block(a, node, d);
        Node4 out{};
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) out[r] += d[r][c] * x[c];
        return out;
    }

private:
    // Where node J's DOF columns start in the values (the first block's column c).
    static void columns(const SparseSystem& a, int32_t node, const double* (&out)[3]) {
        for (int c = 0; c < 3; ++c)
            out[c] = a.values().data() + a.column_starts()[3 * static_cast<size_t>(node) + static_cast<size_t>(c)];
    }
    // The three values from p in lanes 0-2; lane 3 holds p[3], the column's next entry. That
    // lane never reaches lanes 0-2 of a result: pull sums lanes 0-2 of its products only, and
    // push adds it into the output's lane 3, which every reader of the output ignores
    // (block_times and store_node read lanes 0-2); so nothing masks it.
    static Node4 load_column(const double* p) {
        Node4 v;
        __builtin_memcpy(&v, p, sizeof v);
        return v;
    }
    static double lane_sum3(Node4 v) { return v[0] + v[1] + v[2]; }

    int32_t node_count_ = 0;
    uint64_t pattern_id_ = 0;
    vec<int32_t> first_block_;   // node_count_ + 1
    vec<int32_t> row_node_;      // per block
};

}  // namespace sh
