// A two-level multigrid cycle for the implicit step's matrix A = M + h D + h^2 K(x) under large
// rotation, used as conjugate gradients' preconditioner. The coarse level is the rigid motions
// of aggregates of nodes at the rest shape (linalg/rigid_prolongation.hpp: P), with
// the Galerkin coarse matrix P^T A0 P of the matrix at rest, factorised once by the direct
// solver laid out for solves (make_solve_often_solver); the current matrix differs from A0 mostly by each node's rotation R, so the
// coarse correction is warped by them (restricted by P^T R^T, prolonged by R P) instead of
// rebuilt. The smoother is block Gauss-Seidel on the
// current matrix (3x3 node blocks, forward before and backward after the coarse correction,
// so the cycle is symmetric), reading the system's stored triangle in place (UpperBlocks). Its
// setup per step is the diagonal blocks' inverses and the rotations; no factorisation of the
// fine matrix, which at 20 k tets costs 20-26 solves.
#pragma once

#include "core/memory.hpp"
#include "linalg/linear_solver.hpp"
#include "linalg/node_lanes.hpp"
#include "linalg/preconditioned_cg.hpp"
#include "linalg/rigid_prolongation.hpp"
#include "linalg/sparse_system.hpp"
#include "linalg/upper_blocks.hpp"

#include <cstdint>

namespace sh {

/// Two-level warped multigrid preconditioner (see the file comment).
class WarpedMultigrid final : public Preconditioner {
public:
    /// Builds the hierarchy for a0's pattern from a0's values (the step's matrix assembled at
    /// the rest shape) and the free nodes' rest positions (3 per free node, free order).
    /// Allocates; on failure (std::bad_alloc, SH_ERR_SOLVER) it is left unbuilt.
    void build(const SparseSystem& a0, const double* rest);
    /// True once built for system's pattern.
    bool built_for(const SparseSystem& system) const { return built_ && blocks_.matches(system); }
    /// Forgets the hierarchy (a new pattern, step size or material needs a new one).
    void clear() { built_ = false; }
    /// Takes a's current values (read in place by the following applies: a must stay as it
    /// is until then) and the free nodes' rotations (9 per free node, row-major, rest frame to
    /// current). Throws SH_ERR_SOLVER naming the
    /// node whose diagonal block is not positive definite.
    void prepare(const SparseSystem& a, const double* rotations);
    /// z = one V-cycle applied to r. Throws SH_ERR_SOLVER if the coarse solve comes out
    /// non-finite (a non-finite r or rotation).
    void apply(const double* r, double* z) override;
    /// The V-cycle, and az = A z for half a product: the backward sweep leaves each node's
    /// row of A z equal to r but for the blocks left of its diagonal times the changes the
    /// sweep made after it (Eisenstat's observation), so only those blocks are read again.
    bool apply_with_product(const double* r, double* z, double* az) override;
    /// y = A x for the prepared system (x, y: 3 per node; y may be x): the same product as
    /// SparseSystem::multiply, by node blocks (one pass over the nodes, reading their stored
    /// blocks' values and no row indices), for CG's warm start. Uses the cycle's iterate and
    /// push sums as scratch.
    void multiply(const double* x, double* y);
    /// One apply's work plus CG's product (half a product, apply_with_product), in a sparse
    /// solve's operations (FactorWork). Once built.
    double iteration_work() const;
    /// Coarse nodes (aggregates: 6 coarse DOFs each), for reports and tests.
    int32_t coarse_nodes() const { return prolongation_.aggregates(); }

private:
    /// The aggregates, P and the factorised coarse matrix from a0 and the rest positions.
    void build_coarse(const SparseSystem& a0, const double* rest);
    /// One block Gauss-Seidel sweep over the nodes backward, on z_ towards r; change_ := what
    /// it added to z_, and z := z_ (3 per node).
    void backward_sweep(const double* r, double* z);
    /// The forward sweep from z_ = 0, then residual_ = r - A z_. From zero only the blocks
    /// left of the diagonal meet a nonzero z_, and the sweep zeroes each row's residual up to
    /// its diagonal, so that r - A z_ = -U z_ (U the blocks right of it): one pass over the
    /// blocks where a full sweep and a product make two.
    void first_sweep(const double* r);
    /// z_ += R P (coarse solve of P^T R^T residual_).
    void coarse_correction();

    bool built_ = false;
    UpperBlocks blocks_;           // the system's block structure
    const SparseSystem* system_ = nullptr;  // the prepared system, read in place
    vec<Node4> inverse_diagonal_;  // 3 columns per node: the current diagonal blocks' inverses
    vec<Node4> turn_;              // 3 per node: the columns of its rotation R
    RigidProlongation prolongation_;
    SparseSystem coarse_;                 // P^T A0 P
    LinearSolverPtr coarse_solver_;       // its factorisation
    vec<double> coarse_rhs_;              // the restricted residual (6 per aggregate)
    vec<double> coarse_solution_;         // the coarse correction
    vec<Node4> z_;                        // the cycle's iterate
    vec<Node4> residual_;                 // r - A z_ after the first sweep
    vec<Node4> change_;                   // the backward sweep's change of z_
    vec<Node4> pushed_;                   // the backward sweep's sums from the nodes after each (0 between passes)
};

}  // namespace sh
