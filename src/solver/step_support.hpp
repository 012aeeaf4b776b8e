// Pieces every time-stepping scheme shares: saving and restoring the start state, moving
// fixed and prescribed nodes, and the sanity check that triggers a rollback.
#pragma once

#include "model/body.hpp"
#include "solver/stepped_body.hpp"

namespace sh {

/// Copies the body's x and v into the workspace (x0, v0).
void save_start_state(SteppedBody& stepped);

/// Restores the body's x and v from the workspace.
void restore_start_state(SteppedBody& stepped);

/// Gives fixed and prescribed nodes the velocity that takes them to their targets in dt.
void begin_kinematic_motion(Body& body, double dt);

/// Puts fixed and prescribed nodes exactly on their targets with zero velocity; zero velocity
/// for nodes outside the dynamics (orphans).
void end_kinematic_motion(Body& body);

/// True if every position is finite and no node is faster than the runaway speed.
bool body_state_is_sane(const SteppedBody& stepped);

/// Why a step that failed body_state_is_sane was undone (a BodyStepResult reason).
constexpr const char* kRolledBackReason = "the state became non-finite or exceeded the runaway speed; rolled back";

}  // namespace sh
