// Eigen backends: simplicial LDL^T (AMD ordering, symbolic analysis reused) and preconditioned
// conjugate gradient with warm start. Both read the SparseSystem's upper-triangle CSC arrays in
// place through an Eigen::Map (no copy of the system).
#include "solver/linear_solver.hpp"

#include "core/error.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <cmath>

namespace sh {
namespace {

using CscMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int32_t>;
using CscMap = Eigen::Map<const CscMatrix>;
using VectorMap = Eigen::Map<Eigen::VectorXd>;
using ConstVectorMap = Eigen::Map<const Eigen::VectorXd>;

CscMap map_of(const SparseSystem& a) {
    const Eigen::Index n = a.dof_count();
    return CscMap(n, n, static_cast<Eigen::Index>(a.nonzero_count()), a.column_starts().data(),
                  a.row_indices().data(), a.values().data());
}

// ------------------------------------------------------------------------------------------------

class EigenLdltSolver final : public LinearSolver {
public:
    const char* name() const override { return "eigen-ldlt"; }
    bool is_direct() const override { return true; }
    const char* method() const override { return "eigen simplicial LDL^T (AMD)"; }
    int64_t factor_nonzeros() const override {  // strictly lower L plus D
        return factorized_ ? static_cast<int64_t>(ldlt_.matrixL().nestedExpression().nonZeros() + ldlt_.rows()) : 0;
    }

    void analyze(const SparseSystem& a) override {
        const double t0 = solver_detail::now_seconds();
        analysed_id_ = 0;
        factorized_ = false;
        if (a.dof_count() > 0) {
            ldlt_.analyzePattern(map_of(a));
            SH_REQUIRE(ldlt_.info() == Eigen::Success, SH_ERR_SOLVER, "eigen-ldlt: symbolic analysis failed");
            work_.assign(static_cast<size_t>(a.dof_count()), 0.0);
            inverse_d_.assign(static_cast<size_t>(a.dof_count()), 0.0);
        }
        analysed_id_ = a.pattern_id();
        analyze_seconds = solver_detail::now_seconds() - t0;
    }

    void factorize(const SparseSystem& a) override {
        const double t0 = solver_detail::now_seconds();
        solver_detail::require_analysed(a, analysed_id_, name());
        factorized_ = false;
        if (a.dof_count() > 0) {
            solver_detail::require_finite_values(a, name());
            ldlt_.factorize(map_of(a));
            // Eigen stops at an exact zero pivot (NumericalIssue) but accepts negative ones (LDL^T
            // of an indefinite matrix); we need positive definite, so check D. The first bad pivot
            // in elimination order names its original column through the permutation.
            const Eigen::VectorXd d = ldlt_.vectorD();  // Eigen returns a copy
            for (Eigen::Index k = 0; k < d.size(); ++k)
                if (!(d[k] > 0.0)) {
                    const auto& pinv = ldlt_.permutationPinv();
                    const int32_t column = pinv.size() > 0 ? pinv.indices()[k] : static_cast<int32_t>(k);
                    solver_detail::throw_not_positive_definite(
                        a, column, name(), format("pivot %g at elimination step %ld", d[k], static_cast<long>(k)).c_str());
                }
            SH_REQUIRE(ldlt_.info() == Eigen::Success, SH_ERR_SOLVER, "eigen-ldlt: numeric factorisation failed");
            for (Eigen::Index k = 0; k < d.size(); ++k) inverse_d_[static_cast<size_t>(k)] = 1.0 / d[k];
        }
        factorized_ = true;
        factorize_seconds = solver_detail::now_seconds() - t0;
    }

    int solve(const SparseSystem& a, const double* b, double* x) override {
        const double t0 = solver_detail::now_seconds();
        solver_detail::require_analysed(a, analysed_id_, name());
        SH_REQUIRE(factorized_, SH_ERR_INTERNAL, "eigen-ldlt: solve before a successful factorize");
        const Eigen::Index n = a.dof_count();
        if (n > 0) {
            // Eigen's solve() ends with an in-place permutation that allocates a mask; the same
            // steps through a preallocated vector allocate nothing.
            VectorMap y(work_.data(), n);
            ConstVectorMap bm(b, n);
            if (ldlt_.permutationP().size() > 0)
                y.noalias() = ldlt_.permutationP() * bm;
            else
                y = bm;
            ldlt_.matrixL().solveInPlace(y);
            y.array() *= ConstVectorMap(inverse_d_.data(), n).array();
            ldlt_.matrixU().solveInPlace(y);
            VectorMap xm(x, n);
            if (ldlt_.permutationPinv().size() > 0)
                xm.noalias() = ldlt_.permutationPinv() * y;
            else
                xm = y;
            solver_detail::require_finite_solution(a, x, name());
        }
        solve_seconds = solver_detail::now_seconds() - t0;
        return 1;
    }

private:
    Eigen::SimplicialLDLT<CscMap, Eigen::Upper, Eigen::AMDOrdering<int32_t>> ldlt_;
    vec<double> work_;       // permuted right-hand side / solution, dof_count()
    vec<double> inverse_d_;  // 1 / D, dof_count()
    uint64_t analysed_id_ = 0;
    bool factorized_ = false;
};

// ------------------------------------------------------------------------------------------------

// The system stores only its upper triangle, so CG must use Eigen::Upper (a selfadjoint product
// per iteration); Eigen::Lower|Eigen::Upper would take the stored triangle for the whole matrix.
template <class Preconditioner>
class EigenCgSolver final : public LinearSolver {
public:
    EigenCgSolver(double tolerance, int max_iterations, const char* name)
        : tolerance_(tolerance), max_iterations_(max_iterations), name_(name) {}

