// Tearing: mass-spring bodies whose springs have a breaking strain lose the springs stretched
// beyond it at the start of every step, and nodes left holding pieces joined only through them
// are split (a step hook the world owns).
#pragma once

namespace sh {

class World;

/// Makes world tear its mass-spring bodies with sh_spring_params.break_strain > 0 at the start
/// of every step, before the motion; the step report's springs_broken counts the springs.
/// Calling it again changes nothing. Throws std::bad_alloc changing nothing.
void enable_tearing(World& world);

}  // namespace sh
