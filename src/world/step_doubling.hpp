// Step doubling: a body taken over dt in two half steps from its start state, to estimate the
// local error of the full step it then takes from the same start.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"
#include "solver/stepped_body.hpp"

#include <cstdint>

namespace sh {

struct NewtonBodyState;

/// Scratch of one body's step-doubling estimate, sized when the body joins the world.
struct StepDoubling {
    vec<double> start_x, start_v, start_target;  ///< 3 per node: the state to go back to
    vec<double> half_x;                          ///< 3 per node: positions after two half steps
    NewtonBodyState* newton = nullptr;           ///< the half steps' own Newton state, so the
                                                 ///< full step's kept factorisation stays
    /// Scratch for a body of values / 3 nodes.
    explicit StepDoubling(size_t values);
    /// Frees newton.
    ~StepDoubling();
    StepDoubling(const StepDoubling&) = delete;             ///< owns newton
    StepDoubling& operator=(const StepDoubling&) = delete;  ///< owns newton
};

/// Saves body's start state in scratch and moves its kinematic nodes' targets to the midpoint
/// of their motion (where the first half step takes them).
void begin_half_steps(Body& body, StepDoubling& scratch);

/// Gives body its own kinematic targets back, for the second half step.
void restore_targets(Body& body, const StepDoubling& scratch);

/// Keeps body's positions in scratch.half_x (keep_positions) and puts it back as
/// begin_half_steps found it.
void end_half_steps(Body& body, StepDoubling& scratch, bool keep_positions);

/// Takes bodies[0..count) over dt in two half steps of step(h), which advances all of them by h
/// and returns whether that was stable; keeps their positions in their scratch.half_x and puts
/// them back as they were. Returns false if a half step was not stable.
template <class Step>
bool take_half_steps_together(SteppedBody* const* bodies, StepDoubling* const* scratch, int32_t count, double dt,
                              Step&& step) {
    for (int32_t m = 0; m < count; ++m) begin_half_steps(*bodies[m]->body, *scratch[m]);
    bool stable;
    try {
        stable = step(0.5 * dt);
        for (int32_t m = 0; m < count; ++m) restore_targets(*bodies[m]->body, *scratch[m]);
        if (stable) stable = step(0.5 * dt);
    } catch (...) {  // e.g. out of memory building the half steps' solver: the bodies as they were
        for (int32_t m = 0; m < count; ++m) end_half_steps(*bodies[m]->body, *scratch[m], false);
        throw;
    }
    for (int32_t m = 0; m < count; ++m) end_half_steps(*bodies[m]->body, *scratch[m], true);
    return stable;
}

/// take_half_steps_together for one body with its own integrator (an implicit one with
/// scratch.newton as its Newton state).
bool take_half_steps(SteppedBody& stepped, StepDoubling& scratch, double dt, const double gravity[3]);

/// Largest distance between a node of body and its position in scratch.half_x (m).
double largest_half_step_difference(const Body& body, const StepDoubling& scratch);

}  // namespace sh
