// StepHook: what the world calls around each full step, so that layers above it (haptic
// contexts, and cutting) take part in the step without the world knowing them.
#pragma once

#include "core/id_pool.hpp"

#include <softhap/softhap.h>

#include <cstddef>
#include <cstdint>

namespace sh {

class World;

/// What a cutting tool's blade holds of a body under the physical criterion, as the cutting
/// hook shows it to the haptic contexts (a view: valid until the next step or cut).
struct BladeHold {
    const int32_t* nodes = nullptr;   ///< the held nodes, ascending
    const double* forces = nullptr;   ///< the material's force on each (3 each, N) at the last step's end
    size_t count = 0;
    double work = 0.0;     ///< the blade's work on them since the last break, to the last step's end (J)
    double needed = 0.0;   ///< the work a break costs (J)
    uint64_t serial = 0;   ///< which hold it is: each new set of held nodes gets the next
};

/// Something a world calls before and after each full step, in registration order.
class StepHook {
public:
    virtual ~StepHook() = default;

    /// Before a step or a static solve, on the sim thread (e.g. take the newest device pose).
    virtual void before_step(World& world) = 0;

    /// In a step, after every hook's before_step and before anything moves: changes to the
    /// scene that the step's motion must see (cutting), counted in report.
    virtual void before_motion(World& world, sh_step_report& report) {
        (void)world;
        (void)report;
    }

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

    /// Fills out with what tool's blade holds of body, if this hook cuts with it and holds
    /// something; false otherwise.
    virtual bool blade_hold(const World& world, Id tool, Id body, BladeHold& out) const {
        (void)world, (void)tool, (void)body, (void)out;
        return false;
    }
};

/// A hook that only changes the scene before each step's motion (cutting, tearing): its other
/// calls do nothing.
class BeforeMotionHook : public StepHook {
public:
    void before_step(World&) override {}
    void after_step(World&, double) override {}
    void detach() override {}
};

}  // namespace sh
