// The contact of a body's own node or surface triangle with a rigid collider, shared by the
// full model (BodyContacts) and the haptic buffer: its geometry, the collider-relative
// velocity and the Hunt-Crossley and Coulomb law.
#pragma once

#include "contact/body_contacts.hpp"

namespace sh {

/// Node `node` (positions x) inside the collider: fills out's depth, normal, point and one
/// node of weight 1. False if it does not touch.
bool node_shape_contact(const Collider& collider, const double* x, int32_t node, ContactPoint& out);

/// The collider reaching through the triangle face (positions x) between its nodes: fills
/// out's geometry with the three nodes weighted barycentrically. False if it does not.
bool face_shape_contact(const Collider& collider, const double* x, const int32_t face[3], ContactPoint& out);

/// Velocity (m/s) of out's node side (its weighted nodes at velocities v) relative to the
/// collider's material point at out.point.
void velocity_against_collider(const Collider& collider, const ContactPoint& out, const double* v, double vrel[3]);

/// Fills out's stiffness, damping, friction and node forces from its geometry by the law p at
/// relative velocity vrel (null: at rest, no damping nor friction). friction_cap > 0 caps the
/// friction's viscous coefficient (N s/m).
void apply_contact_law(const sh_contact_params& p, const double* vrel, double friction_cap, ContactPoint& out);

}  // namespace sh
