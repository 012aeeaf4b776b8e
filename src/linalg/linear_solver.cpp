#include "linalg/linear_solver.hpp"

#include "core/clock.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace sh {

void LinearSolverDelete::operator()(LinearSolver* solver) const noexcept {
    if (!solver) return;
    void* memory = dynamic_cast<void*>(solver);  // start of the most-derived object, as allocated
    solver->~LinearSolver();
    deallocate(memory);
}

namespace {

void require_analysed(const SparseSystem& a, uint64_t analysed_id, const char* backend) {
    SH_REQUIRE(analysed_id != 0 && a.pattern_id() == analysed_id, SH_ERR_INTERNAL,
               "%s: the system's pattern was not analysed (call analyze after build_pattern)", backend);
}

void require_finite_values(const SparseSystem& a, const char* backend) {
    const int32_t column = a.first_nonfinite_column();
    if (column < 0) return;
    char dof[96];
    a.describe_dof(column, dof, sizeof dof);
    throw Error(SH_ERR_SOLVER, format("%s: non-finite matrix value in column %d (%s)", backend, column, dof));
}

void require_finite_solution(const SparseSystem& a, const double* x, const char* backend) {
    constexpr uint64_t kExponent = 0x7ff0000000000000ull;
    const size_t n = static_cast<size_t>(a.dof_count());
    uint64_t bad = 0;
    for (size_t i = 0; i < n; ++i) {
        uint64_t bits;
        std::memcpy(&bits, x + i, sizeof bits);
        bad |= static_cast<uint64_t>((bits & kExponent) == kExponent);
    }
    if (!bad) return;
    for (size_t i = 0; i < n; ++i)
        if (!std::isfinite(x[i])) {
            char dof[96];
            a.describe_dof(static_cast<int32_t>(i), dof, sizeof dof);
            throw Error(SH_ERR_SOLVER, format("%s: non-finite solution at free DOF %zu (%s): non-finite "
                                              "right-hand side or singular matrix", backend, i, dof));
        }
}

}  // namespace

FactorWork factor_work(double flops, double factor_entries, double speed) {
    FactorWork work;
    work.solve = 4.0 * factor_entries;
    work.factorize = std::max(kMinFactorizeSolves * work.solve, flops / speed);
    return work;
}

void LinearSolver::analyze(const SparseSystem& a, const EliminationOrder* suggested) {
    analysed_id_ = 0;
    factorized_ = false;
    SH_REQUIRE(!suggested || suggested->nodes.size() * 3 == static_cast<size_t>(a.dof_count()), SH_ERR_INTERNAL,
               "%s: suggested order of %zu nodes for %d DOFs", name(), suggested ? suggested->nodes.size() : 0,
               a.dof_count());
    analysed_dofs_ = 0;
    estimated_work_ = FactorWork{};
    if (a.dof_count() > 0) do_analyze(a, suggested);
    analysed_id_ = a.pattern_id();
    analysed_dofs_ = a.dof_count();
}

bool LinearSolver::elimination_order(EliminationOrder& out) const {
    return analysed_id_ != 0 && analysed_dofs_ > 0 && do_elimination_order(out);
}

void LinearSolver::factorize(const SparseSystem& a) {
    const double t0 = now_seconds();
    require_analysed(a, analysed_id_, name());
    factorized_ = false;
    if (a.dof_count() > 0) {
        require_finite_values(a, name());
        do_factorize(a);
    }
    factorized_ = true;
    factorize_seconds = now_seconds() - t0;
}

int LinearSolver::solve(const SparseSystem& a, const double* b, double* x) {
    const double t0 = now_seconds();
    require_analysed(a, analysed_id_, name());
    SH_REQUIRE(factorized_, SH_ERR_INTERNAL, "%s: solve before a successful factorize", name());
    int iterations = 0;
    if (a.dof_count() > 0) {
        try {
            iterations = do_solve(a, b, x);
        } catch (...) {  // CG out of iterations: its time still counts
            solve_seconds = now_seconds() - t0;
            throw;
        }
        require_finite_solution(a, x, name());
    }
    solve_seconds = now_seconds() - t0;
    return iterations;
}

LinearSolverPtr make_linear_solver(LinearSolverKind kind, double cg_tolerance, int cg_max_iterations) {
    switch (kind) {
        case LinearSolverKind::Cholmod:
            return make_cholmod_solver();
        case LinearSolverKind::Ldlt:
            return make_ldlt_solver();
        case LinearSolverKind::ConjugateGradient:
            // Jacobi, by measurement on raptorTetra_19409 (17340 DOF, M + h^2 K, warm start, 1e-6):
            // Eigen's IncompleteCholesky needed ~3x fewer iterations (h = 1e-3: 33 vs 114) but its
            // set-up cost 50-130 ms and ~350k heap allocations per factorize and each iteration about
            // twice as much, so per step Jacobi was faster where CG is usable at all (h = 1e-3:
            // ~40 ms vs ~100 ms) and on par at h = 1e-2; Jacobi's set-up is 0.3 ms, allocation-free.
            return make_cg_solver(cg_tolerance, cg_max_iterations);
    }
    throw Error(SH_ERR_INVALID_ARGUMENT, format("linear solver: unknown kind %d", static_cast<int>(kind)));
}

LinearSolverKind default_direct_solver() {
#if SOFTHAP_WITH_CHOLMOD
    return LinearSolverKind::Cholmod;
#else
    return LinearSolverKind::Ldlt;
#endif
}

LinearSolverPtr make_solve_often_solver() {
#if SOFTHAP_WITH_CHOLMOD
    return make_cholmod_solver(CholmodLayout::ForSolves);
#else
    return make_ldlt_solver();
#endif
}

#if !SOFTHAP_WITH_CHOLMOD
LinearSolverPtr make_cholmod_solver(CholmodLayout) {
    throw Error(SH_ERR_UNSUPPORTED, "linear solver: CHOLMOD is not built in (SOFTHAP_WITH_CHOLMOD=OFF); "
                                    "use the LDL^T or conjugate-gradient solver");
}
#endif

namespace solver_detail {

void throw_not_positive_definite(const SparseSystem& a, int32_t column, const char* backend, const char* detail) {
    char dof[96];
    a.describe_dof(column, dof, sizeof dof);
    throw Error(SH_ERR_SOLVER, format("%s: matrix not positive definite at column %d (%s)%s%s", backend, column, dof,
                                      detail && *detail ? ": " : "", detail ? detail : ""));
}

}  // namespace solver_detail
}  // namespace sh
