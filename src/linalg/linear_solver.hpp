// Linear-solver backends for a SparseSystem: CHOLMOD (sparse Cholesky, symbolic analysis reused
// while the pattern is unchanged), Eigen's simplicial LDL^T, and Eigen's preconditioned conjugate
// gradient with warm start.
#pragma once

#include "core/memory.hpp"
#include "linalg/sparse_system.hpp"

#include <memory>

namespace sh {

enum class LinearSolverKind { Cholmod, Ldlt, ConjugateGradient };

/// A fill-reducing elimination order of a system's free nodes (free DOF d belongs to free node
/// d / 3), as an earlier analysis chose it or as a caller derives it from one, with the cost of
/// the last order computed afresh: an order carried over from it may cost at most
/// kSuggestedOrderTolerance times that per node, so that many small changes cannot drift far.
struct EliminationOrder {
    vec<int32_t> nodes;           ///< the nodes in elimination order (a solver's: a permutation of [0, dof_count / 3))
    double fill_per_node = 0.0;   ///< the factor's stored entries per free node (0: unknown)
    double flops_per_node = 0.0;  ///< the factorisation's floating-point operations per free node (0: unknown)
};

/// Estimates of a direct solver's work for its analysed pattern, in the floating-point
/// operations of one sparse triangular solve (memory-bound: about 0.3 ns each on the machine
/// these were measured on). The implicit step weighs a factorisation against solves and
/// assemblies with them rather than with a clock, so that identical runs make identical choices.
struct FactorWork {
    double factorize = 0.0;  ///< one numeric factorisation (0: unknown, or not a direct solver)
    double solve = 0.0;      ///< one solve: forward and back substitution, 4 per factor entry
};

/// A factorisation's FactorWork from its analysis: flops floating-point operations and
/// factor_entries stored entries of L, the backend running its flops speed times as fast as a
/// solve's (dense kernels over supernodes). It is never under kMinFactorizeSolves solves
/// (small supernodes, symbolic overhead).
FactorWork factor_work(double flops, double factor_entries, double speed);

/// The fewest solves a factorisation's work counts as. Measured with CHOLMOD and OpenBLAS on
/// 1,300 to 17,800 DOF systems of organ meshes and cubes: 10.6 to 26 solves per factorisation.
constexpr double kMinFactorizeSolves = 12.0;

/// Solves A x = b for a SparseSystem A (symmetric positive definite expected).
///
/// Every method works on the SparseSystem it is given; factorize and solve require that system's
/// pattern to be the one last analysed (SH_ERR_INTERNAL otherwise). A system without free DOFs is
/// fine (nothing to do). Not thread-safe; separate solver objects are independent. The checks,
/// timing and empty-system handling live here; backends implement the do_* steps.
class LinearSolver {
public:
    virtual ~LinearSolver() = default;
    /// Symbolic analysis for A's pattern; call again only when the pattern changes (reused otherwise).
    /// suggested (optional, a permutation of A's free nodes): an ordering to start from instead
    /// of computing one, e.g. the last pattern's order extended to nodes a cut added. A backend
    /// that takes it falls back to its own ordering if its fill or flops per node exceed
    /// kSuggestedOrderTolerance times the suggestion's; the others ignore it.
    void analyze(const SparseSystem& a, const EliminationOrder* suggested = nullptr);
    /// The elimination order the last analysis chose, with the per-node cost of the last fresh
    /// ordering it comes from (its own, or the suggestion's if it kept that), into out (allocates).
    /// Returns false, leaving out as it was, if nothing was analysed, the system was empty or the
    /// backend does not order by nodes (CG, LDL^T).
    bool elimination_order(EliminationOrder& out) const;
    /// Numeric factorisation of A's current values (CG: builds its preconditioner). Throws
    /// sh::Error(SH_ERR_SOLVER, "...not positive definite at column N..." or similar) on failure,
    /// also for a non-finite value in A (naming its column).
    void factorize(const SparseSystem& a);
    /// Solves A x = b. On entry x holds an initial guess (used by CG: warm start; ignored by direct
    /// solvers). Returns the iterations used (1 for direct). Throws SH_ERR_NOT_CONVERGED (CG did not reach
    /// its tolerance within its iteration cap; x then holds the best iterate) or SH_ERR_SOLVER.
    /// A non-finite solution (e.g. from a non-finite b) is SH_ERR_SOLVER. x and b must not overlap.
    int solve(const SparseSystem& a, const double* b, double* x);
    /// Seconds spent in the last factorize and solve (for step reports).
    double factorize_seconds = 0, solve_seconds = 0;
    /// The work of a factorisation and a solve with the analysed pattern (FactorWork; zero
    /// before an analysis and for CG). A direct backend knows it after its first factorisation.
    FactorWork work() const { return estimated_work_; }
    /// Static description of the backend ("cholmod", "eigen-ldlt", "eigen-cg-jacobi").
    virtual const char* name() const = 0;
    /// True for direct solvers: after factorize, solve is exact for the factorised values, and
    /// keeps working after the system's values change (CG multiplies with the current system).
    virtual bool is_direct() const = 0;

protected:
    FactorWork estimated_work_;  ///< set by a direct backend's analysis or first factorisation

