// ExternalField: forces on a body from outside it (contact), as the integrators and the static
// solver see them: a force at any state, its tangent, its potential and its stability limit.
#pragma once

#include "core/memory.hpp"

#include <cstdint>

namespace sh {

class Body;
class SparseSystem;

/// Forces a body feels from outside its own elements, evaluated at any state the integrators
/// try, like internal forces. The world attaches one to a body for the duration of a step.
class ExternalField {
public:
    virtual ~ExternalField() = default;

    /// Adds the field's forces at positions x and velocities v (3 per node; v null: at rest)
    /// into f (N).
    virtual void add_forces(const double* x, const double* v, double* f) const = 0;

    /// Adds stiffness_scale * K + damping_scale * D into system, K = -df/dx and D = -df/dv
    /// (their positive semi-definite parts) at (x, v), for the nodes with free_index >= 0.
    virtual void add_tangent(const double* x, const double* v, double stiffness_scale, double damping_scale,
                             const int32_t* free_index, SparseSystem& system) const = 0;

    /// Potential energy of the field's conservative part at x (J). An interaction with another
    /// body counts half here and half in that body's field, so the fields of bodies solved
    /// together sum to their joint potential.
    virtual double energy(const double* x) const = 0;

    /// Implicit steps: the dissipation potential (W) of the field's velocity-dependent forces
    /// at velocities v, whose gradient in v is minus those forces (friction with its normal
    /// force lagged). 0 by default.
    virtual double dissipation(const double* v) const {
        (void)v;
        return 0.0;
    }

    /// True if the field can do work on the body during the step (a moving collider, another
    /// body), so that the body's energy may rise. False by default.
    virtual bool does_work() const { return false; }

    /// Largest explicit step (s) that stays stable under the field at (x, v) for nodes of
    /// these masses (kg); INFINITY when the field adds no stiffness.
    virtual double stable_step(const double* x, const double* v, const double* mass) const = 0;

    /// Explicit integrators: called before each (sub)step; its first add_forces is at the
    /// (sub)step's start state. Nothing by default.
    virtual void begin_explicit_step() const {}

    /// Explicit integrators: called after a (sub)step of length h (s) took the body to x, v.
    /// Applies what the field leaves out of add_forces for explicit bodies (contact friction,
    /// taken implicitly on the new velocities); move_positions: each velocity change also
    /// moves its node by h times it (the step's positions used its end velocities). Nothing
    /// by default.
    virtual void end_explicit_step(double h, bool move_positions, double* x, double* v) const {
        (void)h, (void)move_positions, (void)x, (void)v;
    }

    /// Appends to pairs, as two node indices each, the pairs of the body's own nodes whose
    /// tangent blocks add_tangent fills though they may share no element (a contact whose
    /// terms span several faces), for the step's contacts as detected. The Newton matrix's
    /// pattern holds them; a block it lacks goes onto both nodes' diagonals as a bound. None
    /// by default.
    virtual void add_tangent_links(vec<int32_t>& pairs) const { (void)pairs; }

    /// For bodies solved together (one Newton problem over several bodies): appends to pairs, as (own_index[i],
    /// other_index[j]), every pair of this body's node i and other's node j that an interaction
    /// this field holds links, both indices >= 0 (each interaction is held by one of the two
    /// bodies' fields). None by default.
    virtual void add_coupling_pattern(const Body& other, const int32_t* own_index, const int32_t* other_index,
                                      vec<int32_t>& pairs) const {
        (void)other, (void)own_index, (void)other_index, (void)pairs;
    }

    /// For bodies solved together: adds the blocks stiffness_scale * K + damping_scale * D
    /// between this body's nodes (rows own_index) and other's (columns other_index) of the
    /// interactions add_coupling_pattern reports, at this body's (x, v) and other's current
    /// state (v null: at rest). Their transposes come with them (the system is symmetric).
    virtual void add_coupling_tangent(const double* x, const double* v, double stiffness_scale, double damping_scale,
                                      const int32_t* own_index, const Body& other, const int32_t* other_index,
                                      SparseSystem& system) const {
        (void)x, (void)v, (void)stiffness_scale, (void)damping_scale, (void)own_index, (void)other, (void)other_index,
            (void)system;
    }
};

}  // namespace sh
