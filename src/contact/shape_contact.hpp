// The contact of a body's own node, surface edge or surface triangle with a rigid collider,
// shared by the full model (BodyContacts) and the haptic buffer: its geometry, the
// collider-relative velocity, the Hunt-Crossley and Coulomb law, explicit friction taken
// implicitly, and the pairing of surface triangles across their edges.
#pragma once

#include "contact/collider.hpp"
#include "contact/contact_point.hpp"
#include "contact/hunt_crossley.hpp"
#include "core/memory.hpp"

#include <softhap/softhap.h>

#include <cstddef>
#include <cstdint>

namespace sh {

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
/// gradient (the envelope theorem at the maximiser).
///
/// The share (0..1) of its excess a surface edge or triangle of size (m: its length, or its
/// longest edge) carries against the collider: 1 while the collider's inner radius is at most
/// the size (it can reach between the feature's nodes), 0 from twice the size on (the mesh
/// resolves its curvature: the excess is then only the interpolant's small error, whose
/// maximiser wanders with every node and slows Newton), a C^1 smoothstep between.
double excess_weight(const Collider& collider, double size);

/// Depth (m) over which a feature's excess fades out as its last nodes come into the collider
/// (the mesh then resolves the contact there): a fiftieth of the collider's inner radius.
double resolved_band(const Collider& collider);

/// The excess of a collider made of several balls (Shape::ball_count: a capsule is the balls
/// along its axis). Each ball i has the excess terms of a sphere over every surface edge and
/// triangle, whose signed sum over the surface is the ball's own excess there, P_i (with its
/// own nodes' depths in their interpolants and fades). The collider's excess is their Lehmer
/// mean of order p = kOrder,
///   X = sum_i P_i^(p+1) / sum_i P_i^p   (over P_i > 0),
/// a smooth maximum: equal to the P_i where they are equal (a capsule lying on a face: the
/// balls along its ridge reach equally deep, and the face's nodes share the ridge's push
/// evenly), equal to the only ball that reaches, otherwise between their mean and their
/// largest, within about 11 % of the largest as a capsule tilts onto one end. The exact
/// maximum would make its maximiser jump from one end of a lying capsule to the other as
/// the face tilts, and the forces on the face's nodes with it. Each feature's term takes
/// sum_i s_i T_i of its balls' terms T_i as its energy, s_i = P_i^p / sum_j P_j^p, and
/// sum_i c_i grad T_i as its gradient, c_i = P_i^(p-1) ((p+1) P_i - p X) / sum_j P_j^p: the
/// terms sum to X and their forces to X's gradient. So a collider of several balls takes
/// two passes over its terms per evaluation: add() for every term, finish(), then
/// excess_shape_contact.
class BallMix {
public:
    static constexpr int kOrder = 8;

    /// Makes room for count balls (allocates if there is less).
    void reserve(int count);

    /// Starts a sum over collider's balls (the room reserved must hold them).
    void begin(const Collider& collider);

    /// Adds the ball terms of the edge (count 2) or triangle (count 3) nodes at positions x
    /// (see excess_shape_contact) to the balls' totals.
    void add(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes, int count,
             double weight);

    /// Computes the shares and coefficients from the totals.
    void finish();

    /// Ball i's share s_i of its terms' energy and coefficient c_i of their gradients.
    double share(int i) const { return mix_[kFields * static_cast<size_t>(i) + 1]; }
    double coefficient(int i) const { return mix_[kFields * static_cast<size_t>(i) + 2]; }

    /// The Hessian of X over the totals, d c_i / d P_j = curvature_i delta_ij - (cross_i c_j +
    /// c_i cross_j) (1/J): the smooth maximum's own curvature, which stiffens a lying capsule's
    /// face against tilting (by far more than the law's curvature does).
    double curvature(int i) const { return mix_[kFields * static_cast<size_t>(i) + 3]; }
    double cross(int i) const { return mix_[kFields * static_cast<size_t>(i) + 4]; }

private:
    static constexpr size_t kFields = 5;
    vec<double> mix_;  ///< per ball: total P_i, share, coefficient, curvature, cross
    int count_ = 0;
};

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

/// out = p.hessian (p.has_hessian) projected to positive semi-definite: its negative
/// eigenvalues set to 0, so that the tangent bounds the term's curvature from above.
void positive_hessian(const ContactPoint& p, double out[9][9]);

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
