// Generation-checked ids: how an id names a slot of a pool, and the pool that hands them out.
// An id is the slot's generation in its high 32 bits and the slot's index + 1 in its low 32
// bits, so 0 is the null id and a made-up or stale id is told apart from a live one by reading
// the pool only, never the object. Generations come from one process-wide counter, so an id
// is never valid in another pool (another world) or after its slot was reused.
#pragma once

#include "core/memory.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace sh {

/// An id of an object a pool owns (bodies, tools and obstacles of a world; the C API's opaque
/// handles). The C API's id structs carry this value.
using Id = uint64_t;

/// The null id: names nothing.
constexpr Id kNullId = 0;

/// The id of slot index while it holds generation (generation is never 0).
constexpr Id pack_id(uint32_t index, uint32_t generation) {
    return (static_cast<uint64_t>(generation) << 32) | (static_cast<uint64_t>(index) + 1);
}

/// The slot index id names; meaningless for the null id (check id_generation first).
constexpr uint32_t id_index(Id id) { return static_cast<uint32_t>(id & 0xffffffffu) - 1u; }

/// The generation id carries: 0 for the null id and for any value no pool issued.
constexpr uint32_t id_generation(Id id) { return static_cast<uint32_t>(id >> 32); }

/// A fresh generation for a slot being filled: never 0, and not seen again until the 32-bit
/// counter wraps. Thread-safe and lock-free (worlds and handles on any thread share it).
inline uint32_t next_generation() {
    // One counter for the process, so that ids of different pools differ.
    static std::atomic<uint32_t> counter{1};
    uint32_t g = counter.fetch_add(1, std::memory_order_relaxed);
    while (g == 0) g = counter.fetch_add(1, std::memory_order_relaxed);
    return g;
}

/// Objects of type T (a pointer or a small struct of pointers, T{} meaning none) in slots
/// named by generation-checked ids. A released slot is reused by a later allocate under a new
/// generation. Slot indices are stable, so callers may keep arrays parallel to the slots.
/// Single-threaded: the owner serialises calls.
template <class T>
class IdPool {
public:
    /// Puts value in a free slot (or a new one) and returns its new id. Throws
    /// std::bad_alloc with the pool unchanged; after a successful allocate, release never
    /// allocates.
    Id allocate(T value) {
        uint32_t index;
        if (!free_.empty()) {
            index = free_.back();
            free_.pop_back();
        } else {
            // Room for every slot in the free list, so that release never allocates.
            if (free_.capacity() < values_.size() + 1) free_.reserve(2 * values_.size() + 1);
            values_.push_back(T{});
            try {
                generations_.push_back(0);
            } catch (...) {
                values_.pop_back();
                throw;
            }
            index = static_cast<uint32_t>(values_.size() - 1);
        }
        values_[index] = value;
        generations_[index] = next_generation();
        ++live_;
        return pack_id(index, generations_[index]);
    }

    /// True if id names a live slot of this pool.
    bool contains(Id id) const {
        const uint32_t generation = id_generation(id), index = id_index(id);
        return generation != 0 && index < generations_.size() && generations_[index] == generation;
    }

    /// The value of id's slot, or null if id is not live here.
    T* find(Id id) { return contains(id) ? &values_[id_index(id)] : nullptr; }

    /// The value of id's slot, or null if id is not live here.
    const T* find(Id id) const { return contains(id) ? &values_[id_index(id)] : nullptr; }

    /// Ends id's life (it must be live: check with contains) and returns its value; the slot
    /// holds T{} until reused. Never allocates.
    T release(Id id) {
        const uint32_t index = id_index(id);
        T value = values_[index];
        values_[index] = T{};
        generations_[index] = 0;
        free_.push_back(index);  // within the capacity reserved in allocate
        --live_;
        return value;
    }

    /// Number of slots, live or free: the bound of slot indices.
    size_t size() const { return values_.size(); }

    /// Number of live slots.
    size_t live_count() const { return live_; }

    /// True if slot index is live.
    bool is_live(size_t index) const { return generations_[index] != 0; }

    /// The value of slot index (T{} if free).
    T& operator[](size_t index) { return values_[index]; }

    /// The value of slot index (T{} if free).
    const T& operator[](size_t index) const { return values_[index]; }

    /// The id of live slot index.
    Id id_at(size_t index) const { return pack_id(static_cast<uint32_t>(index), generations_[index]); }

    /// Calls visit(value) for every live slot, in slot order.
    template <class Visit>
    void for_each(Visit&& visit) {
        for (size_t index = 0; index < values_.size(); ++index)
            if (generations_[index] != 0) visit(values_[index]);
    }

    /// Calls visit(value) for every live slot, in slot order.
    template <class Visit>
    void for_each(Visit&& visit) const {
        for (size_t index = 0; index < values_.size(); ++index)
            if (generations_[index] != 0) visit(values_[index]);
    }

private:
    vec<T> values_;              ///< per slot: its value, T{} while free
    vec<uint32_t> generations_;  ///< per slot: its live generation, 0 while free
    vec<uint32_t> free_;         ///< free slots, the last freed reused first
    size_t live_ = 0;            ///< live slots
};

}  // namespace sh
