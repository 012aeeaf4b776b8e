#include "linalg/block_matrix.hpp"

#include "core/error.hpp"

#include <algorithm>

namespace sh {
namespace {

// Index of block (row, column) among the stored blocks, or -1.
int32_t find_block(const vec<int32_t>& row_start, const vec<int32_t>& column, int32_t row, int32_t col) {
    const int32_t* first = column.data() + row_start[static_cast<size_t>(row)];
    const int32_t* last = column.data() + row_start[static_cast<size_t>(row) + 1];
    const int32_t* found = std::lower_bound(first, last, col);
    return found != last && *found == col ? static_cast<int32_t>(found - column.data()) : -1;
}

// Index in columns_'s doubles of entry (row, col) of block k.
int32_t lane_slot(int32_t k, int32_t row, int32_t col) { return 4 * (3 * k + col) + row; }

}  // namespace

void BlockMatrix::build_pattern(const SparseSystem& system) {
    const int32_t n = system.dof_count() / 3;
    const vec<int32_t>& starts = system.column_starts();
    const vec<int32_t>& rows = system.row_indices();
    // Blocks (I, J), I <= J, appear in DOF column 3J as rows 3I; each gives (I, J) and (J, I).
    vec<int32_t> row_start(static_cast<size_t>(n) + 1, 0);
    for (int32_t j = 0; j < n; ++j)
        for (int32_t k = starts[3 * static_cast<size_t>(j)]; k < starts[3 * static_cast<size_t>(j) + 1]; ++k) {
            if (rows[static_cast<size_t>(k)] % 3 != 0) continue;
            const int32_t i = rows[static_cast<size_t>(k)] / 3;
            ++row_start[static_cast<size_t>(i) + 1];
            if (i != j) ++row_start[static_cast<size_t>(j) + 1];
        }
    for (int32_t i = 0; i < n; ++i) row_start[static_cast<size_t>(i) + 1] += row_start[static_cast<size_t>(i)];
    vec<int32_t> column(static_cast<size_t>(row_start[static_cast<size_t>(n)]));
    vec<int32_t> fill(row_start.begin(), row_start.end() - 1);
    // Columns ascend J by J: row I gets (I, J) in J order, row J gets (J, I < J) then later (J, J' > J).
    for (int32_t j = 0; j < n; ++j)
        for (int32_t k = starts[3 * static_cast<size_t>(j)]; k < starts[3 * static_cast<size_t>(j) + 1]; ++k) {
            if (rows[static_cast<size_t>(k)] % 3 != 0) continue;
            const int32_t i = rows[static_cast<size_t>(k)] / 3;
            column[static_cast<size_t>(fill[static_cast<size_t>(i)]++)] = j;
            if (i != j) column[static_cast<size_t>(fill[static_cast<size_t>(j)]++)] = i;
        }
    vec<int32_t> diagonal(static_cast<size_t>(n));
    for (int32_t i = 0; i < n; ++i) {
        diagonal[static_cast<size_t>(i)] = find_block(row_start, column, i, i);
        SH_REQUIRE(diagonal[static_cast<size_t>(i)] >= 0, SH_ERR_INTERNAL, "block matrix: node %d has no diagonal block", i);
    }
    const size_t entries = rows.size();
    vec<int32_t> slot(entries), mirror(entries);
    for (int32_t c = 0; c < system.dof_count(); ++c)
        for (int32_t k = starts[static_cast<size_t>(c)]; k < starts[static_cast<size_t>(c) + 1]; ++k) {
            const int32_t r = rows[static_cast<size_t>(k)];
            const int32_t own = find_block(row_start, column, r / 3, c / 3);
            const int32_t other = find_block(row_start, column, c / 3, r / 3);
            SH_REQUIRE(own >= 0 && other >= 0, SH_ERR_INTERNAL, "block matrix: entry (%d, %d) has no block", r, c);
            slot[static_cast<size_t>(k)] = lane_slot(own, r % 3, c % 3);
            mirror[static_cast<size_t>(k)] = lane_slot(other, c % 3, r % 3);
        }
    vec<Node4> columns(3 * column.size(), Node4{});
    row_start_.swap(row_start), column_.swap(column), diagonal_.swap(diagonal);
    slot_.swap(slot), mirror_.swap(mirror), columns_.swap(columns);
    node_count_ = n;
    pattern_id_ = system.pattern_id();
}

void BlockMatrix::load_values(const SparseSystem& system) {
    SH_REQUIRE(matches(system), SH_ERR_INTERNAL, "block matrix: values of another pattern");
    const double* v = system.values().data();
    double* lanes = reinterpret_cast<double*>(columns_.data());  // GCC: a vector aliases its element type
    for (size_t k = 0; k < slot_.size(); ++k) {
        lanes[static_cast<size_t>(slot_[k])] = v[k];
        lanes[static_cast<size_t>(mirror_[k])] = v[k];
    }
}

void BlockMatrix::multiply(const double* x, double* y) const {
    for (int32_t i = 0; i < node_count_; ++i) {
        Node4 s{};
        for (int32_t k = row_start_[static_cast<size_t>(i)]; k < row_start_[static_cast<size_t>(i) + 1]; ++k)
            s += block_times(block(k), load_node(x + 3 * static_cast<size_t>(column_[static_cast<size_t>(k)])));
        store_node(s, y + 3 * static_cast<size_t>(i));
    }
}

}  // namespace sh
