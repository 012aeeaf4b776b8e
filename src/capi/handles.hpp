// The handle table: what the opaque sh_mesh*, sh_world* and sh_haptic* the host holds stand
// for. A handle is not an address but a generation-checked id (core/id_pool.hpp: a slot index
// and the slot's generation, the encoding of the world's ids), so checking one reads only this
// table, never the object: a destroyed, foreign or made-up handle is reported as
// SH_ERR_INVALID_HANDLE, with no read of freed memory, in O(1) and without a lock.
#pragma once

#include <cstdint>

namespace sh::capi {

/// Kinds of opaque objects handed to the host.
enum class HandleKind : uint8_t { Mesh = 1, World = 2, Haptic = 3 };

/// Most objects (meshes, worlds and haptic contexts together) alive at once.
constexpr uint32_t kMaxLiveHandles = 1u << 16;

/// A new handle naming object, of kind (the caller keeps ownership of object). Throws
/// SH_ERR_OUT_OF_MEMORY when kMaxLiveHandles objects are alive. Thread-safe (takes a lock).
const void* register_handle(HandleKind kind, void* object);

/// Ends handle's life and returns its object, or null if handle is not a live one of kind.
/// Thread-safe (takes a lock).
void* unregister_handle(HandleKind kind, const void* handle);

/// The object of handle if it is a live one of kind, else null. Lock-free, allocation-free.
void* find_handle(HandleKind kind, const void* handle) noexcept;

/// find_handle, or throws SH_ERR_INVALID_HANDLE naming `name` (NULL, or not live).
void* require_handle(HandleKind kind, const void* handle, const char* name);

/// require_handle as a T.
template <class T>
T& object_of(HandleKind kind, const void* handle, const char* name) {
    return *static_cast<T*>(require_handle(kind, handle, name));
}

}  // namespace sh::capi
