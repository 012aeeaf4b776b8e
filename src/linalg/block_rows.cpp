#include "linalg/block_rows.hpp"

namespace sh {

void BlockRows::build(const SparseSystem& system, const UpperBlocks& blocks) {
    const int32_t n = blocks.node_count();
    // Each stored block (I, J), I < J, is entry J of row I and, transposed, entry I of row J.
    vec<int32_t> starts(static_cast<size_t>(n) + 1, 0);
    for (int32_t j = 0; j < n; ++j) {
        starts[static_cast<size_t>(j) + 1] += 1 + blocks.first_block()[j + 1] - blocks.first_block()[j];
        for (int32_t b = blocks.first_block()[j]; b < blocks.first_block()[j + 1]; ++b)
            ++starts[static_cast<size_t>(blocks.row_node()[b]) + 1];
    }
    for (int32_t i = 0; i < n; ++i) starts[static_cast<size_t>(i) + 1] += starts[static_cast<size_t>(i)];
    vec<int32_t> columns(static_cast<size_t>(starts[static_cast<size_t>(n)]));
    vec<Eigen::Matrix3d> values(columns.size());
    vec<int32_t> next(starts.begin(), starts.end() - 1);
    const auto put = [&](int32_t row, int32_t col, const Eigen::Matrix3d& value) {
        const size_t at = static_cast<size_t>(next[static_cast<size_t>(row)]++);
        columns[at] = col;
        values[at] = value;
    };
    for (int32_t j = 0; j < n; ++j) {
        double diagonal[3][3];
        blocks.diagonal_block(system, j, diagonal);
        put(j, j, Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&diagonal[0][0]));
    }
    for (int32_t j = 0; j < n; ++j)
        for (int32_t b = blocks.first_block()[j]; b < blocks.first_block()[j + 1]; ++b) {
            Eigen::Matrix3d upper;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) upper(r, c) = blocks.entry(system, j, b, r, c);
            const int32_t i = blocks.row_node()[b];
            put(i, j, upper);
            put(j, i, upper.transpose());
        }
    first.swap(starts), column.swap(columns), block.swap(values);
}

}  // namespace sh
