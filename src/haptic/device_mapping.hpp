// DeviceMapping: a haptic device's frame, units and tool offset against the world, and the
// force scale (sh_device_mapping). Pure arithmetic: nothing here allocates, locks or throws,
// so a device loop may call it.
#pragma once

#include "collision/pose.hpp"

#include <softhap/softhap.h>

namespace sh {

/// A checked sh_device_mapping: the device frame's pose in the world (unit quaternion), the
/// length scale, the tool offset and the force scale.
struct DeviceMapping {
    Pose base;
    double scale = 1.0;
    double tool_offset[3] = {0.0, 0.0, 0.0};
    double force_scale = 1.0;
};

/// Reads m's fields into out; false (out untouched) if one is not usable, with *field naming
/// it ("scale", "base_orientation", ...; static text). internal_init is the C API's to check.
bool read_device_mapping(const sh_device_mapping& m, DeviceMapping& out, const char** field) noexcept;

/// The world pose of the tool for device pose d.
Pose device_to_world(const DeviceMapping& m, const Pose& d) noexcept;

/// The device pose for world pose w (the inverse of device_to_world).
Pose world_to_device(const DeviceMapping& m, const Pose& w) noexcept;

/// A world wrench in the device frame, times the force scale.
void device_wrench(const DeviceMapping& m, const double force[3], const double torque[3], double out_force[3],
                   double out_torque[3]) noexcept;

}  // namespace sh
