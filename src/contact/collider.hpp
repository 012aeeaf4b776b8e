// Collider: a rigid tool or static obstacle as the contact code sees it: shape, pose over the
// step, velocity, contact law and the reaction it felt.
#pragma once

#include "collision/pose.hpp"
#include "collision/shape.hpp"

#include <softhap/softhap.h>

#include <cstring>

namespace sh {

/// Validates a contact law; messages name the field as prefix.field ("contact.stiffness").
void validate_contact_params(const sh_contact_params& params, const char* prefix);

/// A rigid tool (posed by the host) or a static obstacle.
struct Collider {
    /// Validates def (shape, pose, contact law; a plane only as an obstacle) and places the
    /// collider at def's pose.
    Collider(const sh_collider_def& def, bool is_tool);

    Shape shape;
    bool is_tool;
    sh_contact_params params;
    Pose pose;    ///< where it is during the current (sub)step
    Pose start;   ///< where the last step left it
    Pose previous;  ///< where it was at the start of the current (sub)step
    Pose target;  ///< where the next step takes it (a tool's host-set pose)
    double velocity[3] = {};  ///< of its position during the current step (m/s)
    double angular[3] = {};   ///< angular velocity during the current step (rad/s)
    bool velocity_given = false;  ///< the host gave the next step's velocity
    double given_velocity[3] = {}, given_angular[3] = {};
    sh_contact_state state{};  ///< reaction and measures after the last step
    bool cuts = false;         ///< a cutting tool (sh_tool_set_cutting)
    sh_cut_def cutting{};      ///< how it cuts, when cuts

    /// Velocity (m/s) of the collider's material point at world point q.
    void point_velocity(const double q[3], double out[3]) const {
        const double r[3] = {q[0] - pose.p[0], q[1] - pose.p[1], q[2] - pose.p[2]};
        out[0] = velocity[0] + angular[1] * r[2] - angular[2] * r[1];
        out[1] = velocity[1] + angular[2] * r[0] - angular[0] * r[2];
        out[2] = velocity[2] + angular[0] * r[1] - angular[1] * r[0];
    }

    /// Sets velocity and angular for a step of dt from start to target, unless given.
    void begin_step(double dt);

    /// Largest distance (m) any point of the shape travels between start and target.
    double travel() const;

    /// The shape's balls at pose. A contact pass asks for them per surface feature at one
    /// pose: they are kept for the last pose asked (so a collider serves one thread at a time,
    /// as it does: the world's on the sim thread, a haptic context's copy on the device's).
    const BallRow& balls() const {
        if (!(balls_known_ && std::memcmp(&balls_pose_, &pose, sizeof(Pose)) == 0)) {
            balls_ = shape.ball_row(pose);
            balls_pose_ = pose;
            balls_known_ = true;
        }
        return balls_;
    }

private:
    mutable BallRow balls_;
    mutable Pose balls_pose_;
    mutable bool balls_known_ = false;
};

/// A normalised copy of a host quaternion (w, x, y, z); throws SH_ERR_INVALID_ARGUMENT
/// naming `name` if it is not finite or is zero.
Pose checked_pose(const double position[3], const double orientation[4], const char* name);

}  // namespace sh