    /// The backend's steps, called with a non-empty system: do_factorize with finite values and
    /// the analysed pattern, do_solve after a successful factorize.
    virtual void do_analyze(const SparseSystem& a, const EliminationOrder* suggested) = 0;
    virtual void do_factorize(const SparseSystem& a) = 0;
    virtual int do_solve(const SparseSystem& a, const double* b, double* x) = 0;
    /// The last analysis' order (a non-empty system was analysed); false if the backend has none.
    virtual bool do_elimination_order(EliminationOrder& out) const {
        (void)out;
        return false;
    }

private:
    uint64_t analysed_id_ = 0;
    int32_t analysed_dofs_ = 0;
    bool factorized_ = false;
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

/// The direct backend the library is built with: CHOLMOD where SOFTHAP_WITH_CHOLMOD, else LDL^T.
LinearSolverKind default_direct_solver();

/// The direct backend for a small system factorised once and solved many times (a multigrid's
/// coarse level): CHOLMOD laid out for solves (CholmodLayout::ForSolves) where
/// SOFTHAP_WITH_CHOLMOD, else LDL^T.
LinearSolverPtr make_solve_often_solver();

/// How CHOLMOD chooses between a supernodal and a simplicial factor. Chosen: its own default,
/// supernodal from 40 flops per factor entry, which suits factorisations (dense kernels over
/// supernodes). ForSolves: supernodal only from kSolvesSupernodalSwitch, where a solve's
/// hundreds of small BLAS calls over thin supernodes cost more than a simplicial factor's
/// plain loops.
enum class CholmodLayout { Chosen, ForSolves };

/// Measured on the multigrid's coarse levels, per solve, simplicial against supernodal: the
/// raptor's (2,382 DOF, 68 flops per entry) 0.17-0.19 against 0.25 ms, the 20 k-tet cube's
/// (1,080 DOF, 162 per entry) 0.22 against 0.18-0.19 ms.
constexpr double kSolvesSupernodalSwitch = 100.0;

/// The backends (make_linear_solver picks one of them).
LinearSolverPtr make_cholmod_solver(CholmodLayout layout = CholmodLayout::Chosen);
LinearSolverPtr make_ldlt_solver();
LinearSolverPtr make_cg_solver(double tolerance, int max_iterations);

/// How much more fill or flops per node than the suggestion's own a suggested order may give
/// before the analysis computes a fresh ordering instead. A fresh ordering costs about a third
/// of one factorisation (raptor, 19k tets: 15 ms against 40 ms), so a suggestion that slows
/// every later factorisation by more than a few percent soon costs more than it saved.
constexpr double kSuggestedOrderTolerance = 1.05;

namespace solver_detail {
/// Throws SH_ERR_SOLVER "<backend>: matrix not positive definite at column N (free DOF ..)".
[[noreturn]] void throw_not_positive_definite(const SparseSystem& a, int32_t column, const char* backend,
                                              const char* detail);
}  // namespace solver_detail

}  // namespace sh
