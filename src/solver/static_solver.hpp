// Static equilibrium of a body: Newton-Raphson K(x) dx = f_ext + f(x) with backtracking line
// search on the potential energy and optional load stepping.
#pragma once

#include "model/body.hpp"

#include <softhap/softhap.h>

namespace sh {

/// Moves body to equilibrium under gravity and its external forces, its fixed and prescribed
/// nodes on their targets, velocities zeroed. Appends to report (iterations, history, residual).
/// Throws SH_ERR_SOLVER (singular or indefinite K) or SH_ERR_NOT_CONVERGED; the caller restores
/// the body (its start state is saved in the workspace).
void solve_static_body(Body& body, const double gravity[3], const sh_static_def& def, sh_static_report& report);

}  // namespace sh
