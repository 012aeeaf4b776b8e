// The symmetric sparse system of implicit steps and static solves: a matrix over the free degrees
// of freedom (3 per free node), stored as its upper triangle in compressed sparse columns, with a
// precomputed scatter map from element matrices to value slots.
#pragma once

#include "core/memory.hpp"

#include <cstddef>
#include <cstdint>

namespace sh {

/// Symmetric matrix over the free DOFs (3 per free node), stored as its upper triangle in
/// compressed sparse columns (CSC) with sorted row indices. Pattern from element connectivity.
///
/// Free DOF d = 3 * free_index[node] + c (c = x, y, z). Every free node has its full 3x3
/// diagonal block (6 stored entries) even if no element uses it, and two free nodes sharing an
/// element have a full 3x3 off-diagonal block (9 stored entries), so
/// nonzero_count() = 6 * free nodes + 9 * (pairs of free nodes sharing an element).
/// The diagonal entry of each column is the last entry of that column.
class SparseSystem {
public:
    /// Builds the pattern. elements: element_count x nodes_per_element node indices (2 for springs,
    /// 4 for tets). free_index[i] = position of node i among the free nodes, or -1 if node i is fixed,
    /// prescribed or an orphan (its rows/columns are left out). free_count = number of free nodes.
    /// Also builds, for each element, the map from its local (3k x 3k) upper-triangle entries to
    /// value slots, so add_element is a straight scatter.
    /// Throws SH_ERR_INVALID_ARGUMENT for a node index out of range or a free_index that is not a
    /// one-to-one map onto [0, free_count), SH_ERR_CAPACITY if the matrix would exceed 2^31 - 1
    /// stored entries. Values are zero afterwards. Allocates; on failure the system is empty.
    /// links: link_count node pairs (links[2l], links[2l + 1]) whose blocks the pattern holds
    /// too, though they may share no element (a field's coupling, e.g. a contact that spans
    /// several faces); add_block reaches them, add_element does not.
    /// element_order: the order the elements will be added in, a permutation of
    /// [0, element_count) (nullptr: 0, 1, ...). The scatter map is laid out in it, so that an
    /// assembly in that order reads the map in sequence; only speed depends on it. Throws
    /// SH_ERR_INVALID_ARGUMENT if it is not a permutation.
    void build_pattern(const int32_t* elements, size_t element_count, int nodes_per_element,
                       const int32_t* free_index, int32_t node_count, int32_t free_count,
                       const int32_t* links = nullptr, size_t link_count = 0,
                       const int32_t* element_order = nullptr);
    int32_t dof_count() const { return dof_count_; }  ///< 3 * free_count
    int64_t nonzero_count() const { return static_cast<int64_t>(row_indices_.size()); }  ///< stored (upper) entries
    void clear_values();                 ///< all values to 0
    /// Adds scale * Ke for element e; Ke is (3k x 3k) row-major, symmetric (only its upper part, in the
    /// global ordering, is read); rows/cols of constrained nodes are skipped.
    /// Precisely: local entry (p, q) is added to global entry (g(p), g(q)) when both are free
    /// DOFs and g(p) <= g(q), so a full symmetric Ke gives the exact global sum.
    void add_element(size_t element, const double* Ke, double scale);
    /// add_element for Ke given by node blocks, one element's lane of a batch: local entry
    /// (3a + r, 3b + s) at blocks[((a k + b) 9 + 3r + s) stride] (k nodes per element), as the
    /// element kernels hold a batch's tangents. Saves copying each lane out into a Ke.
    /// position: where the element is expected in the assembly order (build_pattern's
    /// element_order), as an assembly in that order counts; the map is then read without a
    /// lookup by element. Any other value costs only that lookup.
    void add_element_lane(size_t element, size_t position, const double* blocks, size_t stride, double scale);
    /// Adds scale * B (3x3, row-major) to the block of free nodes (I, J) and, for I != J, its
    /// transpose to (J, I): only the stored upper triangle is touched. The nodes must share an
    /// element or a link (or be equal); otherwise throws SH_ERR_INTERNAL.
    void add_block(int32_t free_i, int32_t free_j, const double* B, double scale);
    /// True if the pattern holds the block of free nodes I and J (they share an element or a link).
    bool has_block(int32_t free_i, int32_t free_j) const;
    /// Adds diag[d] to diagonal entry d, for d < dof_count() (lumped mass, per-DOF terms).
    void add_diagonal(const double* diag, double scale);
    /// y = A x for the full symmetric matrix (dof_count() values each; x and y must not overlap).
    void multiply(const double* x, double* y) const;
    const vec<int32_t>& column_starts() const { return column_starts_; }  ///< dof_count()+1
    const vec<int32_t>& row_indices() const { return row_indices_; }
    const vec<double>& values() const { return values_; }
    vec<double>& values() { return values_; }
    /// Per free DOF d: the global DOF 3*node+c it stands for; and the inverse via free_index.
    const vec<int32_t>& dof_to_global() const { return dof_to_global_; }

