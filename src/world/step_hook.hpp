// StepHook: what the world calls around each full step, so that layers above it (haptic
// contexts, and cutting) take part in the step without the world knowing them.
#pragma once

#include "core/id_pool.hpp"

namespace sh {

class World;

/// Something a world calls before and after each full step, in registration order.
class StepHook {
public:
    virtual ~StepHook() = default;

    /// Before a step or a static solve, on the sim thread (e.g. take the newest device pose).
    virtual void before_step(World& world) = 0;

    /// After a step of dt (s), or after a static solve with dt = 0 (no motion to follow).
    virtual void after_step(World& world, double dt) = 0;

    /// Body id's topology changed between steps (a cut): whatever the hook keeps of it per node
    /// or element must be rebuilt before it is used again. Must not throw.
    virtual void topology_changed(World& world, Id id) noexcept {
        (void)world;
        (void)id;
    }

    /// The world is being destroyed: the hook must not touch it again.
    virtual void detach() = 0;
};

}  // namespace sh
