#include "solver/newton_problem.hpp"

#include "core/error.hpp"
#include "model/external_field.hpp"
#include "solver/node_links.hpp"

#include <algorithm>
#include <utility>

namespace sh {
namespace {

// The work of f_ext + m g over m's free DOFs at positions x (J per unit load factor).
double load_work(const SteppedBody& m, const double g[3], const double* x) {
    double work = 0.0;
    for (const int32_t j : m.newton->matrix.system.dof_to_global()) {
        const size_t k = static_cast<size_t>(j);
        work += m.body->applied_load(k, g) * x[k];
    }
    return work;
}

}  // namespace

void NewtonProblem::prepare(SteppedBody* const* bodies, int32_t count, const sh_implicit_settings& settings) {
    SH_REQUIRE(!alone_, SH_ERR_INTERNAL, "a body's own Newton problem cannot take other bodies");
    bool rebuild = !joint_.solver || body_count() != count;
    if (body_count() != count) members_.resize(static_cast<size_t>(count));
    int32_t offset = 0;
    for (int32_t m = 0; m < count; ++m) {
        CoupledMember& member = members_[static_cast<size_t>(m)];
        NewtonBodyState& state = *bodies[m]->newton;
        const int32_t dofs = state.prepare(*bodies[m]->body, bodies[m]->settings.implicit, false);
        rebuild |= member.stepped != bodies[m] || member.offset != offset ||
                   member.pattern_id != state.matrix.system.pattern_id();
        member.stepped = bodies[m];
        member.offset = offset;
        state.matrix.kept.valid = false;  // its matrix holds this solve's values from now on
        offset += dofs;
    }
    if (rebuild) map_joint_nodes(members_);
    collect_coupled_links(members_, pairs_, needed_);
    vec<uint64_t> links;
    if (links_to_build(links_, needed_, rebuild, links)) build_joint(links, settings);
}

void NewtonProblem::build_joint(vec<uint64_t>& links, const sh_implicit_settings& settings) {
    SparseSystem joint = build_joint_pattern(members_, links);
    map_member_slots(members_, joint);
    LinearSolverPtr solver = make_analysed_solver(joint, settings);
    joint_.reset(std::move(joint), std::move(solver));
    links_.swap(links);
    for (CoupledMember& m : members_) m.pattern_id = m.state().matrix.system.pattern_id();
}

void NewtonProblem::add_member_values(const CoupledMember& m) {
    const vec<double>& own = m.state().matrix.system.values();
    double* joint = joint_.system.values().data();
    for (size_t p = 0; p < own.size(); ++p) joint[m.slots[p]] += own[p];
}

void NewtonProblem::add_coupling(double stiffness_scale, double damping_scale, bool at_rest) {
    for (const CoupledMember& a : members_) {
        if (!a.body().field) continue;
        for (const CoupledMember& b : members_)
            if (&a != &b)
                a.body().field->add_coupling_tangent(a.body().x.data(), at_rest ? nullptr : a.body().v.data(), stiffness_scale,
                                                    damping_scale, a.joint_index.data(), b.body(), b.joint_index.data(),
                                                    joint_.system);
    }
}

double NewtonProblem::applied_load_norm(const double g[3]) const {
    double sum = 0.0;
    each([&](const SteppedBody& m, size_t) {
        const Body& b = *m.body;
        for (const int32_t j : m.newton->matrix.system.dof_to_global()) {
            const double load = b.applied_load(static_cast<size_t>(j), g);
            sum += load * load;
        }
    });
    return std::sqrt(sum);
}

double NewtonProblem::potential_energy(const double g[3], double load_factor, bool at_start, double& scale) const {
    double total = 0.0;
    scale = 0.0;
    each([&](const SteppedBody& m, size_t) {
        const Body& b = *m.body;
        const double* x = at_start ? m.workspace.x0.data() : b.x.data();
        const double work = load_work(m, g, x);
        const double elastic = b.elastic_energy_recalled(x), field = b.field ? b.field->energy(x) : 0.0;
        total += elastic + field - load_factor * work;
        scale += std::fabs(elastic) + std::fabs(field) + std::fabs(load_factor * work);
    });
    return total;
}

double NewtonProblem::potential_energy_from(const double g[3], double load_factor, double stored) const {
    double total = stored;
    each([&](const SteppedBody& m, size_t) { total -= load_factor * load_work(m, g, m.body->x.data()); });
    return total;
}

}  // namespace sh
