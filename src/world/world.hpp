// World: owns bodies behind generation-checked ids and steps them.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

struct ImplicitState;
struct StepDoubling;

/// The simulation world of the C API's sh_world.
class World {
public:
    explicit World(const sh_world_def& def);
    ~World();
    World(const World&) = delete;
    World& operator=(const World&) = delete;

    /// Takes ownership of body (made with sh::create) and returns its new id.
    sh_body_id add_body(Body* body);

    /// Destroys the body; its id becomes stale. Throws SH_ERR_INVALID_HANDLE if not live.
    void remove_body(sh_body_id id);

    /// True if id names a live body of this world.
    bool is_valid(sh_body_id id) const;

    /// The body named by id; throws SH_ERR_INVALID_HANDLE if the id is null, stale or foreign.
    Body& body(sh_body_id id) const;

    /// Steps every body by dt; fills report if not null. Throws SH_ERR_UNSTABLE (after
    /// filling report and advancing the stable bodies) if any body was rejected or rolled back.
    void step(double dt, sh_step_report* report);

    /// Moves every body to static equilibrium (see sh_world_solve_static); on failure every
    /// body is restored and the error rethrown.
    void solve_static(const sh_static_def& def, sh_static_report* report);

    double gravity[3];
    uint64_t warnings[SH_WARN_COUNT] = {};

private:
    struct Slot {
        Body* body = nullptr;
        ImplicitState* implicit = nullptr;  ///< built on the first implicit step
        StepDoubling* doubling = nullptr;   ///< with error_estimate_ only
        uint32_t generation = 0;
    };
    void destroy_slot(Slot& slot);
    bool error_estimate_ = false;
    sh_body_id id_of(size_t index) const;
    vec<Slot> slots_;
    vec<uint32_t> free_slots_;
};

}  // namespace sh
