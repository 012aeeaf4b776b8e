// Backward (implicit) Euler for one body as the minimisation of the step's incremental
// potential over the end-of-step velocity: projected Newton with a backtracking line search,
// starting from the current velocity (one iteration = the linearised Baraff-Witkin step), with
// the sparse system and linear solver kept across steps while the set of free nodes is unchanged.
// Direct solvers also keep their factorisation across iterations and steps (a chord/lagged
// Newton method) while the updates it gives cut the residual fast enough. The same Newton loop
// steps bodies coupled by contact together (CoupledSystem).
#pragma once

#include "model/body.hpp"
#include "solver/explicit_integrator.hpp"
#include "solver/stepped_body.hpp"
#include "linalg/linear_solver.hpp"
#include "linalg/sparse_system.hpp"

namespace sh {

class CoupledSystem;

/// The sparse system a Newton loop factorises and solves, its scratch vectors (one value per
/// DOF of the system) and the factorisation it may keep.
struct NewtonSystem {
    SparseSystem system;
    LinearSolverPtr solver;
    vec<double> residual;       ///< per DOF
    vec<double> delta;          ///< per DOF (CG warm start)
    vec<double> previous_v;     ///< per DOF: velocities before a trial update

    // The kept factorisation of a direct solver: of M + h D + h^2 K(x_f) for this step size and
    // the bodies' matrix version, at some earlier state x_f.
    bool factor_valid = false;
    double factor_dt = 0.0;
    uint64_t factor_matrix_version = 0;
    double roundoff_floor = 0.0;  ///< residual round-off level at the factorised state
};

/// Per-body state of the implicit integrator: built on first use, kept across steps. Its system
/// is the body's own (elements, field, mass); it is what a body alone factorises, and what a
/// CoupledSystem assembles each member into before scattering it into the joint system.
struct ImplicitState : NewtonSystem {
    vec<int32_t> free_index;    ///< per node: index among free nodes, or -1
    vec<double> diagonal;       ///< per free DOF: m (1 + h (alpha + c_i)), filled to factorise
    int32_t free_count = -1;    ///< -1: pattern not built yet
};

/// Advances stepped's body by dt with backward Euler; its implicit state is made on the first
/// call. With a direct solver and settings.implicit.factor_reuse > 0 a factorisation is kept across iterations and steps: an
/// update solved with a kept one is accepted if it at least halves the residual (2-norm and
/// max-norm), else discarded and solved again with a factorisation at the same iterate; a
/// linearised step goes on with kept-factorisation updates until the residual is down by
/// factor_reuse. A step that fails after using a kept factorisation is retried with fresh ones.
/// On a failed factorisation (SH_ERR_SOLVER), a
/// Newton loop that misses its tolerance (SH_ERR_NOT_CONVERGED) or a non-finite or runaway
/// state (SH_ERR_UNSTABLE) the body is restored and result.status says why.
/// keep_best: a Newton loop that does not converge keeps its last iterate, the lowest
/// incremental potential it reached (result.not_converged), instead of failing.
BodyStepResult step_implicit(SteppedBody& stepped, double dt, const double gravity[3], bool keep_best = false);

/// step_implicit for the members of system (prepared), as one Newton loop on their joint
/// residual: every member has contact (at least 20 iterations), the tolerance is the strictest
/// member's, the iteration cap the largest, the linear solver and factor_reuse the first
/// member's. On failure every member is restored.
BodyStepResult step_implicit_coupled(CoupledSystem& system, double dt, const double gravity[3], bool keep_best = false);

/// Round-off level of internal forces computed at positions x: they come from position
/// differences that carry about eps |x|, which a stiffness turns into eps |x| K_dd per DOF.
/// system holds K / scale (its diagonal times scale is K_dd); the result is in force units.
double force_roundoff(const SparseSystem& system, const vec<double>& x, double scale);

/// Rebuilds state's pattern (and, with own_solver, its solver and symbolic analysis) if body's
/// free nodes changed since the last call; makes the solver if own_solver and there is none
/// yet. Returns the number of free DOFs.
int32_t prepare_implicit_state(const Body& body, ImplicitState& state, const sh_implicit_settings& settings,
                               bool own_solver = true);

/// The linear solver settings name (DEFAULT: CHOLMOD when built in, else LDL^T), made and
/// analysed for system.
LinearSolverPtr make_analysed_solver(const SparseSystem& system, const sh_implicit_settings& settings);

/// Clears state's system and adds stiffness_scale K + damping_scale D of body at (body.x, v)
/// (v null: at rest) from its elements and its field, then diagonal (per free DOF) if not null.
/// Returns the round-off of the body's forces, force_roundoff of the system before the
/// diagonal with roundoff_scale.
double assemble_body_tangent(const Body& body, ImplicitState& state, double stiffness_scale, double damping_scale,
                             const double* v, const double* diagonal, double roundoff_scale);

}  // namespace sh
