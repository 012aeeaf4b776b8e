// Version, status strings, last-error message and the allocator hook.
#include "capi/guard.hpp"
#include "core/log.hpp"
#include "core/memory.hpp"

#include <cstring>

namespace sh::capi {
namespace {
thread_local char t_last_error[1024] = "";
}

void set_last_error(const char* message) {
    std::strncpy(t_last_error, message, sizeof(t_last_error) - 1);
    t_last_error[sizeof(t_last_error) - 1] = '\0';
}

void clear_last_error() { t_last_error[0] = '\0'; }

}  // namespace sh::capi

using namespace sh;

extern "C" {

SH_API int32_t sh_version(void) { return SH_VERSION; }

SH_API uint32_t sh_build_features(void) {
    uint32_t features = 0;
#if SOFTHAP_WITH_CHOLMOD
    features |= SH_FEATURE_CHOLMOD;
#endif
#if SOFTHAP_WITH_CCD
    features |= SH_FEATURE_CCD;
#endif
    return features;
}

SH_API const char* sh_status_string(sh_status status) {
    switch (status) {
        case SH_OK: return "SH_OK: success";
        case SH_ERR_INVALID_ARGUMENT: return "SH_ERR_INVALID_ARGUMENT: a parameter is invalid";
        case SH_ERR_INVALID_HANDLE: return "SH_ERR_INVALID_HANDLE: a NULL, destroyed or stale handle";
        case SH_ERR_UNINITIALIZED_DEF: return "SH_ERR_UNINITIALIZED_DEF: def not initialised by its default function";
        case SH_ERR_OUT_OF_MEMORY: return "SH_ERR_OUT_OF_MEMORY: an allocation failed";
        case SH_ERR_IO: return "SH_ERR_IO: a file could not be read or written";
        case SH_ERR_PARSE: return "SH_ERR_PARSE: malformed file content";
        case SH_ERR_DEGENERATE_MESH: return "SH_ERR_DEGENERATE_MESH: invalid mesh data";
        case SH_ERR_UNSTABLE: return "SH_ERR_UNSTABLE: step rejected or rolled back";
        case SH_ERR_UNSUPPORTED: return "SH_ERR_UNSUPPORTED: feature not available";
        case SH_ERR_SOLVER: return "SH_ERR_SOLVER: a linear solve failed";
        case SH_ERR_NOT_CONVERGED: return "SH_ERR_NOT_CONVERGED: an iteration did not converge";
        case SH_ERR_CAPACITY: return "SH_ERR_CAPACITY: a fixed capacity would be exceeded";
        case SH_ERR_BUSY: return "SH_ERR_BUSY: not allowed while objects are alive";
        case SH_ERR_INTERNAL: return "SH_ERR_INTERNAL: internal error";
    }
    return "unknown status";
}

SH_API const char* sh_last_error_message(void) { return capi::t_last_error; }

SH_API sh_status sh_set_allocator(const sh_allocator* allocator) {
    return capi::guard([&] {
        if (allocator && (!allocator->alloc || !allocator->free))
            throw Error(SH_ERR_INVALID_ARGUMENT, "allocator->alloc and allocator->free must not be NULL");
        if (live_object_count() != 0)
            throw Error(SH_ERR_BUSY, format("%d softhap objects are alive; destroy them first", live_object_count()));
        set_allocator(allocator);
    });
}

SH_API sh_status sh_set_log_callback(sh_log_fn callback, void* user) {
    return capi::guard([&] {
        if (live_object_count() != 0)
            throw Error(SH_ERR_BUSY, format("%d softhap objects are alive; destroy them first", live_object_count()));
        set_log_callback(callback, user);
    });
}

}  // extern "C"
