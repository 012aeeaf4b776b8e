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

class BallMix;

/// The share of node a's row in contact p's stiffness k g g^T, per unit k: |g_a| sum_b |g_b|
/// (Gershgorin's bound on the row), for the stable step of an explicit integrator.
double stiffness_share(const ContactPoint& p, int a);

/// Sets out's count nodes with their shares weights, and their depth gradients weights[a]
/// times out.normal (which must be set).
void set_contact_nodes(int count, const int32_t* nodes, const double* weights, ContactPoint& out);

/// Node `node` (positions x) inside the collider: fills out's depth, normal, point and one
/// node of weight 1. False if it does not touch.
bool node_shape_contact(const Collider& collider, const double* x, int32_t node, ContactPoint& out);

/// The contact potential of a body's surface against a collider is
///   E = sum_nodes psi(d_i) + sum_faces X_f - sum_edges X_e,
/// psi the law's potential of a depth, d_i a node's depth, and X the excess of a triangle or
/// an edge: the most that psi(depth(x)) exceeds, over the closed feature, the linear
/// interpolant of its nodes' psi(d_i) (at a node the excess is 0). Node terms carry what the
/// mesh resolves; the excess carries a tool reaching between nodes, and hands over to a node
/// smoothly as it comes in (the node's own term grows by what the interpolant takes away).
/// Counting faces minus edges (plus vertices, whose excess is 0) over the region where the
/// excess exceeds a level counts its connected pieces (its Euler characteristic), so each
/// region where the tool reaches beyond the nodes is carried once: a tool smaller than the
/// triangles feels the law psi'(d) at its depth d whether it touches a face, an edge or a
/// vertex, the force is continuous as it slides across them, and a flat tool on nodes adds
/// nothing to them. Each term is a function of the nodes' positions, its forces its exact
/// gradient (the envelope theorem at the maximiser). This is a sphere's excess; a capsule's is
/// a smooth maximum over the balls along its axis, each with a sphere's terms (BallMix), and
/// boxes, convex hulls and planes have none.
///
/// The share (0..1) of its excess a surface edge or triangle of size (m: its length, or its
/// longest edge) carries against the collider: 1 while the collider's inner radius is at most
/// the size (it can reach between the feature's nodes), 0 from twice the size on (the mesh
/// resolves its curvature: the excess is then only the interpolant's small error, whose
/// maximiser wanders with every node and slows Newton), a C^1 smoothstep between.
double excess_weight(const Collider& collider, double size);

/// Depth (m) over which a feature's excess fades out as its last nodes come into the collider
/// (the mesh then resolves the contact there). For a sphere, a fiftieth of its radius: its
/// excess over a feature whose nodes are all in it is the interpolant's small error. For a
/// collider of other shape, its balls' radius: a ball's excess takes the nodes' depths in
/// that ball, which may be 0 for a node deep in the collider, so the excess it fades is up to
/// the law's over the radius, and a narrow band would turn it into a force spike on the node
/// crossing it (a rendered buzz, and Newton creeping).
double resolved_band(const Collider& collider);

/// The excess term of the surface edge (count 2) or outward triangle (count 3) nodes at
/// positions x under law (the step's, or the law at rest): fills out's geometry at the
/// maximiser (depth, point, weights, normal), its signed energy and law_scale (-1 for an
/// edge), node forces, stiffness (psi'' at the depth, signed; for the tangent), normal_force
/// (psi', signed) and net_normal_force, all scaled by weight (excess_weight) and the fade of
/// resolved_band. A collider of several balls mixes its balls' terms by mix (BallMix, summed
/// over the same body's terms; required for it), its geometry then the terms' weighted by
/// their shares of the energy. False if the excess is not positive or has no weight, and for
/// colliders without balls (box, convex hull: their nodes carry them; plane: its depth is
/// linear).
bool excess_shape_contact(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes,
                          int count, double weight, const BallMix* mix, ContactPoint& out);

/// Explicit bodies: scales an excess term's forces by the Hunt-Crossley damping factor
/// 1 + 3/2 alpha x' (at least 0) at the depth rate x' its point has at relative velocity vrel.
void apply_excess_damping(const sh_contact_params& p, const double vrel[3], ContactPoint& out);

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

/// The friction contact of surface node `node` (positions x, velocities v) against collider:
/// a point of weight 1 at the node, its normal along push and its friction_normal |push| (N),
/// push the net force of all the collider's contact terms on the node; no friction force yet
/// (apply_friction). Friction is taken per node, not per term: a node's own, edge and face
/// terms push along different normals, and friction per term would resist its motion across
/// all their tangent planes, separation from the tool included.
ContactPoint node_friction_point(const Collider& collider, int32_t node, const double push[3], const double* x,
                                 const double* v);

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

}  // namespace sh
