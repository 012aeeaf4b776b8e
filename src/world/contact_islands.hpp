// ContactIslands: the bodies that body-pair contacts link in a step, grouped into islands that
// are solved as one system (implicit steps, static solves), and the coupled systems kept for
// them from step to step. A world builds one only once it has body pairs.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

class CoupledSystem;
struct SteppedBody;
struct StepDoubling;

class ContactIslands {
public:
    /// Two world slots whose bodies have contact candidates between them.
    struct Link {
        uint32_t a, b;
    };

    ContactIslands() = default;
    ~ContactIslands();
    ContactIslands(const ContactIslands&) = delete;
    ContactIslands& operator=(const ContactIslands&) = delete;

    /// Groups slots [0, slot_count) into islands joined by links; returns the number of
    /// islands of more than one slot, the only ones kept.
    int32_t group(size_t slot_count);

    /// The island of slot (of more than one slot), or -1.
    int32_t island_of(size_t slot) const { return island_[slot]; }

    int32_t island_count() const { return static_cast<int32_t>(island_start_.size()) - 1; }

    /// Slots of island i, in increasing order.
    const uint32_t* members(int32_t i) const { return &member_slots_[static_cast<size_t>(island_start_[static_cast<size_t>(i)])]; }
    int32_t member_count(int32_t i) const {
        return island_start_[static_cast<size_t>(i) + 1] - island_start_[static_cast<size_t>(i)];
    }

    /// The coupled system kept for the bodies ids[0..count), made on first use. Those not
    /// asked for since the last drop_unused are destroyed by it.
    CoupledSystem& system(const uint64_t* ids, int32_t count);

    /// Destroys the kept systems not asked for since the last call.
    void drop_unused();

    vec<Link> links;  ///< the pairs (with contact candidates) group() joins, filled by the caller

    // One island's members as the caller gathers them (scratch).
    vec<SteppedBody*> stepped;
    vec<StepDoubling*> doublings;
    vec<uint64_t> ids;

private:
    struct Kept {
        vec<uint64_t> ids;
        CoupledSystem* system = nullptr;
        bool used = false;
    };
    uint32_t root(uint32_t slot);
    vec<uint32_t> parent_;         ///< union-find over slots
    vec<int32_t> island_;          ///< per slot
    vec<int32_t> island_start_;    ///< island i's members: [island_start_[i], island_start_[i + 1])
    vec<uint32_t> member_slots_;
    vec<Kept> kept_;
};

}  // namespace sh
