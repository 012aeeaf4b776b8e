// ExternalField: forces on a body from outside it (contact), as the integrators and the static
// solver see them: a force at any state, its tangent, its potential and its stability limit.
#pragma once

#include <cstdint>

namespace sh {

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

    /// Potential energy of the field's conservative part at x (J).
    virtual double energy(const double* x) const = 0;

    /// Largest explicit step (s) that stays stable under the field at (x, v) for nodes of
    /// these masses (kg); INFINITY when the field adds no stiffness.
    virtual double stable_step(const double* x, const double* v, const double* mass) const = 0;
};

}  // namespace sh
