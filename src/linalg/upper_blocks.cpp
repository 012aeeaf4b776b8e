#include "linalg/upper_blocks.hpp"

#include "core/error.hpp"

#include <algorithm>

namespace sh {

void UpperBlocks::build(const SparseSystem& system) {
    const int32_t n = system.dof_count() / 3;
    const vec<int32_t>& starts = system.column_starts();
    const vec<int32_t>& rows = system.row_indices();
    // Column 3J holds three rows per block (I, J), I < J, then the diagonal's first row.
    vec<int32_t> first(static_cast<size_t>(n) + 1, 0);
    for (int32_t j = 0; j < n; ++j) {
        const int32_t entries = starts[3 * static_cast<size_t>(j) + 1] - starts[3 * static_cast<size_t>(j)];
        SH_REQUIRE(entries % 3 == 1, SH_ERR_INTERNAL, "upper blocks: column %d has %d entries", 3 * j, entries);
        first[static_cast<size_t>(j) + 1] = first[static_cast<size_t>(j)] + entries / 3;
    }
    vec<int32_t> row_node(static_cast<size_t>(first[static_cast<size_t>(n)]));
    for (int32_t j = 0; j < n; ++j) {
        const int32_t column = starts[3 * static_cast<size_t>(j)];
        for (int32_t b = first[static_cast<size_t>(j)]; b < first[static_cast<size_t>(j) + 1]; ++b)
            row_node[static_cast<size_t>(b)] = rows[static_cast<size_t>(column + 3 * (b - first[static_cast<size_t>(j)]))] / 3;
    }
    vec<int32_t> column_start(starts.begin(), starts.end());
    first_block_.swap(first), row_node_.swap(row_node), column_start_.swap(column_start);
    node_count_ = n;
    pattern_id_ = system.pattern_id();
}

double UpperBlocks::diagonal_entry(const double* values, int32_t node, int row, int col) const {
    // Column 3J + c ends with the diagonal block's rows 0..c.
    const int upper = std::max(row, col), lower = std::min(row, col);
    const size_t column = 3 * static_cast<size_t>(node) + static_cast<size_t>(upper);
    return values[static_cast<size_t>(column_start_[column + 1] - 1 - upper + lower)];
}

void UpperBlocks::multiply(const double* values, const double* x, double* y, Node4* lanes) const {
    Node4* in = lanes;
    Node4* out = lanes + node_count_;
    for (int32_t j = 0; j < node_count_; ++j) {
        in[j] = load_node(x + 3 * static_cast<size_t>(j));
        out[j] = Node4{};
    }
    // Row J gets its diagonal and left blocks here and its right blocks from the later columns'
    // pushes.
    for (int32_t j = 0; j < node_count_; ++j) {
        out[j] += diagonal_times(values, j, in[j]) + pull(values, j, in);
        push(values, j, in[j], out);
    }
    for (int32_t j = 0; j < node_count_; ++j) store_node(out[j], y + 3 * static_cast<size_t>(j));
}

}  // namespace sh