    const char* name() const override { return name_; }

    void analyze(const SparseSystem& a) override {
        const double t0 = solver_detail::now_seconds();
        analysed_id_ = 0;
        factorized_ = false;
        if (a.dof_count() > 0) {
            cg_.analyzePattern(map_of(a));
            SH_REQUIRE(cg_.info() == Eigen::Success, SH_ERR_SOLVER, "%s: preconditioner analysis failed", name_);
        }
        analysed_id_ = a.pattern_id();
        analyze_seconds = solver_detail::now_seconds() - t0;
    }

    void factorize(const SparseSystem& a) override {
        const double t0 = solver_detail::now_seconds();
        solver_detail::require_analysed(a, analysed_id_, name_);
        factorized_ = false;
        if (a.dof_count() > 0) {
            solver_detail::require_finite_values(a, name_);
            // A non-positive diagonal entry proves A is not positive definite (and would make the
            // Jacobi preconditioner indefinite).
            const double* v = a.values().data();
            for (int32_t d = 0; d < a.dof_count(); ++d)
                if (!(v[a.diagonal_slot(d)] > 0.0))
                    solver_detail::throw_not_positive_definite(
                        a, d, name_, format("diagonal entry %g", v[a.diagonal_slot(d)]).c_str());
            cg_.factorize(map_of(a));
            SH_REQUIRE(cg_.info() == Eigen::Success, SH_ERR_SOLVER, "%s: preconditioner factorisation failed", name_);
        }
        factorized_values_ = a.values().data();
        factorized_ = true;
        factorize_seconds = solver_detail::now_seconds() - t0;
    }

    int solve(const SparseSystem& a, const double* b, double* x) override {
        const double t0 = solver_detail::now_seconds();
        solver_detail::require_analysed(a, analysed_id_, name_);
        // CG multiplies with the matrix it was given at factorize: it must still be a's storage.
        SH_REQUIRE(factorized_ && factorized_values_ == a.values().data(), SH_ERR_INTERNAL,
                   "%s: solve before a successful factorize of this system", name_);
        const Eigen::Index n = a.dof_count();
        int iterations = 0;
        last_relative_residual = 0.0;
        if (n > 0) {
            ConstVectorMap bm(b, n);
            SH_REQUIRE(bm.allFinite(), SH_ERR_SOLVER, "%s: non-finite right-hand side", name_);
            VectorMap xm(x, n);
            if (!xm.allFinite()) xm.setZero();  // a non-finite guess would poison every iterate
            cg_.setTolerance(tolerance_);
            cg_.setMaxIterations(max_iterations_);
            xm = cg_.solveWithGuess(bm, xm);
            iterations = static_cast<int>(cg_.iterations());
            last_relative_residual = cg_.error();
            solve_seconds = solver_detail::now_seconds() - t0;
            if (cg_.info() != Eigen::Success)
                throw Error(SH_ERR_NOT_CONVERGED,
                            format("%s: relative residual %.3g after %d iterations, tolerance %.3g", name_,
                                   last_relative_residual, iterations, tolerance_));
            solver_detail::require_finite_solution(a, x, name_);
        }
        solve_seconds = solver_detail::now_seconds() - t0;
        return iterations;
    }

private:
    // MatrixType CscMatrix: the solver keeps an Eigen::Ref to the Map given at factorize (no copy).
    Eigen::ConjugateGradient<CscMatrix, Eigen::Upper, Preconditioner> cg_;
    double tolerance_;
    int max_iterations_;
    const char* name_;
    uint64_t analysed_id_ = 0;
    const double* factorized_values_ = nullptr;
    bool factorized_ = false;
};

}  // namespace

LinearSolverPtr make_ldlt_solver() { return LinearSolverPtr(create<EigenLdltSolver>()); }

LinearSolverPtr make_cg_solver(double tolerance, int max_iterations, CgPreconditioner preconditioner) {
    SH_REQUIRE(std::isfinite(tolerance) && tolerance > 0.0, SH_ERR_INVALID_ARGUMENT,
               "conjugate gradient: tolerance %g must be finite and > 0", tolerance);
    SH_REQUIRE(max_iterations >= 1, SH_ERR_INVALID_ARGUMENT, "conjugate gradient: max_iterations %d must be >= 1",
               max_iterations);
    switch (preconditioner) {
        case CgPreconditioner::Jacobi:
            return LinearSolverPtr(create<EigenCgSolver<Eigen::DiagonalPreconditioner<double>>>(
                tolerance, max_iterations, "eigen-cg-jacobi"));
        case CgPreconditioner::IncompleteCholesky:
            return LinearSolverPtr(
                create<EigenCgSolver<Eigen::IncompleteCholesky<double, Eigen::Upper, Eigen::AMDOrdering<int32_t>>>>(
                    tolerance, max_iterations, "eigen-cg-ichol"));
    }
    throw Error(SH_ERR_INVALID_ARGUMENT,
                format("conjugate gradient: unknown preconditioner %d", static_cast<int>(preconditioner)));
}

}  // namespace sh
