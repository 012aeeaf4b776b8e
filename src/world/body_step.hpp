// One body's step with its own integrator: the dispatch World::step and the step-doubling
// estimate share.
#pragma once

#include "model/body.hpp"
#include "solver/explicit_integrator.hpp"

namespace sh {

struct ImplicitState;

/// Advances body by dt with its integrator. implicit is the body's implicit solver state,
/// created here on the first implicit step (and kept by the caller).
BodyStepResult step_body(Body& body, ImplicitState*& implicit, double dt, const double gravity[3]);

}  // namespace sh
