#include "world/body_step.hpp"

#include "solver/implicit_integrator.hpp"

#include <algorithm>

namespace sh {

BodyStepResult step_body(SteppedBody& stepped, double dt, const double gravity[3], bool keep_best) {
    if (stepped.settings.integrator != SH_INTEGRATOR_IMPLICIT_EULER) return step_explicit(stepped, dt, gravity);
    return step_implicit(stepped, dt, gravity, keep_best);
}

void add_step_figures(sh_step_report& r, const BodyStepResult& result) {
    r.dt_critical = std::min(r.dt_critical, result.dt_critical);
    r.substeps = std::max(r.substeps, result.substeps);
    r.newton_iterations = std::max(r.newton_iterations, result.newton_iterations);
    r.linear_iterations += result.linear_iterations;
    r.newton_residual = std::max(r.newton_residual, result.newton_residual);
    r.factorize_seconds += result.factorize_seconds;
    r.solve_seconds += result.solve_seconds;
    r.factorizations += result.factorizations;
    if (result.substeps > 1) r.warnings |= 1u << SH_WARN_SUBSTEPPED;
}

}  // namespace sh
