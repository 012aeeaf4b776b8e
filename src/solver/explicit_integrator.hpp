// Explicit time stepping of one body by its row of the integrator table (a Runge-Kutta
// tableau or symplectic Euler), with the critical-step policy (reject or sub-step) and
// rollback of non-finite or runaway states.
#pragma once

#include "model/body.hpp"
#include "solver/stepped_body.hpp"

#include <cstdint>

namespace sh {

/// What step_explicit did.
struct BodyStepResult {
    bool stable = true;       ///< false: the body was left exactly as before the call
    sh_status status = SH_OK; ///< why it was not stable (SH_ERR_UNSTABLE, _SOLVER, _NOT_CONVERGED)
    const char* reason = "";  ///< static text for the message
    bool rejected = false;    ///< dt exceeded dt_crit under SH_UNSTABLE_REJECT
    int32_t substeps = 1;     ///< sub-steps taken
    double dt_critical = 0.0; ///< the body's critical step at the start (s)
    int32_t newton_iterations = 0;  ///< implicit: Newton iterations taken
    int32_t linear_iterations = 0;  ///< implicit: linear-solver iterations (1 per direct solve)
    double newton_residual = 0.0;   ///< implicit: final relative residual (-1 if not measured)
    double factorize_seconds = 0.0; ///< implicit: time in factorisations (s)
    double solve_seconds = 0.0;     ///< implicit: time in solves (s)
    int32_t factorizations = 0;     ///< implicit: factorisations in this step
    bool not_converged = false;     ///< implicit: Newton missed its tolerance and the step kept
                                    ///< its best iterate (stable stays true)
};


/// Advances stepped's body by dt (s) under gravity (m/s^2) with its explicit integrator.
/// Allocation-free.
BodyStepResult step_explicit(SteppedBody& stepped, double dt, const double gravity[3]);

/// Accelerations a (3 per node) at state (x, v): internal, external and gravity forces over
/// mass, minus viscous damping; zero for fixed, prescribed and orphan nodes.
void compute_accelerations(const Body& body, const double* x, const double* v, const double gravity[3], double* a);

}  // namespace sh
