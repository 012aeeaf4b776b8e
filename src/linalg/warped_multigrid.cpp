#include "linalg/warped_multigrid.hpp"

#include "core/error.hpp"
#include "linalg/block_rows.hpp"
#include "linalg/node_aggregates.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <utility>

namespace sh {
namespace {

// What one of the cycle's operations costs against one of a sparse solve's: the stored
// triangle (2.5 MB at 20 k tets) stays in cache across the cycle and is read in 4-double lanes,
// where a solve streams its factor (29 MB) from memory. Measured on the raptor's 17,793 DOF
// (AMD EPYC, AVX-512): 0.54 ms per iteration against 3.6 ms per CHOLMOD solve.
constexpr double kCachedOperationWeight = 0.22;

}  // namespace

void WarpedMultigrid::build_coarse(const SparseSystem& a0, const double* rest) {
    BlockRows rows;
    rows.build(a0, blocks_);
    vec<int32_t> aggregate;
    const int32_t aggregates = aggregate_nodes(rows, aggregate);
    prolongation_.build(std::move(aggregate), aggregates, rest);
    prolongation_.galerkin(rows, coarse_);
    coarse_solver_ = make_solve_often_solver();
    coarse_solver_->analyze(coarse_);
    try {
        coarse_solver_->factorize(coarse_);
    } catch (const Error& e) {
        if (e.status() != SH_ERR_SOLVER) throw;
        throw Error(SH_ERR_SOLVER, format("multigrid: the coarse matrix of %d aggregates: %s", aggregates,
                                          e.message().c_str()));
    }
    coarse_rhs_.assign(static_cast<size_t>(prolongation_.coarse_dofs()), 0.0);
    coarse_solution_.assign(coarse_rhs_.size(), 0.0);
    // One solve here, so that the backend's solve workspace is allocated by the build and not
    // by the first cycle.
    coarse_solver_->solve(coarse_, coarse_rhs_.data(), coarse_solution_.data());
}

void WarpedMultigrid::build(const SparseSystem& a0, const double* rest) {
    built_ = false;
    blocks_.build(a0);
    const int32_t nodes = blocks_.node_count();
    build_coarse(a0, rest);
    inverse_diagonal_.assign(3 * static_cast<size_t>(nodes), Node4{});
    turn_.assign(3 * static_cast<size_t>(nodes), Node4{});
    z_.assign(static_cast<size_t>(nodes), Node4{});
    pushed_.assign(static_cast<size_t>(nodes), Node4{});
    residual_.assign(static_cast<size_t>(nodes), Node4{});
    change_.assign(static_cast<size_t>(nodes), Node4{});
    built_ = true;
}

void WarpedMultigrid::prepare(const SparseSystem& a, const double* rotations) {
    SH_REQUIRE(built_for(a), SH_ERR_INTERNAL, "multigrid: prepared with another pattern than it was built for");
    system_ = &a;
    for (int32_t i = 0; i < blocks_.node_count(); ++i) {
        const double* R = rotations + 9 * static_cast<size_t>(i);  // row-major
        Node4* turn = &turn_[3 * static_cast<size_t>(i)];
        for (int c = 0; c < 3; ++c) turn[c] = Node4{R[c], R[3 + c], R[6 + c], 0.0};  // R's columns
    }
    for (int32_t i = 0; i < blocks_.node_count(); ++i) {
        double diagonal[3][3];
        blocks_.diagonal_block(*system_, i, diagonal);
        const Eigen::Matrix3d d = Eigen::Map<const Eigen::Matrix3d>(&diagonal[0][0]);  // symmetric
        // Positive definite by its leading minors (Sylvester); the inverse in closed form,
        // where a 3x3 Cholesky factorisation and solve take several times as long.
        const bool definite = d(0, 0) > 0.0 && d(0, 0) * d(1, 1) - d(0, 1) * d(0, 1) > 0.0 && d.determinant() > 0.0;
        const Eigen::Matrix3d inverse = d.inverse();
        SH_REQUIRE(definite && inverse.allFinite(), SH_ERR_SOLVER,
                   "multigrid: the diagonal block of free node %d is not positive definite", i);
        for (int c = 0; c < 3; ++c)
            inverse_diagonal_[3 * static_cast<size_t>(i) + static_cast<size_t>(c)] =
                Node4{inverse(0, c), inverse(1, c), inverse(2, c), 0.0};
    }
}

void WarpedMultigrid::backward_sweep(const double* r, double* z) {
    // Row J sums its right part from the pushes of the nodes after it (already new) and its
    // left part from the blocks it holds (the nodes before it, not yet changed). pushed_ is
    // zero between passes: each row's sum is cleared once read, where a pass of its own would
    // clear them all first.
    for (int32_t j = blocks_.node_count() - 1; j >= 0; --j) {
        const size_t n = static_cast<size_t>(j);
        const Node4 s = load_node(r + 3 * n) - pushed_[n] - blocks_.pull(*system_, j, z_.data());
        pushed_[n] = Node4{};
        const Node4 updated = block_times(&inverse_diagonal_[3 * n], s);
        blocks_.push(*system_, j, updated, pushed_.data());
        change_[n] = updated - z_[n];
        z_[n] = updated;
        store_node(updated, z + 3 * n);
    }
}

void WarpedMultigrid::first_sweep(const double* r) {
    // residual_ gathers -U z_ from each node's push once its value is final. Row J's pushes
    // come from the nodes after it, so it is cleared when the pass reaches it.
    for (int32_t j = 0; j < blocks_.node_count(); ++j) {
        const size_t n = static_cast<size_t>(j);
        residual_[n] = Node4{};
        z_[n] = block_times(&inverse_diagonal_[3 * n], load_node(r + 3 * n) - blocks_.pull(*system_, j, z_.data()));
        blocks_.push(*system_, j, -z_[n], residual_.data());
    }
}

void WarpedMultigrid::coarse_correction() {
    // Each node's rotation is applied as the transfer passes it (R^T e into the restriction,
    // R into the prolongation's value), where a pass of its own would write and read the
    // rotated vector once more.
    prolongation_.restrict_with([this](size_t i) { return block_transpose_times(&turn_[3 * i], residual_[i]); },
                                coarse_rhs_.data());
    coarse_solver_->solve(coarse_, coarse_rhs_.data(), coarse_solution_.data());
    prolongation_.prolong_with(coarse_solution_.data(),
                               [this](size_t i, Node4 value) { z_[i] += block_times(&turn_[3 * i], value); });
}

void WarpedMultigrid::apply(const double* r, double* z) {
    first_sweep(r);
    coarse_correction();
    backward_sweep(r, z);
}

bool WarpedMultigrid::apply_with_product(const double* r, double* z, double* az) {
    apply(r, z);
    // Node j's sweep solved its row for r with the nodes before it (i < j) not yet changed:
    // (A z)_j = r_j + sum over i < j of A_ji change_i.
    for (int32_t j = 0; j < blocks_.node_count(); ++j) {
        const size_t n = static_cast<size_t>(j);
        store_node(load_node(r + 3 * n) + blocks_.pull(*system_, j, change_.data()), az + 3 * n);
    }
    return true;
}

void WarpedMultigrid::multiply(const double* x, double* y) {
    // Node J's row gathers A_JI x_I from its blocks (I < J) and its diagonal block's product;
    // the blocks push A_IJ x_J into the rows before it, whose sums are final once the pass is
    // over.
    for (int32_t j = 0; j < blocks_.node_count(); ++j) {
        const size_t n = static_cast<size_t>(j);
        z_[n] = load_node(x + 3 * n);
        pushed_[n] += blocks_.diagonal_times(*system_, j, z_[n]) + blocks_.pull(*system_, j, z_.data());
        blocks_.push(*system_, j, z_[n], pushed_.data());
    }
    for (size_t n = 0; n < pushed_.size(); ++n) {
        store_node(pushed_[n], y + 3 * n);
        pushed_[n] = Node4{};  // zero between passes (see backward_sweep)
    }
}

double WarpedMultigrid::iteration_work() const {
    // Per stored block, 36 operations for each sweep (its pull and its push: the first sweep
    // with its residual, the backward sweep) and 18 for the half product CG's A p takes from
    // the cycle; the transfers (per node a rotation and a cross product each way): they count
    // kCachedOperationWeight of a sparse solve's operation each. The coarse solve is a sparse
    // solve, whose factor the sweeps' passes push out of cache: its own work, at full weight.
    // On the raptor's 17,793 DOF this counts 1.2e6 operations, 0.18 of a solve with the fine
    // factor (6.9e6); measured in one busy hour, a cycle with its half product took 0.71-0.75
    // ms (the sweeps 0.18-0.21 ms each, the coarse correction 0.23 of which its solve 0.13,
    // the half product 0.11) and a fine solve 2.8-3.2 ms: 0.25 of one. The weights favour the
    // multigrid a little against a factorisation's solves.
    const double stored = static_cast<double>(blocks_.block_count()) + blocks_.node_count();
    const double transfers = 60.0 * blocks_.node_count();
    return kCachedOperationWeight * ((2.0 * 36.0 + 18.0) * stored + transfers) + coarse_solver_->work().solve;
}

}  // namespace sh
