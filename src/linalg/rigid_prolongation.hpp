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

#include <cstddef>
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
    /// coarse = P^T s (s: 1 per node, in node lanes; coarse: coarse_dofs()).
    void restrict_to(const Node4* s, double* coarse) const {
        restrict_with([s](size_t i) { return s[i]; }, coarse);
    }
    /// out += P u (out: 1 per node, in node lanes; u: coarse_dofs()).
    void prolong_add(const double* u, Node4* out) const {
        prolong_with(u, [out](size_t i, Node4 value) { out[i] += value; });
    }
    /// restrict_to for s_i = node_value(i), computed as the pass reaches node i (a caller's
    /// transform of its vector, e.g. a rotation, without an array for the result).
    template <class NodeValue>
    void restrict_with(const NodeValue& node_value, double* coarse) const {
        // P_i^T s_i: the translations take s_i / sqrt(n_a); rotation k takes (g_k x d_i) . s_i =
        // g_k . (d_i x s_i). Aggregate by aggregate, so that the sums stay in registers.
        for (size_t a = 0; a < static_cast<size_t>(aggregates_); ++a) {
            Node4 translation{}, moment{};
            for (int32_t k = member_start_[a]; k < member_start_[a + 1]; ++k) {
                const size_t i = static_cast<size_t>(members_[static_cast<size_t>(k)]);
                const Node4 s = node_value(i);
                translation += s;
                moment += node_cross(offset_[i], s);
            }
            store_restriction(a, translation, moment, coarse);
        }
    }
    /// sink(i, (P u)_i) for each node i in turn, aggregate by aggregate (prolong_add with the
    /// caller's use of each node's value, e.g. rotated into its own vector).
    template <class NodeSink>
    void prolong_with(const double* u, const NodeSink& sink) const {
        // P_i u = t_a / sqrt(n_a) + w_a x d_i, w_a = G_a r_a for aggregate a's translation t_a
        // and rotation modes r_a.
        for (size_t a = 0; a < static_cast<size_t>(aggregates_); ++a) {
            const double* ua = u + 6 * a;
            const Node4 translation = scale_[a] * load_node(ua), turn = block_times(&gauge_[3 * a], load_node(ua + 3));
            for (int32_t k = member_start_[a]; k < member_start_[a + 1]; ++k) {
                const size_t i = static_cast<size_t>(members_[static_cast<size_t>(k)]);
                sink(i, translation + node_cross(turn, offset_[i]));
            }
        }
    }
    /// out := P^T A P for the matrix rows, over two pseudo-nodes of 3 DOFs per aggregate
    /// (translations, rotations), pattern and values; an inert DOF gets 1 on the diagonal, so
    /// that out is positive definite where A is. Allocates; on failure out is as it was.
    void galerkin(const BlockRows& rows, SparseSystem& out) const;

private:
    static Node4 node_cross(Node4 a, Node4 b) {
        return Node4{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0], 0.0};
    }
    /// Aggregate a's six coarse entries from the sums over its nodes of s_i and d_i x s_i.
    void store_restriction(size_t a, Node4 translation, Node4 moment, double* coarse) const {
        translation *= scale_[a];
        for (int k = 0; k < 3; ++k) {
            const Node4 g = gauge_[3 * a + static_cast<size_t>(k)] * moment;
            coarse[6 * a + static_cast<size_t>(k)] = translation[k];
            coarse[6 * a + 3 + static_cast<size_t>(k)] = g[0] + g[1] + g[2];
        }
    }
    /// P's 3 x 6 block of node i.
    Eigen::Matrix<double, 3, 6> block(size_t node) const;
    /// Row a of P^T A P, its blocks for aggregates b >= a, appended to columns and blocks;
    /// slot: -1 per aggregate on entry and on return.
    void galerkin_row(const BlockRows& rows, int32_t a, vec<int32_t>& slot, vec<int32_t>& columns,
                      vec<Eigen::Matrix<double, 6, 6>>& blocks) const;

    int32_t aggregates_ = 0;
    vec<int32_t> aggregate_;   // per node
    vec<int32_t> member_start_;  // per aggregate + 1: where its nodes start in members_
    vec<int32_t> members_;       // the nodes, aggregate by aggregate (in node order within each)
    vec<Node4> offset_;        // per node, d_i: its rest position less its aggregate's centroid
    vec<double> scale_;        // per aggregate, 1 / sqrt(its nodes)
    vec<Node4> gauge_;         // per aggregate, G_a's three columns
    vec<uint8_t> inert_;       // per coarse DOF: 1 if its column of P is zero
};

}  // namespace sh
