#include "contact/collider.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

void validate_contact_params(const sh_contact_params& p, const char* prefix) {
    SH_REQUIRE(std::isfinite(p.stiffness) && p.stiffness > 0.0, SH_ERR_INVALID_ARGUMENT,
               "%s.stiffness = %g N/m^n, must be finite and > 0", prefix, p.stiffness);
    SH_REQUIRE(std::isfinite(p.exponent) && p.exponent >= 1.0 && p.exponent <= 10.0, SH_ERR_INVALID_ARGUMENT,
               "%s.exponent = %g, must be in [1, 10]", prefix, p.exponent);
    SH_REQUIRE(std::isfinite(p.damping) && p.damping >= 0.0, SH_ERR_INVALID_ARGUMENT,
               "%s.damping = %g s/m, must be finite and >= 0", prefix, p.damping);
    SH_REQUIRE(std::isfinite(p.dynamic_friction) && p.dynamic_friction >= 0.0, SH_ERR_INVALID_ARGUMENT,
               "%s.dynamic_friction = %g, must be finite and >= 0", prefix, p.dynamic_friction);
    SH_REQUIRE(std::isfinite(p.static_friction) && p.static_friction >= p.dynamic_friction, SH_ERR_INVALID_ARGUMENT,
               "%s.static_friction = %g, must be finite and >= dynamic_friction (%g)", prefix, p.static_friction,
               p.dynamic_friction);
    SH_REQUIRE(std::isfinite(p.slip_velocity) && p.slip_velocity > 0.0, SH_ERR_INVALID_ARGUMENT,
               "%s.slip_velocity = %g m/s, must be finite and > 0", prefix, p.slip_velocity);
    SH_REQUIRE(p.capacity > 0, SH_ERR_INVALID_ARGUMENT, "%s.capacity = %d, must be > 0", prefix, p.capacity);
}

Pose checked_pose(const double position[3], const double orientation[4], const char* name) {
    require(position != nullptr && orientation != nullptr, SH_ERR_INVALID_ARGUMENT,
            format("%s: position and orientation must not be NULL", name));
    Pose pose;
    double norm = 0.0;
    for (int k = 0; k < 3; ++k) {
        SH_REQUIRE(std::isfinite(position[k]), SH_ERR_INVALID_ARGUMENT, "%s: position[%d] = %g is not finite", name, k,
                   position[k]);
        pose.p[k] = position[k];
    }
    for (int k = 0; k < 4; ++k) {
        SH_REQUIRE(std::isfinite(orientation[k]), SH_ERR_INVALID_ARGUMENT, "%s: orientation[%d] = %g is not finite",
                   name, k, orientation[k]);
        norm += orientation[k] * orientation[k];
    }
    norm = std::sqrt(norm);
    SH_REQUIRE(norm > 1e-12, SH_ERR_INVALID_ARGUMENT, "%s: orientation (%g, %g, %g, %g) is not a rotation (zero)", name,
               orientation[0], orientation[1], orientation[2], orientation[3]);
    for (int k = 0; k < 4; ++k) pose.q[k] = orientation[k] / norm;
    return pose;
}

namespace {

Pose initial_pose(const sh_collider_def& def, const Shape& shape) {
    if (shape.is_half_space()) {
        for (int k = 0; k < 3; ++k)
            SH_REQUIRE(std::isfinite(def.position[k]), SH_ERR_INVALID_ARGUMENT, "position[%d] = %g is not finite", k,
                       def.position[k]);
        return plane_pose(def.position, def.shape.normal);
    }
    return checked_pose(def.position, def.orientation, "def");
}

}  // namespace

Collider::Collider(const sh_collider_def& def, bool tool) : shape(def.shape), is_tool(tool), params(def.contact) {
    require(!(tool && shape.is_half_space()), SH_ERR_INVALID_ARGUMENT,
            "shape.kind = SH_SHAPE_PLANE: a plane can only be an obstacle, not a tool");
    validate_contact_params(params, "contact");
    pose = initial_pose(def, shape);
    start = pose;
    previous = pose;
    target = pose;
}

void Collider::begin_step(double dt) {
    if (velocity_given) {
        for (int k = 0; k < 3; ++k) {
            velocity[k] = given_velocity[k];
            angular[k] = given_angular[k];
        }
        return;
    }
    for (int k = 0; k < 3; ++k) velocity[k] = (target.p[k] - start.p[k]) / dt;
    // Relative rotation r = target * conj(start); angular velocity = axis * angle / dt.
    const double* a = target.q;
    const double b[4] = {start.q[0], -start.q[1], -start.q[2], -start.q[3]};
    double r[4] = {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3], a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                   a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1], a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
    if (r[0] < 0.0)
        for (double& c : r) c = -c;
    const double s = std::sqrt(r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
    const double angle = 2.0 * std::atan2(s, r[0]);
    for (int k = 0; k < 3; ++k) angular[k] = s > 0.0 ? r[k + 1] / s * angle / dt : 0.0;
}

double Collider::travel() const {
    if (shape.is_half_space()) return 0.0;
    double move = 0.0, dot = 0.0;
    for (int k = 0; k < 3; ++k) move += (target.p[k] - start.p[k]) * (target.p[k] - start.p[k]);
    for (int k = 0; k < 4; ++k) dot += target.q[k] * start.q[k];
    const double angle = 2.0 * std::acos(std::min(1.0, std::fabs(dot)));
    // The shape's farthest point from its origin bounds how far a rotation carries a point.
    double lo[3], hi[3];
    shape.bounds(Pose{}, 0.0, lo, hi);
    double reach = 0.0;
    for (int k = 0; k < 3; ++k) reach += std::fmax(lo[k] * lo[k], hi[k] * hi[k]);
    return std::sqrt(move) + angle * std::sqrt(reach);
}

}  // namespace sh
