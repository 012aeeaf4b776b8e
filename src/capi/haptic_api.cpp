// C API: haptic contexts (the Volumetric Buffer Model).
#include "capi/guard.hpp"
#include "capi/handles.hpp"
#include "capi/world_handle.hpp"
#include "haptic/haptic_context.hpp"

using namespace sh;

namespace {

HapticContext& context_of(const sh_haptic* haptic) {
    return capi::object_of<HapticContext>(capi::HandleKind::Haptic, haptic, "haptic");
}

sh_haptic_def checked_def(const sh_haptic_def* def) {
    capi::require_initialised(def, "def");
    validate_haptic_def(*def);
    return *def;
}

}  // namespace

extern "C" {

SH_API void sh_haptic_def_default(sh_haptic_def* def) {
    if (!def) return;
    *def = sh_haptic_def{};
    def->internal_init = capi::kDefInitialised;
    def->capacity_tets = 2000;
    def->capacity_nodes = 2000;
    def->radius = 0.02;
    def->rings = 0;
    def->dt = 1e-3;
    def->max_force = 10.0;
    def->max_force_rate = 2000.0;
    def->ramp_time = 0.05;
    def->stale_after = 0.1;
}

SH_API sh_status sh_haptic_memory_bytes(const sh_haptic_def* def, size_t* out_bytes) {
    return capi::guard([&] {
        capi::require_pointer(out_bytes, "out_bytes");
        *out_bytes = 0;
        *out_bytes = HapticContext::memory_bytes(checked_def(def));
    });
}

SH_API sh_status sh_haptic_create(sh_world* world, const sh_haptic_def* def, sh_haptic** out_haptic) {
    return capi::guard([&] {
        capi::require_pointer(out_haptic, "out_haptic");
        *out_haptic = nullptr;
        World& w = capi::world_of(world);
        const sh_haptic_def d = checked_def(def);
        SH_REQUIRE(w.is_valid_collider(d.tool.value, true), SH_ERR_INVALID_HANDLE,
                   "def->tool = 0x%llx is not a live tool of this world", static_cast<unsigned long long>(d.tool.value));
        HapticContext* context = sh::create<HapticContext>(w, d);
        try {
            w.add_hook(context);
            *out_haptic = static_cast<sh_haptic*>(const_cast<void*>(capi::register_handle(capi::HandleKind::Haptic, context)));
        } catch (...) {
            w.remove_hook(context);
            sh::destroy(context);
            throw;
        }
    });
}

SH_API sh_status sh_haptic_destroy(sh_haptic* haptic) {
    return capi::guard([&] {
        if (!haptic) return;
        auto* context = static_cast<HapticContext*>(capi::unregister_handle(capi::HandleKind::Haptic, haptic));
        require(context != nullptr, SH_ERR_INVALID_HANDLE, "haptic is not a live object (destroyed twice or never created)");
        if (World* w = context->world()) w->remove_hook(context);
        sh::destroy(context);
    });
}

SH_API sh_status sh_haptic_step(sh_haptic* haptic, const double position[3], const double orientation[4], double dt,
                                sh_haptic_output* out_output) {
    // No guard: nothing here throws, and the step must not touch the last-error message's
    // formatting (it allocates). The handle check reads the handle table only.
    auto* context = static_cast<HapticContext*>(capi::find_handle(capi::HandleKind::Haptic, haptic));
    if (!context) return SH_ERR_INVALID_HANDLE;
    if (!out_output) return SH_ERR_INVALID_ARGUMENT;
    return context->step(position, orientation, dt, *out_output);
}

SH_API sh_status sh_haptic_get_warnings(const sh_haptic* haptic, uint64_t out_counts[SH_WARN_COUNT]) {
    return capi::guard([&] {
        HapticContext& context = context_of(haptic);
        capi::require_pointer(out_counts, "out_counts");
        context.read_warnings(out_counts);
    });
}

}  // extern "C"
