// Step doubling: a body taken over dt in two half steps from its start state, to estimate the
// local error of the full step it then takes from the same start.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

namespace sh {

struct ImplicitState;

/// Scratch of one body's step-doubling estimate, sized when the body joins the world.
struct StepDoubling {
    vec<double> start_x, start_v, start_target;  ///< 3 per node: the state to go back to
    vec<double> half_x;                          ///< 3 per node: positions after two half steps
    ImplicitState* implicit = nullptr;           ///< the half steps' own implicit solver state,
                                                 ///< so the full step's kept factorisation stays
    explicit StepDoubling(size_t values);
    ~StepDoubling();
    StepDoubling(const StepDoubling&) = delete;
    StepDoubling& operator=(const StepDoubling&) = delete;
};

/// Takes body over dt in two half steps (kinematic nodes reach the midpoint of their motion
/// after the first), keeps the positions in scratch.half_x and puts body back as it was.
/// Returns false if a half step was not stable.
bool take_half_steps(Body& body, StepDoubling& scratch, double dt, const double gravity[3]);

/// Largest distance between a node of body and its position in scratch.half_x (m).
double largest_half_step_difference(const Body& body, const StepDoubling& scratch);

}  // namespace sh
