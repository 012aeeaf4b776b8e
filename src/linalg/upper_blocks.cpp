#include "linalg/upper_blocks.hpp"

#include "core/error.hpp"


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
    first_block_.swap(first), row_node_.swap(row_node);
    node_count_ = n;
    pattern_id_ = system.pattern_id();
}

void UpperBlocks::diagonal_block(const SparseSystem& a, int32_t node, double (&out)[3][3]) const {
    // Column 3J + c ends with the diagonal block's rows 0..c.
    for (int c = 0; c < 3; ++c) {
        const size_t column = 3 * static_cast<size_t>(node) + static_cast<size_t>(c);
        const double* last = a.values().data() + a.column_starts()[column + 1] - 1;
        for (int r = 0; r <= c; ++r) out[r][c] = out[c][r] = last[r - c];
    }
}

}  // namespace sh
