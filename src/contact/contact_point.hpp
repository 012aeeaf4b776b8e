// ContactPoint: one acting contact as the contact code evaluates it at a state.
#pragma once

#include <cstdint>

namespace sh {

/// One acting contact, as evaluate() reports it.
struct ContactPoint {
    double depth;            ///< penetration (m), > 0
    double normal[3];        ///< unit direction of the push on the node side (node or face)
    double point[3];         ///< touching point (world)
    int32_t nodes[3];        ///< own nodes the contact acts on
    int count;               ///< 1, 2 (kEdgeShape) or 3
    double weights[3];       ///< own nodes' shares of the node side's motion and friction (sign
                             ///< included: kFaceNode's own face is the far side)
    double gradient[3][3];   ///< per own node: -d depth / d x, its weight times the normal (the
                             ///< normal force on it is the normal force times this; for an
                             ///< excess term, the same at its maximiser, for the tangent only)
    double node_force[3][3]; ///< per own node: the force it feels (N)
    double stiffness;        ///< dFn/dx (N/m)
    double damping;          ///< dFn/dx' (N s/m)
    double friction;         ///< viscous coefficient of the friction (N s/m)
    double normal_force;     ///< Hunt-Crossley normal force (N)
    double friction_normal;  ///< normal force the friction is proportional to (N); 0: no friction
    double relative_velocity[3]; ///< node side's velocity relative to the other side (m/s)
    double law_scale;        ///< the sign of the term in the contact potential: -1 for an
                             ///< edge's excess, else 1 (shape_contact.hpp)
    double energy;           ///< excess terms: the term's potential, sign included (J)
    double net_normal_force; ///< what its friction is proportional to (N): the normal force, or
                             ///< for an excess term the net push of its node forces along
                             ///< the normal, sign included
    double other_weights[3]; ///< kNodeFace: the other body's face nodes' shares (-w, the far
                             ///< side); their gradients are these times the normal
    /// A collider's excess term mixed over its balls (BallMix::term): the full model's
    /// tangent takes the mix's across its terms (BallMix::tangent), not stiffness g g^T, and
    /// stiffness_bound holds an upper bound (N/m) on each node's rows of the term's stiffness,
    /// along every axis (the mix's gradients are not along the normal alone), for an explicit
    /// integrator's stable step and the haptic buffer's contact tangent. Else false.
    bool mixed = false;
    double stiffness_bound[3];
};

/// Node a's stiffness_bound for a mixed term, else 0 (N/m).
inline double mixed_stiffness_bound(const ContactPoint& p, int a) { return p.mixed ? p.stiffness_bound[a] : 0.0; }

/// The weight of p's normal tangent, g_a g_b^T per pair of its nodes (a mixed term: its
/// damping's only), in a matrix
/// stiffness_scale K + damping_scale D: a subtracted term (an edge's excess, whose stiffness is
/// negative) is left out, so that the tangent stays positive semi-definite (and bounds the
/// potential's Hessian from above).
inline double normal_tangent_scale(const ContactPoint& p, double stiffness_scale, double damping_scale) {
    // A term mixed over a collider's balls has its stiffness elsewhere (BallMix::tangent).
    const double scale = (p.mixed ? 0.0 : stiffness_scale * p.stiffness) + damping_scale * p.damping;
    return scale > 0.0 ? scale : 0.0;
}

}  // namespace sh
