#include "world/step_doubling.hpp"

#include "solver/newton_body_state.hpp"
#include "world/body_step.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

StepDoubling::StepDoubling(size_t values) : start_x(values), start_v(values), start_target(values), half_x(values) {}

StepDoubling::~StepDoubling() { sh::destroy(newton); }

void begin_half_steps(Body& body, StepDoubling& scratch) {
    std::copy(body.x.begin(), body.x.end(), scratch.start_x.begin());
    std::copy(body.v.begin(), body.v.end(), scratch.start_v.begin());
    std::copy(body.target.begin(), body.target.end(), scratch.start_target.begin());
    for (size_t i = 0; i < body.kinematic.size(); ++i)
        if (body.kinematic[i])
            for (size_t k = 3 * i; k < 3 * i + 3; ++k) body.target[k] = 0.5 * (body.x[k] + body.target[k]);
}

void restore_targets(Body& body, const StepDoubling& scratch) {
    std::copy(scratch.start_target.begin(), scratch.start_target.end(), body.target.begin());
}

void end_half_steps(Body& body, StepDoubling& scratch, bool keep_positions) {
    if (keep_positions) std::copy(body.x.begin(), body.x.end(), scratch.half_x.begin());
    restore_targets(body, scratch);
    std::copy(scratch.start_x.begin(), scratch.start_x.end(), body.x.begin());
    std::copy(scratch.start_v.begin(), scratch.start_v.end(), body.v.begin());
}

bool take_half_steps(SteppedBody& stepped, StepDoubling& scratch, double dt, const double gravity[3]) {
    SteppedBody* const bodies[1] = {&stepped};
    StepDoubling* scratches[1] = {&scratch};
    // An implicit body's half steps keep their own state and factorisation, so that the full
    // step's stays (the first half step makes it).
    const SwappedNewtonStates own(bodies, &scratch.newton, 1);
    return take_half_steps_together(bodies, scratches, 1, dt,
                                    [&](double h) { return step_body(stepped, h, gravity, false).stable; });
}

double largest_half_step_difference(const Body& body, const StepDoubling& scratch) {
    double largest = 0.0;
    for (size_t i = 0; i < body.x.size(); i += 3) {
        const double dx = body.x[i] - scratch.half_x[i], dy = body.x[i + 1] - scratch.half_x[i + 1],
                     dz = body.x[i + 2] - scratch.half_x[i + 2];
        largest = std::max(largest, dx * dx + dy * dy + dz * dz);
    }
    return std::sqrt(largest);
}

}  // namespace sh
