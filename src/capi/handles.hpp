// Registry of live opaque objects, so that a destroyed or foreign pointer is reported as
// SH_ERR_INVALID_HANDLE instead of being dereferenced.
#pragma once

namespace sh::capi {

/// Kinds of opaque objects handed to the host.
enum class HandleKind { Mesh, World, Haptic };

/// Records object as live.
void register_handle(HandleKind kind, const void* object);

/// Forgets object; returns false if it was not live.
bool unregister_handle(HandleKind kind, const void* object);

/// Throws SH_ERR_INVALID_HANDLE naming `name` unless object is live and of this kind.
void require_handle(HandleKind kind, const void* object, const char* name);

}  // namespace sh::capi
