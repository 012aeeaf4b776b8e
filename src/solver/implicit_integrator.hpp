// Backward (implicit) Euler for one body: Newton iterations on the end-of-step velocity,
// starting from the current one (one iteration = the linearised Baraff-Witkin step), with the
// sparse system and linear solver kept across steps while the set of free nodes is unchanged.
// Direct solvers also keep their factorisation across iterations and steps (a chord/lagged
// Newton method) while the updates it gives cut the residual fast enough.
#pragma once

#include "model/body.hpp"
#include "solver/explicit_integrator.hpp"
#include "solver/linear_solver.hpp"
#include "solver/sparse_system.hpp"

namespace sh {

/// Per-body state of the implicit integrator: built on first use, kept across steps.
struct ImplicitState {
    SparseSystem system;
    LinearSolverPtr solver;
    vec<int32_t> free_index;    ///< per node: index among free nodes, or -1
    vec<double> residual;       ///< per free DOF
    vec<double> delta;          ///< per free DOF (CG warm start)
    vec<double> diagonal;       ///< per free DOF: m (1 + h (alpha + c_i)), filled to factorise
    vec<double> previous_v;     ///< per free DOF: velocities before a trial update
    int32_t free_count = -1;    ///< -1: pattern not built yet

    // The kept factorisation of a direct solver: of M + h D + h^2 K(x_f) for this step size and
    // the body's matrix version, at some earlier state x_f.
    bool factor_valid = false;
    double factor_dt = 0.0;
    uint64_t factor_matrix_version = 0;
    double roundoff_floor = 0.0;  ///< residual round-off level at the factorised state
};

/// Advances body by dt with backward Euler. With a direct solver and
/// settings.implicit.factor_reuse > 0 a factorisation is kept across iterations and steps: an
/// update solved with a kept one is accepted if it at least halves the residual (2-norm and
/// max-norm), else discarded and solved again with a factorisation at the same iterate; a
/// linearised step goes on with kept-factorisation updates until the residual is down by
/// factor_reuse. A step that fails after using a kept factorisation is retried with fresh ones.
/// On a failed factorisation (SH_ERR_SOLVER), a
/// Newton loop that misses its tolerance (SH_ERR_NOT_CONVERGED) or a non-finite or runaway
/// state (SH_ERR_UNSTABLE) the body is restored and result.status says why.
BodyStepResult step_implicit(Body& body, ImplicitState& state, double dt, const double gravity[3]);

/// Round-off level of internal forces computed at positions x: they come from position
/// differences that carry about eps |x|, which a stiffness turns into eps |x| K_dd per DOF.
/// system holds K / scale (its diagonal times scale is K_dd); the result is in force units.
double force_roundoff(const SparseSystem& system, const vec<double>& x, double scale);

/// Rebuilds state's pattern, solver and symbolic analysis if body's free nodes changed since
/// the last call. Returns the number of free DOFs.
int32_t prepare_implicit_state(const Body& body, ImplicitState& state, const sh_implicit_settings& settings);

}  // namespace sh
