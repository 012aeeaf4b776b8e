// Backward (implicit) Euler for one body as the minimisation of the step's incremental
// potential over the end-of-step velocity: projected Newton with a backtracking line search,
// starting from the current velocity (one iteration = the linearised Baraff-Witkin step), with
// the sparse system and linear solver kept across steps while the set of free nodes is unchanged.
// Direct solvers also keep their factorisation across iterations and steps (a chord/lagged
// Newton method) while the updates it gives cut the residual fast enough. The same Newton loop
// steps bodies coupled by contact together (a NewtonProblem over several bodies).
#pragma once

#include "model/body.hpp"
#include "solver/explicit_integrator.hpp"
#include "solver/newton_problem.hpp"
#include "solver/stepped_body.hpp"

namespace sh {

/// Advances stepped's body by dt with backward Euler; its NewtonBodyState is made on the first
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

/// step_implicit for the bodies of problem (prepared, solved together), as one Newton loop on
/// their joint residual: every body has contact (at least 20 iterations), the tolerance is the
/// strictest body's, the iteration cap the largest, the linear solver and factor_reuse the
/// first body's. On failure every body is restored.
BodyStepResult step_implicit_coupled(NewtonProblem& problem, double dt, const double gravity[3], bool keep_best = false);

}  // namespace sh
