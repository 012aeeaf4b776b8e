// Arena: one allocation carved into the fixed-size arrays of a haptic context. The same carve
// sequence first measures (no memory) and then hands out pointers, so the size a context
// reports is exactly what it holds.
#pragma once

#include "core/memory.hpp"

#include <cstddef>
#include <cstdint>

namespace sh {

/// A bump allocator over one block; measuring when the block is null.
class Arena {
public:
    /// Measuring arena: take() returns null and only counts bytes.
    Arena() = default;

    /// Carving arena over bytes of memory at base (64-byte aligned).
    Arena(void* base, size_t bytes) : base_(static_cast<unsigned char*>(base)), capacity_(bytes) {}

    /// count zero-initialised Ts, 64-byte aligned (null while measuring).
    template <class T>
    T* take(size_t count) {
        used_ = (used_ + 63) & ~static_cast<size_t>(63);
        const size_t bytes = count * sizeof(T);
        T* out = nullptr;
        if (base_) {
            out = reinterpret_cast<T*>(base_ + used_);
            for (size_t i = 0; i < count; ++i) new (out + i) T();
        }
        used_ += bytes;
        return out;
    }

    /// Bytes taken so far (with alignment padding).
    size_t used() const { return used_; }

private:
    unsigned char* base_ = nullptr;
    size_t capacity_ = 0;
    size_t used_ = 0;
};

}  // namespace sh
