// Static equilibrium of a body, or of bodies coupled by contact: Newton-Raphson
// K(x) dx = f_ext + f(x) with backtracking line search on the potential energy and optional load
// stepping.
#pragma once

#include "solver/stepped_body.hpp"

#include <softhap/softhap.h>

namespace sh {

class NewtonProblem;

/// Moves stepped's body to equilibrium under gravity and its external forces, its fixed and
/// prescribed nodes on their targets, velocities zeroed, with a fresh NewtonBodyState of its
/// own (the body's is left as it was). Appends to report (iterations, history, residual).
/// Throws SH_ERR_SOLVER (singular or indefinite K) or SH_ERR_NOT_CONVERGED; the caller restores
/// the body (save_start_state before the call). The workspace's stage arrays are scratch.
void solve_static_body(SteppedBody& stepped, const double gravity[3], const sh_static_def& def, sh_static_report& report);

/// solve_static_body for bodies[0..count) (each with a fresh NewtonBodyState) solved together
/// as problem (prepared here):
/// one Newton loop on their joint out-of-balance force and potential. At least one of them must
/// have a fixed or prescribed node; one without any is held by its contacts with the others,
/// and the directions they leave free (sliding along frictionless contact) are held by a tiny
/// shift of its tangent's diagonal, so that the solve ends at the equilibrium nearest its start.
void solve_static_coupled(NewtonProblem& problem, SteppedBody* const* bodies, int32_t count, const double gravity[3],
                          const sh_static_def& def, sh_static_report& report);

}  // namespace sh
