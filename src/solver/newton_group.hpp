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
    SteppedBody* alone_body;  ///< alone (null when coupled); its implicit state is the system
    CoupledSystem* coupled;   ///< together (null when alone)
    NewtonSystem& newton;     ///< the system solved

    static NewtonGroup alone(SteppedBody& stepped) { return NewtonGroup{&stepped, nullptr, *stepped.implicit}; }
    static NewtonGroup together(CoupledSystem& system) { return NewtonGroup{nullptr, &system, system}; }

    /// Calls visit(stepped, offset) for each body, offset its first DOF in newton.
    template <class Visit>
    void each(Visit&& visit) const {
        if (!coupled) {
            visit(*alone_body, size_t{0});
            return;
        }
        for (int32_t m = 0; m < coupled->member_count(); ++m) {
            const CoupledMember& member = coupled->member(m);
            visit(*member.stepped, static_cast<size_t>(member.offset));
        }
    }

    /// Assembles the system solved: assemble_member(stepped) fills each body's own system and
    /// returns its force round-off; coupled, the members' systems are added into the joint
    /// one with their coupling blocks (stiffness_scale K + damping_scale D, at rest or not).
    /// Returns the round-off of the forces.
    template <class AssembleMember>
    double assemble(AssembleMember&& assemble_member, double stiffness_scale, double damping_scale, bool at_rest) const {
        if (!coupled) return assemble_member(*alone_body);
        return coupled->assemble([&](CoupledMember& m) { return assemble_member(*m.stepped); }, stiffness_scale,
                                 damping_scale, at_rest);
    }

    uint64_t matrix_version() const { return coupled ? coupled->matrix_version() : alone_body->body->matrix_version; }

    /// |f_ext + m g| over the free DOFs (N).
    double applied_load_norm(const double g[3]) const {
        double sum = 0.0;
        each([&](const SteppedBody& m, size_t) {
            const Body& b = *m.body;
            for (const int32_t j : m.implicit->system.dof_to_global()) {
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
        each([&](const SteppedBody& m, size_t) {
            const Body& b = *m.body;
            const double* x = at_start ? m.workspace.x0.data() : b.x.data();
            double work = 0.0;
            for (const int32_t j : m.implicit->system.dof_to_global()) {
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