    /// Changes on every build_pattern (unique across systems): solvers check that the system they
    /// factorize is the one they analysed.
    uint64_t pattern_id() const { return pattern_id_; }
    /// Value slot of diagonal entry d (the last entry of column d).
    int32_t diagonal_slot(int32_t d) const { return column_starts_[static_cast<size_t>(d) + 1] - 1; }
    /// -1 if every value is finite, else the column of the first non-finite value.
    int32_t first_nonfinite_column() const;
    /// The node and component free DOF d stands for, for messages: "node n, component x".
    void describe_dof(int32_t d, char* out, size_t size) const;

private:
    /// Value slot of stored entry (row, column), row <= column; -1 if the pattern has none.
    int32_t value_slot(int32_t row, int32_t column) const;
    int32_t dof_count_ = 0;
    size_t element_count_ = 0;
    uint64_t pattern_id_ = 0;
    vec<int32_t> column_starts_;
    vec<int32_t> row_indices_;
    vec<double> values_;
    vec<int32_t> dof_to_global_;
    // Element scatter map: element e's records, one per local node pair (a, b) whose global
    // block (I, J) has I <= J, are [block_record_start_[p], block_record_start_[p + 1]) for its
    // position p = element_position_[e] in the assembly order (element_order_[p] = e).
    struct BlockRecord {
        int32_t slot[3];        // value slot of global entry (3I, 3J + s); rows 3I+1, 3I+2 follow it
        uint16_t local;         // Ke offset of the block: 3a * 3k + 3b
        uint16_t pair : 15;     // its local node pair a k + b
        uint16_t diagonal : 1;  // 1 if I == J (only its upper part r <= s is added)
    };
    /// Adds scale * entry(record, r, s) for every stored entry of element's blocks (position:
    /// its expected place in the assembly order, see add_element_lane): the one scatter of
    /// add_element and add_element_lane.
    template <class Entry>
    void scatter_element(size_t element, size_t position, double scale, const Entry& entry);
    int32_t local_size_ = 0;  // 3k
    vec<int32_t> element_position_;
    vec<int32_t> element_order_;
    vec<size_t> block_record_start_;
    vec<BlockRecord> block_records_;

    /// The element scatter map (records per element, see sparse_system.cpp) over the node
    /// blocks (block_start, block_rows) and DOF columns (column_starts) of the pattern.
    /// order: the elements in assembly order (element_position_'s inverse).
    static void build_scatter_map(const int32_t* elements, const vec<int32_t>& order, size_t k,
                                  const int32_t* free_index, const vec<size_t>& block_start,
                                  const vec<int32_t>& block_rows, const vec<int32_t>& column_starts,
                                  vec<size_t>& record_start, vec<BlockRecord>& records);
};

}  // namespace sh
