#include "solver/static_solver.hpp"

#include "core/error.hpp"
#include "model/external_field.hpp"
#include "solver/implicit_integrator.hpp"
#include "solver/step_support.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// Out-of-balance force f(x) + load_factor * (f_ext + m g) on the free DOFs, and its norm.
double out_of_balance(const Body& body, const ImplicitState& state, const double g[3], double load_factor,
                      vec<double>& force_scratch, vec<double>& out) {
    std::fill(force_scratch.begin(), force_scratch.end(), 0.0);
    body.add_internal_forces(body.x.data(), nullptr, force_scratch.data());
    if (body.field) body.field->add_forces(body.x.data(), nullptr, force_scratch.data());
    const vec<int32_t>& global = state.system.dof_to_global();
    double s = 0.0;
    for (size_t d = 0; d < out.size(); ++d) {
        const size_t j = static_cast<size_t>(global[d]);
        out[d] = force_scratch[j] + load_factor * body.applied_load(j, g);
        s += out[d] * out[d];
    }
    return std::sqrt(s);
}

// Potential energy: elastic energy minus the work of the applied loads.
double potential(const Body& body, const ImplicitState& state, const double g[3], double load_factor) {
    double work = 0.0;
    for (const int32_t j : state.system.dof_to_global()) {
        const size_t k = static_cast<size_t>(j);
        work += body.applied_load(k, g) * body.x[k];
    }
    const double field = body.field ? body.field->energy(body.x.data()) : 0.0;
    return body.elastic_energy(body.x.data()) + field - load_factor * work;
}

}  // namespace

void solve_static_body(Body& body, const double g[3], const sh_static_def& def, sh_static_report& report) {
    bool anchored = false;
    for (const uint8_t k : body.kinematic) anchored |= k != 0;
    require(anchored, SH_ERR_SOLVER,
            "a body has no fixed or prescribed node: it can float freely, so its stiffness is singular and it has "
            "no static equilibrium (fix or prescribe nodes first)");
    ImplicitState state;
    sh_implicit_settings solver{};
    solver.linear_solver = def.linear_solver;
    solver.cg_tolerance = std::max(1e-3 * def.tolerance, 1e-15);  // well below the Newton tolerance
    solver.cg_max_iterations = 20000;
    const int32_t dofs = prepare_implicit_state(body, state, solver);
    end_kinematic_motion(body);  // fixed and prescribed nodes on their targets
    std::fill(body.v.begin(), body.v.end(), 0.0);
    if (dofs == 0) return;

    vec<double> scratch(body.x.size()), residual(static_cast<size_t>(dofs)), step(static_cast<size_t>(dofs), 0.0);
    vec<double> saved(body.x.size());
    const vec<int32_t>& global = state.system.dof_to_global();
    // Scale of the residual: the full applied load, or 1 N if nothing is applied.
    double load_norm = 0.0;
    for (const int32_t j : global) {
        const size_t k = static_cast<size_t>(j);
        const double load = body.applied_load(k, g);
        load_norm += load * load;
    }
    load_norm = load_norm > 0.0 ? std::sqrt(load_norm) : 1.0;

    for (int32_t load_step = 1; load_step <= def.load_steps; ++load_step) {
        const double factor = static_cast<double>(load_step) / def.load_steps;
        double r = out_of_balance(body, state, g, factor, scratch, residual) / load_norm;
        bool converged = r <= def.tolerance;
        double floor = 0.0;
        for (int32_t iteration = 0; iteration < def.max_iterations && !converged; ++iteration) {
            state.system.clear_values();
            body.add_tangent(body.x.data(), 1.0, 0.0, state.system);
            if (body.field) body.field->add_tangent(body.x.data(), nullptr, 1.0, 0.0, state.free_index.data(), state.system);
            // Below the round-off of the internal forces the residual cannot fall further.
            floor = std::max(floor, force_roundoff(state.system, body.x, 1.0) / load_norm);
            state.solver->factorize(state.system);
            state.solver->solve(state.system, residual.data(), step.data());
            double slope = 0.0;  // d potential / d alpha at alpha = 0
            for (size_t d = 0; d < residual.size(); ++d) slope -= residual[d] * step[d];
            const double energy0 = potential(body, state, g, factor), r0 = r;
            std::copy(body.x.begin(), body.x.end(), saved.begin());
            double alpha = 1.0;
            for (int trial = 0; trial < 30; ++trial, alpha *= 0.5) {
                for (size_t d = 0; d < step.size(); ++d) {
                    const size_t j = static_cast<size_t>(global[d]);
                    body.x[j] = saved[j] + alpha * step[d];
                }
                r = out_of_balance(body, state, g, factor, scratch, residual) / load_norm;
                const double energy = potential(body, state, g, factor);
                if ((std::isfinite(energy) && energy <= energy0 + 1e-4 * alpha * slope) || r < r0) break;
            }
            ++report.iterations;
            if (report.history_count < SH_STATIC_HISTORY) report.residual_history[report.history_count++] = r;
            converged = r <= std::max(def.tolerance, floor);
            require(std::isfinite(r), SH_ERR_SOLVER, "the Newton iteration produced a non-finite state");
        }
        report.residual = std::max(report.residual, r);
        if (!converged)
            throw Error(SH_ERR_NOT_CONVERGED,
                        format("static solve: relative residual %.3g after %d iterations of load step %d/%d (tolerance %g)",
                               r, def.max_iterations, load_step, def.load_steps, def.tolerance));
    }
    report.load_steps = std::max(report.load_steps, def.load_steps);
}

}  // namespace sh
