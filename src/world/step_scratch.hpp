// StepScratch: what a world's step writes and drops again, gathered in one object the world
// owns and reuses from step to step, so that a warmed-up step allocates nothing for it.
#pragma once

#include "contact/body_contacts.hpp"
#include "core/memory.hpp"
#include "solver/explicit_integrator.hpp"

#include <cstddef>
#include <cstdint>

namespace sh {

/// What one step's attempts keep about one body (see World::run_attempts).
struct BodyAttempt {
    vec<double> saved;        ///< x then v at the step's start, for attempts of more than one
                              ///< sub-step
    BodyStepResult failure;   ///< why the body's last attempt failed
    bool failed = false;      ///< its last attempt in this step failed
    bool keep_best = false;   ///< this attempt is its last: keep the best iterate
};

/// A world's step scratch, indexed like the world's body slots.
struct StepScratch {
    vec<BodyAttempt> bodies;  ///< per body slot
    vec<uint8_t> skip;        ///< per body slot: sits out the current attempt
    ContactScratch contact;   ///< every body's contact evaluation (lent to its BodyContacts)

    /// Makes room for body slot index (of slot_count) whose state (x then v) has state_size
    /// values, so that a step allocates nothing. Throws std::bad_alloc.
    void reserve_body(size_t slot_count, size_t index, size_t state_size) {
        if (bodies.size() < slot_count) bodies.resize(slot_count);
        reserve_growing(bodies[index].saved, state_size);
        skip.reserve(slot_count);
    }

    /// Frees body slot index's saved state (its body is gone).
    void release_body(size_t index) { bodies[index].saved = vec<double>(); }
};

}  // namespace sh
