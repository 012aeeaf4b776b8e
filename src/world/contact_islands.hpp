// ContactIslands: the bodies that body-pair contacts link in a step, grouped into islands that
// are solved as one Newton problem (implicit steps, static solves), and the problems kept for
// them from step to step. A world builds one only once it has body pairs.
#pragma once

#include "core/id_pool.hpp"
#include "core/memory.hpp"
#include "model/body.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

class NewtonProblem;
struct SteppedBody;
struct StepDoubling;

/// The islands of bodies linked by contact candidates in one step, and the Newton problems kept
/// for them across steps.
class ContactIslands {
public:
    /// Two world slots whose bodies have contact candidates between them.
    struct Link {
        uint32_t a, b;  ///< the two slots
    };

    ContactIslands() = default;  ///< no islands, no kept problems
    ~ContactIslands();           ///< destroys the kept problems
    ContactIslands(const ContactIslands&) = delete;             ///< owns the kept problems
    ContactIslands& operator=(const ContactIslands&) = delete;  ///< owns the kept problems

    /// Groups slots [0, slot_count) into islands joined by links; returns the number of
    /// islands of more than one slot, the only ones kept.
    int32_t group(size_t slot_count);

    /// The island of slot (of more than one slot), or -1.
    int32_t island_of(size_t slot) const { return island_[slot]; }

    /// Number of islands (of more than one slot).
    int32_t island_count() const { return static_cast<int32_t>(island_start_.size()) - 1; }

    /// Slots of island i, in increasing order.
    const uint32_t* members(int32_t i) const { return &member_slots_[static_cast<size_t>(island_start_[static_cast<size_t>(i)])]; }
    /// Number of slots of island i.
    int32_t member_count(int32_t i) const {
        return island_start_[static_cast<size_t>(i) + 1] - island_start_[static_cast<size_t>(i)];
    }

    /// The Newton problem kept for the bodies ids[0..count) solved together, made on first
    /// use. Those not asked for since the last drop_unused are destroyed by it.
    NewtonProblem& problem(const Id* ids, int32_t count);

    /// Destroys the kept problems not asked for since the last call.
    void drop_unused();

    vec<Link> links;  ///< the pairs (with contact candidates) group() joins, filled by the caller

    // One island's members as the caller gathers them (scratch).
    vec<SteppedBody*> stepped;     ///< the members' stepped bodies
    vec<StepDoubling*> doublings;  ///< their step-doubling scratch
    vec<Id> ids;           ///< their ids

private:
    /// A Newton problem kept for one set of bodies solved together.
    struct Kept {
        vec<Id> ids;               ///< its bodies, in order
        NewtonProblem* problem = nullptr;  ///< owned
        bool used = false;                 ///< asked for since the last drop_unused
    };
    /// The root of slot's set in the union-find (halving its path).
    uint32_t root(uint32_t slot);
    vec<uint32_t> parent_;         ///< union-find over slots
    vec<int32_t> island_;          ///< per slot
    vec<int32_t> island_start_;    ///< island i's members: [island_start_[i], island_start_[i + 1])
    vec<uint32_t> member_slots_;   ///< every island's slots, island after island
    vec<Kept> kept_;               ///< the problems kept across steps
};

}  // namespace sh
