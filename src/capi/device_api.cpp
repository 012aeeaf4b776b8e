// C API: the device mapping. The per-tick transforms never throw nor set the last-error
// message (a device loop calls them); sh_device_mapping_check says what is wrong, once.
#include "capi/guard.hpp"
#include "core/vec3.hpp"
#include "haptic/device_mapping.hpp"

using namespace sh;

namespace {

// m read and checked; false for NULL, not initialised or an unusable field.
bool usable(const sh_device_mapping* m, DeviceMapping& out, const char** field) noexcept {
    if (!m || m->internal_init != capi::kDefInitialised) return false;
    return read_device_mapping(*m, out, field);
}

// One pose through map (device_to_world or world_to_device); the outputs only on success.
sh_status map_pose(const sh_device_mapping* mapping, Pose (*map)(const DeviceMapping&, const Pose&) noexcept,
                   const double position[3], const double orientation[4], double out_position[3],
                   double out_orientation[4]) noexcept {
    DeviceMapping m;
    Pose in;
    if (!usable(mapping, m, nullptr) || !read_pose(position, orientation, in) || !out_position ||
        !out_orientation)
        return SH_ERR_INVALID_ARGUMENT;
    const Pose out = map(m, in);
    for (int k = 0; k < 3; ++k) out_position[k] = out.p[k];
    for (int k = 0; k < 4; ++k) out_orientation[k] = out.q[k];
    return SH_OK;
}

}  // namespace

extern "C" {

SH_API void sh_device_mapping_default(sh_device_mapping* mapping) {
    if (!mapping) return;
    *mapping = sh_device_mapping{};
    mapping->internal_init = capi::kDefInitialised;
    mapping->scale = 1.0;
    mapping->base_orientation[0] = 1.0;
    mapping->force_scale = 1.0;
}

SH_API sh_status sh_device_mapping_check(const sh_device_mapping* mapping) {
    return capi::guard([&] {
        capi::require_initialised(mapping, "mapping");
        DeviceMapping m;
        const char* field = "";
        SH_REQUIRE(read_device_mapping(*mapping, m, &field), SH_ERR_INVALID_ARGUMENT,
                   "mapping->%s is not usable (scales finite and > 0, positions finite, base_orientation a finite "
                   "non-zero quaternion)",
                   field);
    });
}

SH_API sh_status sh_device_to_world(const sh_device_mapping* mapping, const double device_position[3],
                                    const double device_orientation[4], double out_position[3],
                                    double out_orientation[4]) {
    return map_pose(mapping, device_to_world, device_position, device_orientation, out_position, out_orientation);
}

SH_API sh_status sh_world_to_device(const sh_device_mapping* mapping, const double position[3],
                                    const double orientation[4], double out_device_position[3],
                                    double out_device_orientation[4]) {
    return map_pose(mapping, world_to_device, position, orientation, out_device_position, out_device_orientation);
}

SH_API sh_status sh_device_force(const sh_device_mapping* mapping, const double force[3], const double torque[3],
                                 double out_device_force[3], double out_device_torque[3]) {
    DeviceMapping m;
    if (!usable(mapping, m, nullptr) || !force || !torque || !out_device_force || !out_device_torque ||
        !finite3(force) || !finite3(torque))
        return SH_ERR_INVALID_ARGUMENT;
    double f[3], t[3];
    device_wrench(m, force, torque, f, t);
    for (int k = 0; k < 3; ++k) out_device_force[k] = f[k], out_device_torque[k] = t[k];
    return SH_OK;
}

}  // extern "C"
