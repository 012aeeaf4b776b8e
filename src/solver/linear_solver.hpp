// Linear-solver backends for a SparseSystem: CHOLMOD (sparse Cholesky, symbolic analysis reused
// while the pattern is unchanged), Eigen's simplicial LDL^T, and Eigen's preconditioned conjugate
// gradient with warm start.
#pragma once

#include "core/memory.hpp"
#include "solver/sparse_system.hpp"

#include <memory>

namespace sh {

enum class LinearSolverKind { Cholmod, Ldlt, ConjugateGradient };

/// Solves A x = b for a SparseSystem A (symmetric positive definite expected).
///
/// Every method works on the SparseSystem it is given; factorize and solve require that system's
/// pattern to be the one last analysed (SH_ERR_INTERNAL otherwise). A system without free DOFs is
/// fine (nothing to do). Not thread-safe; separate solver objects are independent.
class LinearSolver {
public:
    virtual ~LinearSolver() = default;
    /// Symbolic analysis for A's pattern; call again only when the pattern changes (reused otherwise).
    virtual void analyze(const SparseSystem& a) = 0;
    /// Numeric factorisation of A's current values (CG: builds its preconditioner). Throws
    /// sh::Error(SH_ERR_SOLVER, "...not positive definite at column N..." or similar) on failure.
    /// Also SH_ERR_SOLVER for a non-finite value in A (naming its column).
    virtual void factorize(const SparseSystem& a) = 0;
    /// Solves A x = b. On entry x holds an initial guess (used by CG: warm start; ignored by direct
    /// solvers). Returns the iterations used (1 for direct). Throws SH_ERR_NOT_CONVERGED (CG did not reach
    /// its tolerance within its iteration cap; x then holds the best iterate) or SH_ERR_SOLVER.
    /// A non-finite solution (e.g. from a non-finite b) is SH_ERR_SOLVER. x and b must not overlap.
    virtual int solve(const SparseSystem& a, const double* b, double* x) = 0;
    /// Seconds spent in the last analyze, factorize and solve (for step reports).
    double analyze_seconds = 0, factorize_seconds = 0, solve_seconds = 0;

    // ---- additions -------------------------------------------------------------------------

    /// Static description of the backend as configured ("cholmod", "eigen-ldlt", "eigen-cg-jacobi").
    virtual const char* name() const = 0;
    /// True for direct solvers: after factorize, solve is exact for the factorised values, and
    /// keeps working after the system's values change (CG multiplies with the current system).
    virtual bool is_direct() const { return false; }
    /// After factorize: a short description of the factorisation actually used, e.g.
    /// "cholmod supernodal LL^T" (CHOLMOD's automatic choice); name() before.
    virtual const char* method() const { return name(); }
    /// Stored entries of the factor L (direct solvers, after factorize; 0 for CG).
    virtual int64_t factor_nonzeros() const { return 0; }
    /// CG: relative residual |b - A x| / |b| reached by the last solve; 0 for direct solvers.
    double last_relative_residual = 0;
};

/// Frees a LinearSolver made by make_linear_solver through sh::destroy's allocator.
struct LinearSolverDelete {
    void operator()(LinearSolver* solver) const noexcept;
};
using LinearSolverPtr = std::unique_ptr<LinearSolver, LinearSolverDelete>;

/// Makes a backend. Cholmod throws SH_ERR_UNSUPPORTED if built without SOFTHAP_WITH_CHOLMOD.
/// cg_tolerance: relative residual |b - A x| / |b|; cg_max_iterations: cap.
/// ConjugateGradient requires cg_tolerance > 0 (finite) and cg_max_iterations >= 1
/// (SH_ERR_INVALID_ARGUMENT); the other kinds ignore both.
LinearSolverPtr make_linear_solver(LinearSolverKind kind, double cg_tolerance, int cg_max_iterations);

/// CHOLMOD's choice between supernodal and simplicial factorisation. Automatic picks supernodal
/// for 3D tet meshes of a few thousand nodes and up. Note for real-time hosts: Debian's CHOLMOD 3
/// runs OpenMP parallel regions in the supernodal factorisation (up to 4 threads, fixed at its
/// compile time; OMP_THREAD_LIMIT=1 keeps it on the calling thread) and uses the system BLAS
/// (reference BLAS by default: ~5x slower there than OpenBLAS). Simplicial uses neither.
enum class CholmodMode { Automatic, Supernodal, Simplicial };

/// CHOLMOD fill-reducing ordering: CHOLMOD's default strategy (AMD, then METIS too when AMD's fill
/// is high, keeping the better), or one method only.
enum class CholmodOrdering { Default, Amd, Metis, NestedDissection };

/// make_linear_solver(Cholmod) with the factorisation kind and ordering forced (benchmarks,
/// tests). SH_ERR_UNSUPPORTED without SOFTHAP_WITH_CHOLMOD.
LinearSolverPtr make_cholmod_solver(CholmodMode mode = CholmodMode::Automatic,
                                    CholmodOrdering ordering = CholmodOrdering::Default);

/// CG preconditioners.
enum class CgPreconditioner { Jacobi, IncompleteCholesky };

/// make_linear_solver(ConjugateGradient) with the preconditioner chosen (make_linear_solver uses
/// the default one, see linear_solver.cpp).
LinearSolverPtr make_cg_solver(double tolerance, int max_iterations, CgPreconditioner preconditioner);

/// make_linear_solver(Ldlt).
LinearSolverPtr make_ldlt_solver();

namespace solver_detail {
/// Seconds on a monotonic clock.
double now_seconds();
/// Throws SH_ERR_INTERNAL unless a's pattern is the analysed one (analysed_id).
void require_analysed(const SparseSystem& a, uint64_t analysed_id, const char* backend);
/// Throws SH_ERR_SOLVER naming the column of the first non-finite value of a.
void require_finite_values(const SparseSystem& a, const char* backend);
/// Throws SH_ERR_SOLVER when x (a.dof_count() values) has a non-finite entry.
void require_finite_solution(const SparseSystem& a, const double* x, const char* backend);
/// Throws SH_ERR_SOLVER "<backend>: matrix not positive definite at column N (free DOF ..)".
[[noreturn]] void throw_not_positive_definite(const SparseSystem& a, int32_t column, const char* backend,
                                              const char* detail);
}  // namespace solver_detail

}  // namespace sh
