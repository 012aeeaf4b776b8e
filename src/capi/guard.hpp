// The C boundary: every extern "C" entry point runs its body through sh::capi::guard, which
// turns exceptions into status codes and records the thread's last-error message.
#pragma once

#include "core/error.hpp"

#include <softhap/softhap.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <new>

namespace sh::capi {

/// Records the calling thread's last-error message (truncated to a fixed buffer: no allocation).
void set_last_error(const char* message);

/// Clears the calling thread's last-error message.
void clear_last_error();

/// Runs body() and returns SH_OK, or the status of what it threw, with the message recorded.
template <class Body>
sh_status guard(Body&& body) noexcept {
    try {
        clear_last_error();
        body();
        return SH_OK;
    } catch (const Error& e) {
        set_last_error(e.message().c_str());
        return e.status();
    } catch (const std::bad_alloc&) {
        set_last_error("out of memory");
        return SH_ERR_OUT_OF_MEMORY;
    } catch (const std::exception& e) {
        set_last_error(e.what());
        return SH_ERR_INTERNAL;
    } catch (...) {
        set_last_error("unknown internal error");
        return SH_ERR_INTERNAL;
    }
}

/// Throws SH_ERR_INVALID_ARGUMENT naming `name` when pointer is null.
inline void require_pointer(const void* pointer, const char* name) {
    if (!pointer) throw Error(SH_ERR_INVALID_ARGUMENT, format("%s is NULL", name));
}

/// Throws SH_ERR_INVALID_ARGUMENT naming `name` when value is not finite.
inline void require_finite(double value, const char* name) {
    if (!std::isfinite(value)) throw Error(SH_ERR_INVALID_ARGUMENT, format("%s is not finite", name));
}

/// Throws SH_ERR_INVALID_ARGUMENT when the output array `name`, with room for `capacity`
/// items (nodes, tets, ...: `items` names them), cannot hold the `needed` ones.
inline void require_capacity(int32_t capacity, size_t needed, const char* name, const char* items) {
    if (capacity < 0 || static_cast<size_t>(capacity) < needed)
        throw Error(SH_ERR_INVALID_ARGUMENT, format("%s: capacity %d is smaller than the %zu %s to copy", name,
                                                    static_cast<int>(capacity), needed, items));
}

/// Copies source, values_per_item values for each item (3 per node for positions, 4 per tet),
/// into the output array `name`, which has room for capacity items (`items` names them).
template <class T, class Vector>
void copy_out(const Vector& source, size_t values_per_item, T* out, int32_t capacity, const char* name,
              const char* items) {
    require_pointer(out, name);
    require_capacity(capacity, source.size() / values_per_item, name, items);
    std::copy(source.begin(), source.end(), out);
}

/// Magic value that *_def_default writes into internal_init.
constexpr uint32_t kDefInitialised = 0x53484446u;  // "SHDF"

/// Throws SH_ERR_UNINITIALIZED_DEF unless def->internal_init was set by its default function.
template <class Def>
void require_initialised(const Def* def, const char* name) {
    require_pointer(def, name);
    if (def->internal_init != kDefInitialised)
        throw Error(SH_ERR_UNINITIALIZED_DEF,
                    format("%s was not initialised by its *_default function", name));
}

}  // namespace sh::capi
