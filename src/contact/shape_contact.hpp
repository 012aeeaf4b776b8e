// The contact of a body's own node, surface edge or surface triangle with a rigid collider,
// shared by the full model (BodyContacts) and the haptic buffer: its geometry, the
// collider-relative velocity, the Hunt-Crossley and Coulomb law, explicit friction taken
// implicitly, and the pairing of surface triangles across their edges.
#pragma once

#include "contact/collider.hpp"
#include "contact/contact_point.hpp"
#include "contact/hunt_crossley.hpp"

#include <softhap/softhap.h>

#include <cstddef>
#include <cstdint>

namespace sh {

/// Node `node` (positions x) inside the collider: fills out's depth, normal, point and one
/// node of weight 1. False if it does not touch.
bool node_shape_contact(const Collider& collider, const double* x, int32_t node, ContactPoint& out);

/// The collider reaching through the triangle face (positions x) between its nodes: fills
/// out's geometry with the three nodes weighted barycentrically. False if it does not.
bool face_shape_contact(const Collider& collider, const double* x, const int32_t face[3], ContactPoint& out);

/// The collider on the convex surface edge (edge[0], edge[1]) between own triangle
/// (edge[0], edge[1], edge[2]) and the one across, (edge[1], edge[0], edge[3]), both outward:
/// fills out's geometry with the edge's two nodes and out.law_scale, the share of the law an
/// edge flatter than 15 degrees carries. False if the edge is not convex or not touched.
bool edge_shape_contact(const Collider& collider, const double* x, const int32_t edge[4], ContactPoint& out);

/// Velocity (m/s) of out's node side (its weighted nodes at velocities v) relative to the
/// collider's material point at out.point.
void velocity_against_collider(const Collider& collider, const ContactPoint& out, const double* v, double vrel[3]);

/// Fills out's normal law from its geometry: the Hunt-Crossley force times out.law_scale at
/// the relative velocity vrel (null: at rest), its stiffness and damping, out.relative_velocity,
/// and node forces of the normal force alone; no friction yet.
void apply_normal_law(const sh_contact_params& p, const double* vrel, ContactPoint& out);

/// apply_normal_law for a body stepped implicitly: the force of law (hunt_crossley_step_law,
/// whose damping is in the depth) at out.depth; out.damping is 0.
void apply_step_normal_law(const sh_contact_params& p, const StepLaw& law, const double* vrel, ContactPoint& out);

/// Adds Coulomb friction proportional to friction_normal (N) against out.relative_velocity's
/// tangential part to out's node forces, out.friction and out.friction_normal.
void apply_friction(const sh_contact_params& p, double friction_normal, ContactPoint& out);

/// A friction contact of an explicit (sub)step, as found at its start, to be taken implicitly
/// on the velocities the step reaches without it (apply_implicit_friction).
struct FrictionRecord {
    int32_t nodes[3];
    double weights[3];
    int count;
    double normal[3];
    double offset[3];      ///< sum of weights[a] v[a] minus the relative velocity (m/s)
    double normal_force;   ///< N
    double point[3];       ///< where it touched (m, world)
    const sh_contact_params* params;
};

/// The record of contact p (law params) at velocities v.
FrictionRecord friction_record(const ContactPoint& p, const sh_contact_params& params, const double* v);

/// Backward-Euler friction of record r over a step of h (s) on velocities v (and, when x is
/// not null, the positions the step reached with them), nodes of inverse masses inverse_mass:
/// the contact's tangential velocity ends at implicit_slip_speed's. Stable at any step: a
/// sticking contact creeps at most at slip_velocity. When impulse is not null it receives the
/// friction impulse on the node side (N s).
void apply_implicit_friction(const FrictionRecord& r, const double* inverse_mass, double h, double* x, double* v,
                             double impulse[3] = nullptr);

/// For the count surface triangles tris (3 nodes each), writes neighbor[3 t + k]: the triangle
/// across the edge from node k to node k + 1 of triangle t, or -1 unless exactly two triangles
/// share that edge. Allocates.
void pair_triangles_across_edges(const int32_t* tris, size_t count, int32_t* neighbor);

/// The node of triangle u (3 nodes) that is neither a nor b.
inline int32_t third_node(const int32_t* u, int32_t a, int32_t b) {
    return u[0] != a && u[0] != b ? u[0] : u[1] != a && u[1] != b ? u[1] : u[2];
}

}  // namespace sh
