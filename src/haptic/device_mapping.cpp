#include "haptic/device_mapping.hpp"

#include "core/vec3.hpp"

#include <cmath>

namespace sh {

bool read_device_mapping(const sh_device_mapping& m, DeviceMapping& out, const char** field) noexcept {
    const char* bad = nullptr;
    Pose base;
    if (!(std::isfinite(m.scale) && m.scale > 0.0)) bad = "scale";
    else if (!(std::isfinite(m.force_scale) && m.force_scale > 0.0)) bad = "force_scale";
    else if (!finite3(m.tool_offset)) bad = "tool_offset";
    else if (!finite3(m.base_position)) bad = "base_position";
    else if (!read_pose(m.base_position, m.base_orientation, base)) bad = "base_orientation";
    if (bad) {
        if (field) *field = bad;
        return false;
    }
    out.base = base;
    out.scale = m.scale;
    for (int k = 0; k < 3; ++k) out.tool_offset[k] = m.tool_offset[k];
    out.force_scale = m.force_scale;
    return true;
}

Pose device_to_world(const DeviceMapping& m, const Pose& d) noexcept {
    // p = base + scale R_base (p_d + R_d offset), q = q_base q_d
    double tip[3], local[3];
    d.to_world(m.tool_offset, tip);
    for (int k = 0; k < 3; ++k) local[k] = m.scale * tip[k];
    Pose w;
    m.base.to_world(local, w.p);
    quaternion_product(m.base.q, d.q, w.q);
    return w;
}

Pose world_to_device(const DeviceMapping& m, const Pose& w) noexcept {
    // q_d = q_base^* q, p_d = R_base^T (p - base) / scale - R_d offset
    const double base_inverse[4] = {m.base.q[0], -m.base.q[1], -m.base.q[2], -m.base.q[3]};
    Pose d;
    quaternion_product(base_inverse, w.q, d.q);
    double local[3], offset[3];
    m.base.to_local(w.p, local);
    d.rotate(m.tool_offset, offset);
    for (int k = 0; k < 3; ++k) d.p[k] = local[k] / m.scale - offset[k];
    return d;
}

void device_wrench(const DeviceMapping& m, const double force[3], const double torque[3], double out_force[3],
                   double out_torque[3]) noexcept {
    m.base.unrotate(force, out_force);
    m.base.unrotate(torque, out_torque);
    for (int k = 0; k < 3; ++k) {
        out_force[k] *= m.force_scale;
        out_torque[k] *= m.force_scale;
    }
}

}  // namespace sh
