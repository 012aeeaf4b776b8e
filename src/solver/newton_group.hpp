// NewtonGroup: the bodies one Newton loop (an implicit step or a static solve) solves for, seen
// the same way whether a body is alone or several are coupled.
#pragma once

#include "model/external_field.hpp"
#include "solver/coupled_system.hpp"
#include "solver/implicit_integrator.hpp"

#include <cmath>
#include <cstddef>
#include <limits>

namespace sh {

/// Round-off (J) of a sum of energy terms whose magnitudes add up to scale: what the Newton
/// line searches allow a potential to rise by and still count as not raised.
inline double sum_roundoff(double scale) { return 64.0 * std::numeric_limits<double>::epsilon() * scale; }

/// A body alone, whose own system is the one solved, or the members of a CoupledSystem.
struct NewtonGroup {
    Body* body;              ///< alone (null when coupled)
    ImplicitState* state;    ///< alone (null when coupled)
    CoupledSystem* coupled;  ///< together (null when alone)
    NewtonSystem& newton;    ///< the system solved

    static NewtonGroup alone(Body& body, ImplicitState& state) { return NewtonGroup{&body, &state, nullptr, state}; }
    static NewtonGroup together(CoupledSystem& system) { return NewtonGroup{nullptr, nullptr, &system, system}; }

    /// Calls visit(body, state, offset) for each body, offset its first DOF in newton.
    template <class Visit>
    void each(Visit&& visit) const {
        if (!coupled) {
            visit(*body, *state, size_t{0});
            return;
        }
        for (int32_t m = 0; m < coupled->member_count(); ++m) {
            const CoupledMember& member = coupled->member(m);
            visit(*member.body, *member.state, static_cast<size_t>(member.offset));
        }
    }

    /// Assembles the system solved: assemble_member(body, state) fills each body's own system
    /// and returns its force round-off; coupled, the members' systems are added into the joint
    /// one with their coupling blocks (stiffness_scale K + damping_scale D, at rest or not).
    /// Returns the round-off of the forces.
    template <class AssembleMember>
    double assemble(AssembleMember&& assemble_member, double stiffness_scale, double damping_scale, bool at_rest) const {
        if (!coupled) return assemble_member(*body, *state);
        return coupled->assemble([&](CoupledMember& m) { return assemble_member(*m.body, *m.state); }, stiffness_scale,
                                 damping_scale, at_rest);
    }

    uint64_t matrix_version() const { return coupled ? coupled->matrix_version() : body->matrix_version; }

    /// |f_ext + m g| over the free DOFs (N).
    double applied_load_norm(const double g[3]) const {
        double sum = 0.0;
        each([&](const Body& b, const ImplicitState& s, size_t) {
            for (const int32_t j : s.system.dof_to_global()) {
                const double load = b.applied_load(static_cast<size_t>(j), g);
                sum += load * load;
            }
        });
        return std::sqrt(sum);
    }

    /// The bodies' potential energy at their positions (at_start: the step's start,
    /// workspace.x0): elastic energy, the fields' potential, minus load_factor times the work
    /// of f_ext + m g over the free DOFs (J). scale gets the terms' magnitudes.
    double potential_energy(const double g[3], double load_factor, bool at_start, double& scale) const {
        double total = 0.0;
        scale = 0.0;
        each([&](const Body& b, const ImplicitState& s, size_t) {
            const double* x = at_start ? b.workspace.x0.data() : b.x.data();
            double work = 0.0;
            for (const int32_t j : s.system.dof_to_global()) {
                const size_t k = static_cast<size_t>(j);
                work += b.applied_load(k, g) * x[k];
            }
            const double elastic = b.elastic_energy(x), field = b.field ? b.field->energy(x) : 0.0;
            total += elastic + field - load_factor * work;
            scale += std::fabs(elastic) + std::fabs(field) + std::fabs(load_factor * work);
        });
        return total;
    }
};

}  // namespace sh
