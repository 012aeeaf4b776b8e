// Eigen backends: simplicial LDL^T (AMD ordering, symbolic analysis reused) and conjugate
// gradient with a Jacobi preconditioner and warm start. Both read the SparseSystem's
// upper-triangle CSC arrays in place through an Eigen::Map (no copy of the system).
#include "linalg/linear_solver.hpp"

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

protected:
    void do_analyze(const SparseSystem& a, const EliminationOrder*) override {
        ldlt_.analyzePattern(map_of(a));
        SH_REQUIRE(ldlt_.info() == Eigen::Success, SH_ERR_SOLVER, "eigen-ldlt: symbolic analysis failed");
        work_.assign(static_cast<size_t>(a.dof_count()), 0.0);
        inverse_d_.assign(static_cast<size_t>(a.dof_count()), 0.0);
    }

    void do_factorize(const SparseSystem& a) override {
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
        if (estimated_work_.solve == 0.0) measure_work();
    }

    int do_solve(const SparseSystem& a, const double* b, double* x) override {
        const Eigen::Index n = a.dof_count();
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
        return 1;
    }

private:
    // How many times a solve's operations per second the simplicial factorisation does (one
    // column at a time, no dense kernels).
    static constexpr double kSimplicialSpeed = 1.5;

    // estimated_work_ from L's column counts c_j (strictly below the diagonal): about sum c_j^2
    // operations to factorise, n + sum c_j entries.
    void measure_work() {
        const auto& l = ldlt_.matrixL().nestedExpression();
        double flops = 0.0, entries = static_cast<double>(l.cols());
        for (Eigen::Index j = 0; j < l.outerSize(); ++j) {
            const double c = static_cast<double>(l.innerVector(j).nonZeros());
            flops += c * c;
            entries += c;
        }
        estimated_work_ = factor_work(flops, entries, kSimplicialSpeed);
    }

    Eigen::SimplicialLDLT<CscMap, Eigen::Upper, Eigen::AMDOrdering<int32_t>> ldlt_;
    vec<double> work_;       // permuted right-hand side / solution, dof_count()
    vec<double> inverse_d_;  // 1 / D, dof_count()
};

// ------------------------------------------------------------------------------------------------

// The system stores only its upper triangle, so CG must use Eigen::Upper (a selfadjoint product
// per iteration); Eigen::Lower|Eigen::Upper would take the stored triangle for the whole matrix.
class EigenCgSolver final : public LinearSolver {
public:
    EigenCgSolver(double tolerance, int max_iterations) : tolerance_(tolerance), max_iterations_(max_iterations) {}

    const char* name() const override { return "eigen-cg-jacobi"; }
    bool is_direct() const override { return false; }

protected:
    void do_analyze(const SparseSystem& a, const EliminationOrder*) override {
        cg_.analyzePattern(map_of(a));
        SH_REQUIRE(cg_.info() == Eigen::Success, SH_ERR_SOLVER, "%s: preconditioner analysis failed", name());
    }

    void do_factorize(const SparseSystem& a) override {
        // A non-positive diagonal entry proves A is not positive definite (and would make the
        // Jacobi preconditioner indefinite).
        const double* v = a.values().data();
        for (int32_t d = 0; d < a.dof_count(); ++d)
            if (!(v[a.diagonal_slot(d)] > 0.0))
                solver_detail::throw_not_positive_definite(a, d, name(),
                                                           format("diagonal entry %g", v[a.diagonal_slot(d)]).c_str());
        cg_.factorize(map_of(a));
        SH_REQUIRE(cg_.info() == Eigen::Success, SH_ERR_SOLVER, "%s: preconditioner factorisation failed", name());
        factorized_values_ = a.values().data();
    }

    int do_solve(const SparseSystem& a, const double* b, double* x) override {
        // CG multiplies with the matrix it was given at factorize: it must still be a's storage.
        SH_REQUIRE(factorized_values_ == a.values().data(), SH_ERR_INTERNAL,
                   "%s: solve with another system than the one factorised", name());
        const Eigen::Index n = a.dof_count();
        ConstVectorMap bm(b, n);
        SH_REQUIRE(bm.allFinite(), SH_ERR_SOLVER, "%s: non-finite right-hand side", name());
        VectorMap xm(x, n);
        if (!xm.allFinite()) xm.setZero();  // a non-finite guess would poison every iterate
        cg_.setTolerance(tolerance_);
        cg_.setMaxIterations(max_iterations_);
        xm = cg_.solveWithGuess(bm, xm);
        const int iterations = static_cast<int>(cg_.iterations());
        if (cg_.info() != Eigen::Success)
            throw Error(SH_ERR_NOT_CONVERGED, format("%s: relative residual %.3g after %d iterations, tolerance %.3g",
                                                     name(), cg_.error(), iterations, tolerance_));
        return iterations;
    }

private:
    // MatrixType CscMatrix: the solver keeps an Eigen::Ref to the Map given at factorize (no copy).
    Eigen::ConjugateGradient<CscMatrix, Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg_;
    double tolerance_;
    int max_iterations_;
    const double* factorized_values_ = nullptr;
};

}  // namespace

LinearSolverPtr make_ldlt_solver() { return LinearSolverPtr(create<EigenLdltSolver>()); }

LinearSolverPtr make_cg_solver(double tolerance, int max_iterations) {
    SH_REQUIRE(std::isfinite(tolerance) && tolerance > 0.0, SH_ERR_INVALID_ARGUMENT,
               "conjugate gradient: tolerance %g must be finite and > 0", tolerance);
    SH_REQUIRE(max_iterations >= 1, SH_ERR_INVALID_ARGUMENT, "conjugate gradient: max_iterations %d must be >= 1",
               max_iterations);
    return LinearSolverPtr(create<EigenCgSolver>(tolerance, max_iterations));
}

}  // namespace sh
