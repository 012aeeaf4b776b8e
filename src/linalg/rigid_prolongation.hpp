// The multigrid's coarse space: the rigid motions of aggregates of nodes (aggregation
// multigrid for elasticity, Vanek, Mandel and Brezina 1996). Each aggregate
// (linalg/node_aggregates.hpp) gives six coarse DOFs, the translations of its nodes' rest
// positions and their rotations about its centroid, made orthonormal over the aggregate; P's
// block for node i is then [I / sqrt(n_a) | -[d_i]x G_a], d_i its offset from the centroid
// and G_a the rotations' scaling, so the transfers need 3 numbers per node and 12 per aggregate.
// Rigid motions are what an elastic body's low modes are made of piecewise (a limb swinging,
// a tail bending), which a grid's trilinear displacements capture only where the grid is finer
// than the limb. Measured on the raptor's swing (softhap_bench implicit swing/stvk/cholmod):
// 7.7 CG iterations per step against 17.7 for a trilinear grid of 25 nodes per coarse node,
// 14 against 30 at the worst steps. Smoothing P by a damped Jacobi step of the matrix
// (smoothed aggregation) took as many iterations there (7.5) and a third fewer on a 20 k tet
// cube (4.1 against 5.7), but three entries per node and a coarse factor of twice the fill cost
// as much per iteration as that saved.
#pragma once

#include "core/memory.hpp"
#include "linalg/block_rows.hpp"
#include "linalg/node_lanes.hpp"
#include "linalg/sparse_system.hpp"

#include <Eigen/Dense>

#include <cstdint>

namespace sh {

/// P, the coarse space's prolongation (see the file comment). Coarse DOF 6a + c is aggregate
/// a's translation along axis c (c < 3) or its rotation mode c - 3.
class RigidProlongation {
public:
    /// Builds P for the nodes' aggregates (aggregate_nodes: aggregates of them, each in [0,
    /// aggregates) and each aggregate non-empty, else SH_ERR_INTERNAL) and rest positions (3 per
    /// node). An aggregate whose nodes lie on a line or a point has rotation modes of no motion:
    /// their columns of P are zero and they are marked inert. Allocates; on failure it is as
    /// it was.
    void build(vec<int32_t> aggregate, int32_t aggregates, const double* rest);
    /// The aggregates (coarse nodes).
    int32_t aggregates() const { return aggregates_; }
    /// The coarse DOFs (6 per aggregate).
    int32_t coarse_dofs() const { return 6 * aggregates_; }
    /// coarse = P^T s (s: 1 per node, in node lanes; coarse: coarse_dofs()). Uses the object's
    /// scratch: one transfer at a time.
    void restrict_to(const Node4* s, double* coarse);
    /// out += P u (out: 1 per node, in node lanes; u: coarse_dofs()). Uses the object's
    /// scratch, as restrict_to.
    void prolong_add(const double* u, Node4* out);
    /// out := P^T A P for the matrix rows, over two pseudo-nodes of 3 DOFs per aggregate
    /// (translations, rotations), pattern and values; an inert DOF gets 1 on the diagonal, so
    /// that out is positive definite where A is. Allocates; on failure out is as it was.
    void galerkin(const BlockRows& rows, SparseSystem& out) const;

private:
    /// P's 3 x 6 block of node i.
    Eigen::Matrix<double, 3, 6> block(size_t node) const;
    /// Row a of P^T A P, its blocks for aggregates b >= a, appended to columns and blocks;
    /// members: the nodes of each aggregate (CSR); slot: -1 per aggregate on entry and on return.
    void galerkin_row(const BlockRows& rows, int32_t a, const vec<int32_t>& member_start, const vec<int32_t>& members,
                      vec<int32_t>& slot, vec<int32_t>& columns, vec<Eigen::Matrix<double, 6, 6>>& blocks) const;

    int32_t aggregates_ = 0;
    vec<int32_t> aggregate_;   // per node
    vec<Node4> offset_;        // per node, d_i: its rest position less its aggregate's centroid
    vec<double> scale_;        // per aggregate, 1 / sqrt(its nodes)
    vec<Node4> gauge_;         // per aggregate, G_a's three columns
    vec<uint8_t> inert_;       // per coarse DOF: 1 if its column of P is zero
    vec<Node4> lanes_;         // per aggregate, 2: the transfers' sums (translation, rotation)
};

}  // namespace sh
