// One body's step with its own integrator: the dispatch World::step and the step-doubling
// estimate share, and how a step's figures go into the step report.
#pragma once

#include "model/body.hpp"
#include "solver/explicit_integrator.hpp"
#include "solver/stepped_body.hpp"

namespace sh {

/// Advances stepped's body by dt with its integrator. keep_best: an implicit step that does
/// not converge keeps its best iterate (see step_implicit).
BodyStepResult step_body(SteppedBody& stepped, double dt, const double gravity[3], bool keep_best);

/// Adds the figures of one solve (a body's step, or an island's) to r: critical step,
/// sub-steps, Newton and linear-solver counts and times, the sub-stepping warning.
void add_step_figures(sh_step_report& r, const BodyStepResult& result);

}  // namespace sh
