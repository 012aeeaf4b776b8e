#include "world/body_step.hpp"

#include "solver/implicit_integrator.hpp"

namespace sh {

BodyStepResult step_body(Body& body, ImplicitState*& implicit, double dt, const double gravity[3]) {
    if (body.settings.integrator != SH_INTEGRATOR_IMPLICIT_EULER) return step_explicit(body, dt, gravity);
    if (!implicit) implicit = sh::create<ImplicitState>();
    return step_implicit(body, *implicit, dt, gravity);
}

}  // namespace sh
