#include "linalg/sparse_system.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <atomic>
#include <cinttypes>
#include <climits>
#include <cstdio>
#include <cstring>

namespace sh {
namespace {

std::atomic<uint64_t> g_next_pattern_id{1};

// Largest nodes per element: local indices (3k)^2 - 1 must fit a uint16_t.
constexpr int kMaxNodesPerElement = 85;

// Checks build_pattern's arguments (see the header) for its elements or its links: what names
// them in messages.
void check_pattern_input(const int32_t* elements, size_t element_count, int nodes_per_element,
                         const int32_t* free_index, int32_t node_count, int32_t free_count, const char* what) {
    SH_REQUIRE(nodes_per_element >= 1 && nodes_per_element <= kMaxNodesPerElement, SH_ERR_INVALID_ARGUMENT,
               "sparse system: nodes_per_element %d is not in [1, %d]", nodes_per_element, kMaxNodesPerElement);
    SH_REQUIRE(node_count >= 0 && free_count >= 0 && free_count <= node_count, SH_ERR_INVALID_ARGUMENT,
               "sparse system: free_count %d is not in [0, node_count = %d]", free_count, node_count);
    SH_REQUIRE(free_count <= INT32_MAX / 3, SH_ERR_CAPACITY, "sparse system: %d free nodes exceed %d",
               free_count, INT32_MAX / 3);
    SH_REQUIRE(element_count == 0 || elements, SH_ERR_INVALID_ARGUMENT, "sparse system: %ss is NULL", what);
    SH_REQUIRE(node_count == 0 || free_index, SH_ERR_INVALID_ARGUMENT, "sparse system: free_index is NULL");
    const size_t k = static_cast<size_t>(nodes_per_element);
    SH_REQUIRE(element_count <= SIZE_MAX / k, SH_ERR_INVALID_ARGUMENT, "sparse system: %s count overflows", what);
    for (size_t i = 0; i < element_count * k; ++i)
        SH_REQUIRE(elements[i] >= 0 && elements[i] < node_count, SH_ERR_INVALID_ARGUMENT,
                   "sparse system: %s %zu node %zu is %d, not in [0, %d)", what, i / k, i % k, elements[i], node_count);
}

// Free DOF -> global DOF, checking that free_index is one-to-one onto [0, free_count).
vec<int32_t> free_dofs(const int32_t* free_index, int32_t node_count, int32_t free_count) {
    const size_t nfree = static_cast<size_t>(free_count);
    vec<int32_t> dof_to_global(3 * nfree, -1);
    for (int32_t i = 0; i < node_count; ++i) {
        const int32_t f = free_index[i];
        if (f == -1) continue;
        SH_REQUIRE(f >= 0 && f < free_count, SH_ERR_INVALID_ARGUMENT,
                   "sparse system: free_index[%d] = %d is not -1 or in [0, %d)", i, f, free_count);
        SH_REQUIRE(dof_to_global[3 * static_cast<size_t>(f)] < 0, SH_ERR_INVALID_ARGUMENT,
                   "sparse system: nodes %d and %d both have free index %d", dof_to_global[3 * static_cast<size_t>(f)] / 3,
                   i, f);
        for (int c = 0; c < 3; ++c) dof_to_global[3 * static_cast<size_t>(f) + c] = 3 * i + c;
    }
    for (size_t f = 0; f < nfree; ++f)
        SH_REQUIRE(dof_to_global[3 * f] >= 0, SH_ERR_INVALID_ARGUMENT,
                   "sparse system: no node has free index %zu (free_count %d)", f, free_count);
    return dof_to_global;
}

// The elements in assembly order (element_order, or 0, 1, ... for nullptr) and each element's
// position in it, checking that element_order is a permutation of [0, element_count).
void assembly_order(const int32_t* element_order, size_t element_count, vec<int32_t>& order, vec<int32_t>& position) {
    SH_REQUIRE(element_count <= static_cast<size_t>(INT32_MAX), SH_ERR_CAPACITY,
               "sparse system: %zu elements exceed 2^31 - 1", element_count);
    order.resize(element_count);
    position.assign(element_count, -1);
    for (size_t p = 0; p < element_count; ++p) {
        const int32_t e = element_order ? element_order[p] : static_cast<int32_t>(p);
        SH_REQUIRE(e >= 0 && static_cast<size_t>(e) < element_count && position[static_cast<size_t>(e)] < 0,
                   SH_ERR_INVALID_ARGUMENT,
                   "sparse system: element_order[%zu] = %d is out of [0, %zu) or repeats an earlier entry", p, e,
                   element_count);
        order[p] = e;
        position[static_cast<size_t>(e)] = static_cast<int32_t>(p);
    }
}

// The node-block pattern of the strict upper triangle: for free column node J, the sorted,
// distinct free row nodes I < J sharing an element with it, rows[start[J], start[J + 1]).
struct NodeBlocks {
    vec<size_t> start;
    vec<int32_t> rows;
};

NodeBlocks upper_node_blocks(const int32_t* elements, size_t element_count, size_t k, const int32_t* free_index,
                             size_t nfree, const int32_t* links, size_t link_count) {
    NodeBlocks blocks;
    blocks.start.assign(nfree + 1, 0);
    auto for_each_pair = [&](auto&& visit) {
        const auto pair = [&](int32_t i, int32_t j) {
            const int32_t fa = free_index[i], fb = free_index[j];
            if (fa >= 0 && fb > fa) visit(fa, fb);  // row fa < column fb
        };
        for (size_t e = 0; e < element_count; ++e) {
            const int32_t* en = elements + e * k;
            for (size_t a = 0; a < k; ++a)
                for (size_t b = 0; b < k; ++b) pair(en[a], en[b]);
        }
        for (size_t l = 0; l < link_count; ++l) {
            pair(links[2 * l], links[2 * l + 1]);
            pair(links[2 * l + 1], links[2 * l]);
        }
    };
    // Counted, filled, then sorted and deduplicated per column.
    for_each_pair([&](int32_t, int32_t col) { ++blocks.start[static_cast<size_t>(col) + 1]; });
    for (size_t j = 0; j < nfree; ++j) blocks.start[j + 1] += blocks.start[j];
    blocks.rows.resize(blocks.start[nfree]);
    {
        vec<size_t> fill(blocks.start.begin(), blocks.start.end() - 1);
        for_each_pair([&](int32_t row, int32_t col) { blocks.rows[fill[static_cast<size_t>(col)]++] = row; });
    }
    size_t unique_blocks = 0;
    for (size_t j = 0; j < nfree; ++j) {
        int32_t* first = blocks.rows.data() + blocks.start[j];
        int32_t* last = blocks.rows.data() + blocks.start[j + 1];
        std::sort(first, last);
        last = std::unique(first, last);
        const size_t start = unique_blocks;
        for (int32_t* p = first; p != last; ++p) blocks.rows[unique_blocks++] = *p;
        blocks.start[j] = start;
    }
    blocks.start[nfree] = unique_blocks;
    blocks.rows.resize(unique_blocks);
    return blocks;
}

// Expands node blocks to DOF columns: column 3J+c holds rows 3I..3I+2 of each block row I < J,
// then the diagonal block's rows 3J..3J+c (so the diagonal entry comes last).
void expand_columns(const NodeBlocks& blocks, size_t nfree, vec<int32_t>& column_starts, vec<int32_t>& row_indices) {
    int32_t p = 0;
    for (size_t j = 0; j < nfree; ++j) {
        for (int c = 0; c < 3; ++c) {
            column_starts[3 * j + c] = p;
            for (size_t b = blocks.start[j]; b < blocks.start[j + 1]; ++b)
                for (int r = 0; r < 3; ++r) row_indices[static_cast<size_t>(p++)] = 3 * blocks.rows[b] + r;
            for (int r = 0; r <= c; ++r) row_indices[static_cast<size_t>(p++)] = 3 * static_cast<int32_t>(j) + r;
        }
    }
    column_starts[3 * nfree] = p;
}

}  // namespace

// Element scatter map, one record per 3x3 block. Local node pair (a, b) with free indices
// I <= J maps Ke's block (rows 3a.., columns 3b..) to the global block (3I.., 3J..): entry
// (r, s) goes to slot column_start(3J+s) + 3 * (position of I among column J's block rows) + r,
// the diagonal block (I == J) coming after all block rows and keeping only r <= s. Pairs with
// I > J are left out: their entries lie in the lower triangle (the pair (b, a) supplies them).
// That is exactly "local (p, q) is added when g(p) <= g(q)", also for a repeated node.
void SparseSystem::build_scatter_map(const int32_t* elements, const vec<int32_t>& order, size_t k,
                                     const int32_t* free_index, const vec<size_t>& block_start,
                                     const vec<int32_t>& block_rows, const vec<int32_t>& column_starts,
                                     vec<size_t>& record_start, vec<BlockRecord>& records) {
    const size_t n3 = 3 * k, element_count = order.size();
    record_start.assign(element_count + 1, 0);
    // The off-diagonal blocks first, then the diagonal ones: the scatter branches on the kind,
    // and in this order it branches the same way for every element with the same free nodes
    // (in the order the pairs come, the diagonal blocks fall where the nodes' numbers put them,
    // and a mispredicted branch per block cost more than the block's nine additions).
    auto element_blocks = [&](size_t e, auto&& visit) {
        const int32_t* en = elements + e * k;
        for (const bool diagonal : {false, true})
            for (size_t a = 0; a < k; ++a) {
                const int32_t fi = free_index[en[a]];
                if (fi < 0) continue;
                for (size_t b = 0; b < k; ++b) {
                    const int32_t fj = free_index[en[b]];
                    if (fj < fi || (fj == fi) != diagonal) continue;  // also skips fj == -1
                    visit(a, b, fi, fj);
                }
            }
    };
    for (size_t p = 0; p < element_count; ++p) {
        size_t count = 0;
        element_blocks(static_cast<size_t>(order[p]), [&](size_t, size_t, int32_t, int32_t) { ++count; });
        record_start[p + 1] = record_start[p] + count;
    }
    records.resize(record_start[element_count]);
    for (size_t p = 0; p < element_count; ++p) {
        size_t i = record_start[p];
        element_blocks(static_cast<size_t>(order[p]), [&](size_t a, size_t b, int32_t fi, int32_t fj) {
            const size_t j = static_cast<size_t>(fj);
            const int32_t* rows = block_rows.data() + block_start[j];
            const size_t count = block_start[j + 1] - block_start[j];
            const size_t pos = fi == fj ? count : static_cast<size_t>(std::lower_bound(rows, rows + count, fi) - rows);
            BlockRecord& rec = records[i++];
            for (size_t c = 0; c < 3; ++c) rec.slot[c] = column_starts[3 * j + c] + static_cast<int32_t>(3 * pos);
            rec.local = static_cast<uint16_t>(3 * a * n3 + 3 * b);
            rec.pair = static_cast<uint16_t>(a * k + b) & 0x7fffu;
            rec.diagonal = fi == fj ? 1 : 0;
        });
    }
}

void SparseSystem::build_pattern(const int32_t* elements, size_t element_count, int nodes_per_element,
                                 const int32_t* free_index, int32_t node_count, int32_t free_count,
                                 const int32_t* links, size_t link_count, const int32_t* element_order) {
    // Start empty, so a failure below (bad input, std::bad_alloc) leaves an empty system.
    {
        SparseSystem empty;
        std::swap(*this, empty);
    }
    check_pattern_input(elements, element_count, nodes_per_element, free_index, node_count, free_count, "element");
    check_pattern_input(links, link_count, 2, free_index, node_count, free_count, "link");
    const size_t k = static_cast<size_t>(nodes_per_element), nfree = static_cast<size_t>(free_count);
    vec<int32_t> dof_to_global = free_dofs(free_index, node_count, free_count);
    const NodeBlocks blocks = upper_node_blocks(elements, element_count, k, free_index, nfree, links, link_count);
    const uint64_t nnz = 6 * static_cast<uint64_t>(nfree) + 9 * static_cast<uint64_t>(blocks.rows.size());
    SH_REQUIRE(nnz <= static_cast<uint64_t>(INT32_MAX), SH_ERR_CAPACITY,
               "sparse system: %" PRIu64 " stored entries exceed 2^31 - 1", nnz);
    vec<int32_t> column_starts(3 * nfree + 1);
    vec<int32_t> row_indices(static_cast<size_t>(nnz));
    expand_columns(blocks, nfree, column_starts, row_indices);
    vec<int32_t> order, position;
    assembly_order(element_order, element_count, order, position);
    vec<size_t> record_start;
    vec<BlockRecord> records;
    build_scatter_map(elements, order, k, free_index, blocks.start, blocks.rows, column_starts, record_start, records);
    vec<double> values(static_cast<size_t>(nnz), 0.0);

    dof_count_ = 3 * free_count;
    element_count_ = element_count;
    column_starts_.swap(column_starts);
    row_indices_.swap(row_indices);
    values_.swap(values);
    dof_to_global_.swap(dof_to_global);
    local_size_ = static_cast<int32_t>(3 * k);
    element_position_.swap(position);
    element_order_.swap(order);
    block_record_start_.swap(record_start);
    block_records_.swap(records);
    pattern_id_ = g_next_pattern_id.fetch_add(1);
}

void SparseSystem::clear_values() { std::fill(values_.begin(), values_.end(), 0.0); }

template <class Entry>
void SparseSystem::scatter_element(size_t element, size_t position, double scale, const Entry& entry) {
    SH_REQUIRE(element < element_count_, SH_ERR_INTERNAL, "sparse system: element %zu of %zu", element,
               element_count_);
    double* v = values_.data();
    if (position >= element_order_.size() || static_cast<size_t>(element_order_[position]) != element)
        position = static_cast<size_t>(element_position_[element]);
    const BlockRecord* rec = block_records_.data() + block_record_start_[position];
    const BlockRecord* end = block_records_.data() + block_record_start_[position + 1];
    for (; rec != end; ++rec) {
        if (!rec->diagonal) {
            for (int s = 0; s < 3; ++s) {
                double* col = v + rec->slot[s];
                for (int r = 0; r < 3; ++r) col[r] += scale * entry(*rec, r, s);
            }
        } else {
            for (int s = 0; s < 3; ++s)
                for (int r = 0; r <= s; ++r) v[rec->slot[s] + r] += scale * entry(*rec, r, s);
        }
    }
}

void SparseSystem::add_element(size_t element, const double* Ke, double scale) {
    const size_t m = static_cast<size_t>(local_size_);
    scatter_element(element, SIZE_MAX, scale, [&](const BlockRecord& rec, int r, int s) {
        return Ke[rec.local + static_cast<size_t>(r) * m + static_cast<size_t>(s)];
    });
}

void SparseSystem::add_element_lane(size_t element, size_t position, const double* blocks, size_t stride,
                                    double scale) {
    // Entry k of a block lies k strides past its first: the nine offsets once per element,
    // where each entry's would cost a multiplication by the stride.
    size_t offset[9];
    for (size_t k = 0; k < 9; ++k) offset[k] = k * stride;
    const size_t block_size = 9 * stride;
    scatter_element(element, position, scale, [&](const BlockRecord& rec, int r, int s) {
        return blocks[static_cast<size_t>(rec.pair) * block_size + offset[3 * r + s]];
    });
}

void SparseSystem::add_block(int32_t free_i, int32_t free_j, const double* B, double scale) {
    // Stored upper triangle: entry (row, column) with row <= column. Block (I, J) with I > J is
    // stored as the transpose of (J, I).
    const bool transpose = free_i > free_j;
    const int32_t I = transpose ? free_j : free_i, J = transpose ? free_i : free_j;
    for (int s = 0; s < 3; ++s) {
        const int32_t column = 3 * J + s;
        for (int r = 0; r < 3; ++r) {
            const int32_t row = 3 * I + r;
            if (row > column) continue;
            const int32_t slot = value_slot(row, column);
            SH_REQUIRE(slot >= 0, SH_ERR_INTERNAL, "sparse system: no block for free nodes %d and %d", free_i, free_j);
            const double b = transpose ? B[3 * s + r] : B[3 * r + s];
            values_[static_cast<size_t>(slot)] += scale * b;
        }
    }
}

int32_t SparseSystem::value_slot(int32_t row, int32_t column) const {
    const int32_t* first = row_indices_.data() + column_starts_[static_cast<size_t>(column)];
    const int32_t* last = row_indices_.data() + column_starts_[static_cast<size_t>(column) + 1];
    const int32_t* slot = std::lower_bound(first, last, row);
    return slot != last && *slot == row ? static_cast<int32_t>(slot - row_indices_.data()) : -1;
}

bool SparseSystem::has_block(int32_t free_i, int32_t free_j) const {
    return value_slot(3 * std::min(free_i, free_j), 3 * std::max(free_i, free_j)) >= 0;
}

void SparseSystem::add_diagonal(const double* diag, double scale) {
    double* v = values_.data();
    const int32_t* cs = column_starts_.data();
    for (int32_t d = 0; d < dof_count_; ++d) v[cs[d + 1] - 1] += scale * diag[d];
}

void SparseSystem::multiply(const double* x, double* y) const {
    // Column j of the upper triangle holds A(i, j), i <= j: it adds A(i, j) x_j to y_i and, off
    // the diagonal (the column's last entry), A(i, j) x_i to y_j.
    const double* v = values_.data();
    const int32_t* cs = column_starts_.data();
    const int32_t* rows = row_indices_.data();
    for (int32_t j = 0; j < dof_count_; ++j) {
        const double xj = x[j];
        double yj = 0.0;
        const int32_t last = cs[j + 1] - 1;
        for (int32_t k = cs[j]; k < last; ++k) {
            y[rows[k]] += v[k] * xj;
            yj += v[k] * x[rows[k]];
        }
        y[j] = yj + v[last] * xj;  // rows above j are done: y_j gets no more later
    }
}

int32_t SparseSystem::first_nonfinite_column() const {
    // Integer exponent test: vectorises, unlike a floating-point reduction.
    constexpr uint64_t kExponent = 0x7ff0000000000000ull;
    const double* v = values_.data();
    const size_t n = values_.size();
    uint64_t bad = 0;
    for (size_t i = 0; i < n; ++i) {
        uint64_t bits;
        std::memcpy(&bits, v + i, sizeof bits);
        bad |= static_cast<uint64_t>((bits & kExponent) == kExponent);
    }
    if (!bad) return -1;
    for (int32_t j = 0; j < dof_count_; ++j)
        for (int32_t p = column_starts_[static_cast<size_t>(j)]; p < column_starts_[static_cast<size_t>(j) + 1]; ++p) {
            uint64_t bits;
            std::memcpy(&bits, v + p, sizeof bits);
            if ((bits & kExponent) == kExponent) return j;
        }
    return -1;
}

void SparseSystem::describe_dof(int32_t d, char* out, size_t size) const {
    if (d >= 0 && d < dof_count_) {
        const int32_t g = dof_to_global_[static_cast<size_t>(d)];
        std::snprintf(out, size, "node %d, component %c", g / 3, "xyz"[g % 3]);
    } else {
        std::snprintf(out, size, "no such free DOF");
    }
}

}  // namespace sh
