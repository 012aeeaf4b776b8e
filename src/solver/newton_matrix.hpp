// NewtonMatrix: the linear system a Newton solve assembles and factorises — the sparse matrix
// over the solve's free DOFs, the linear solver analysed for its pattern, the factorisation a
// direct solver may keep across iterations and steps, and the scratch vectors of the solve (one
// value per DOF of the matrix).
#pragma once

#include "core/memory.hpp"
#include "linalg/linear_solver.hpp"
#include "linalg/preconditioned_cg.hpp"
#include "linalg/sparse_system.hpp"
#include "linalg/warped_multigrid.hpp"
#include "solver/node_rotations.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

/// What is known of the factorisation a direct solver holds, kept across Newton iterations and
/// steps while it may serve (a chord/lagged Newton method): it is of M + h D + h^2 K(x_f) for
/// one step size and one matrix version of the bodies, at some earlier iterate x_f.
struct KeptFactorisation {
    bool valid = false;           ///< the solver holds a factorisation that may be reused
    double dt = 0.0;              ///< the step size it was made for (s)
    uint64_t matrix_version = 0;  ///< the bodies' matrix version it was made for
    double roundoff_floor = 0.0;  ///< the residual's round-off level at the factorised iterate
    // Work in a sparse solve's floating-point operations (FactorWork), estimated from counts:
    // the step's choices depend on no clock.
    double factorize_work = 0.0;  ///< a factorisation's: the price of a new one
    double solve_work = 0.0;      ///< one solve's with it
    double assemble_work = 0.0;   ///< one assembly of the tangent's (Body::tangent_work)
    int steps_served = 0;            ///< steps begun with it since it was made
    bool failed = false;             ///< an update solved with it failed
    /// Steps the factorisations' updates served before their first failure, a running mean
    /// over the factorisations (their cost per step is the factorisation's over it); -1 before
    /// the first failure.
    double mean_life = -1.0;
    /// CG iterations per solve preconditioned with a factorisation made in the same step [0]
    /// or an earlier one [1] (running means).
    double krylov_iterations[2] = {4.0, 4.0};
    double krylov_spent = 0.0;    ///< assembly and CG work spent with it as preconditioner
};

/// The sparse linear system of a Newton solve and what solving it needs.
struct NewtonMatrix {
    SparseSystem system;     ///< the matrix: pattern and values over the solve's free DOFs
    LinearSolverPtr solver;  ///< analysed for system's pattern (null: not made yet, or not needed)
    vec<double> residual;    ///< per DOF: the residual (gradient) at the current iterate
    vec<double> delta;       ///< per DOF: the Newton update (CG's warm start)
    vec<double> previous_v;  ///< per DOF: velocities before a trial update (the line search's start)
    KeptFactorisation kept;  ///< the factorisation the solver may be holding
    PreconditionedCgWork cg; ///< CG's vectors when the kept factorisation or multigrid preconditions it
    /// A large body's CG preconditioner under large rotation, built at the rest shape on first
    /// use for one step size and matrix version (the members below), and its nodes' rotations.
    WarpedMultigrid multigrid;
    NodeRotations rotations;
    double multigrid_dt = 0.0;         ///< the step size multigrid was built (or failed) for (s)
    uint64_t multigrid_version = 0;    ///< and the bodies' matrix version
    bool multigrid_failed = false;     ///< its build failed for them: not tried again
    bool multigrid_mode = false;       ///< steps start with it (it paid when a factorisation failed)
    double multigrid_iterations = 6.0; ///< CG iterations per solve with it (running mean)
    int multigrid_calm_steps = 0;      ///< its updates in a row whose nodes barely turned
    int multigrid_calm_needed = 10;    ///< how many of them leave it (doubles when leaving did not pay)
    bool multigrid_left_calm = false;  ///< it was left for being calm, and not chosen again since
    int multigrid_pause = 0;           ///< steps it still sits out after a solve it could not use
    int multigrid_pause_length = 1;    ///< the next such pause (doubles with failures in a row)

    /// Takes pattern as the matrix and solver (analysed for it, or null) as its solver, sizes
    /// the scratch vectors for its DOFs (delta zeroed) and forgets any kept factorisation.
    /// Allocates before it changes anything: if that throws, the matrix is as it was.
    void reset(SparseSystem&& pattern, LinearSolverPtr solver);
};

/// The linear solver settings name (DEFAULT: CHOLMOD when built in, else LDL^T), made and
/// analysed for system, starting from the suggested elimination order if one is given.
LinearSolverPtr make_analysed_solver(const SparseSystem& system, const sh_implicit_settings& settings,
                                     const EliminationOrder* suggested = nullptr);

/// Round-off level of internal forces computed at positions x: they come from position
/// differences that carry about eps |x|, which a stiffness turns into eps |x| K_dd per DOF.
/// system holds K / scale (its diagonal times scale is K_dd); the result is in force units.
double force_roundoff(const SparseSystem& system, const vec<double>& x, double scale);

}  // namespace sh
