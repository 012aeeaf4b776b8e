#include "solver/implicit_integrator.hpp"

#include "core/error.hpp"
#include "model/external_field.hpp"
#include "solver/step_support.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sh {
namespace {

// Speeds below this (m/s) count as rest when judging a Newton correction negligible.
constexpr double kSpeedFloor = 1e-9;

// An update solved with a kept factorisation is kept only if it cuts the residual at least by
// this factor (chord iterations slower than this cost more solves than a new factorisation is
// worth), and one factorisation serves at most kMaxStaleSolves such solves in a step.
constexpr double kStaleContraction = 0.5;
constexpr int kMaxStaleSolves = 4;

// Newton iterations allowed to a body with contact candidates, whatever its settings.
constexpr int kContactNewtonIterations = 20;

LinearSolverKind solver_kind(sh_linear_solver kind) {
    switch (kind) {
        case SH_LINEAR_SOLVER_CHOLMOD: return LinearSolverKind::Cholmod;
        case SH_LINEAR_SOLVER_LDLT: return LinearSolverKind::Ldlt;
        case SH_LINEAR_SOLVER_CG: return LinearSolverKind::ConjugateGradient;
        default: return (sh_build_features() & SH_FEATURE_CHOLMOD) ? LinearSolverKind::Cholmod : LinearSolverKind::Ldlt;
    }
}

double norm(const vec<double>& a) {
    double s = 0.0;
    for (double v : a) s += v * v;
    return std::sqrt(s);
}

}  // namespace

double force_roundoff(const SparseSystem& system, const vec<double>& x, double scale) {
    double largest = 0.0;
    for (const double c : x) largest = std::max(largest, std::fabs(c));
    double sum = 0.0;
    for (int32_t d = 0; d < system.dof_count(); ++d) {
        const double k = scale * system.values()[static_cast<size_t>(system.diagonal_slot(d))];
        sum += k * k;
    }
    return 64.0 * std::numeric_limits<double>::epsilon() * largest * std::sqrt(sum);
}

int32_t prepare_implicit_state(const Body& body, ImplicitState& state, const sh_implicit_settings& s) {
    const int32_t n = body.node_count();
    bool changed = state.free_count < 0;
    int32_t free_count = 0;
    if (!changed)
        for (int32_t i = 0; i < n && !changed; ++i) changed = (state.free_index[static_cast<size_t>(i)] >= 0) != body.is_free(i);
    if (!changed) return 3 * state.free_count;

    vec<int32_t> free_index(static_cast<size_t>(n), -1);
    for (int32_t i = 0; i < n; ++i)
        if (body.is_free(i)) free_index[static_cast<size_t>(i)] = free_count++;
    SparseSystem system;
    system.build_pattern(body.element_nodes(), static_cast<size_t>(body.element_count()), body.nodes_per_element(),
                         free_index.data(), n, free_count);
    LinearSolverPtr solver = make_linear_solver(solver_kind(s.linear_solver), s.cg_tolerance, s.cg_max_iterations);
    if (free_count > 0) solver->analyze(system);
    const size_t dofs = 3 * static_cast<size_t>(free_count);
    vec<double> residual(dofs), delta(dofs, 0.0), diagonal(dofs), previous_v(dofs);
    // Commit only once everything is built.
    state.system = std::move(system);
    state.solver = std::move(solver);
    state.free_index.swap(free_index);
    state.residual.swap(residual);
    state.delta.swap(delta);
    state.diagonal.swap(diagonal);
    state.previous_v.swap(previous_v);
    state.factor_valid = false;
    state.free_count = free_count;
    return 3 * free_count;
}

namespace {

// One attempt at the step; allow_stale: updates may use a kept factorisation. used_stale
// tells whether any did.
BodyStepResult attempt_step(Body& body, ImplicitState& state, double dt, const double g[3], bool allow_stale,
                            bool& used_stale) {
    BodyStepResult result;
    result.dt_critical = INFINITY;
    const sh_implicit_settings& s = body.settings.implicit;
    const int32_t dofs = prepare_implicit_state(body, state, s);
    const vec<int32_t>& global = state.system.dof_to_global();
    IntegratorWorkspace& w = body.workspace;
    const size_t n3 = body.x.size();

    save_start_state(body);
    begin_kinematic_motion(body, dt);
    const bool reuse = s.factor_reuse > 0.0 && state.solver->is_direct();  // keep factorisations
    bool factor_current = reuse && allow_stale && state.factor_valid && state.factor_dt == dt &&
                          state.factor_matrix_version == body.matrix_version;

    double applied_load = 0.0;  // |f_ext + m g| over the free DOFs (N)
    for (int32_t d = 0; d < dofs; ++d) {
        const size_t j = static_cast<size_t>(global[static_cast<size_t>(d)]);
        const double load = body.applied_load(j, g);
        applied_load += load * load;
    }
    applied_load = std::sqrt(applied_load);
    const double gravity_norm = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);

    // Newton on g(v) = M (v - v0) - dt F(x0 + dt v, v) over the free DOFs, from v = v0.
    double* a = w.a[0].data();
    double largest_residual = 0.0;  // max norm of the last residual_norm()
    auto residual_norm = [&] {
        for (size_t j = 0; j < n3; ++j) body.x[j] = w.x0[j] + dt * body.v[j];
        compute_accelerations(body, body.x.data(), body.v.data(), g, a);
        largest_residual = 0.0;
        for (int32_t d = 0; d < dofs; ++d) {
            const size_t j = static_cast<size_t>(global[static_cast<size_t>(d)]);
            const double r_d = body.mass[j / 3] * (body.v[j] - w.v0[j] - dt * a[j]);
            state.residual[static_cast<size_t>(d)] = r_d;
            largest_residual = std::max(largest_residual, std::fabs(r_d));
        }
        return norm(state.residual);
    };
    auto fail = [&](sh_status status, const char* reason) {
        restore_start_state(body);
        state.factor_valid = false;  // built at an iterate that went wrong
        result.stable = false;
        result.status = status;
        result.reason = reason;
        return result;
    };

    // Contacts switch on and off within a step, which a single linearised update cannot
    // follow (it cycles between too deep and too shallow): a body in contact iterates.
    const int max_iterations = std::max(body.field ? kContactNewtonIterations : 1, s.newton_max_iterations);
    const bool linearised = max_iterations == 1;
    double r = residual_norm(), r_max = largest_residual;
    const double residual0 = std::max(r, dt * applied_load);
    // Updates with a kept factorisation must reach this in both norms: the max norm keeps a
    // small badly-solved region from hiding in the sum.
    const double target = s.factor_reuse * r, target_max = s.factor_reuse * r_max;
    result.newton_residual = -1.0;
    bool converged = residual0 == 0.0;
    bool fresh = false;    // the factorisation is of the tangent at the current iterate
    int stale_solves = 0;  // solves with a kept factorisation since the last factorisation
    for (int iteration = 0; !converged;) {
        // Converged: small against the first residual or the applied load's impulse, or down
        // to the round-off of the element forces themselves.
        if (iteration > 0 && r <= std::max(s.newton_tolerance * residual0, state.roundoff_floor)) {
            converged = true;
            break;
        }
        if (iteration == max_iterations) break;

        try {
            if (!factor_current || stale_solves == kMaxStaleSolves) {
                const bool per_node = !body.node_damping.empty();
                for (int32_t d = 0; d < dofs; ++d) {
                    const size_t node = static_cast<size_t>(global[static_cast<size_t>(d)]) / 3;
                    const double c = body.settings.damping_mass + (per_node ? body.node_damping[node] : 0.0);
                    state.diagonal[static_cast<size_t>(d)] = body.mass[node] * (1.0 + dt * c);
                }
                state.factor_valid = false;
                state.system.clear_values();
                body.add_tangent(body.x.data(), dt * dt, dt, state.system);
                if (body.field)
                    body.field->add_tangent(body.x.data(), body.v.data(), dt * dt, dt, state.free_index.data(),
                                            state.system);
                state.roundoff_floor = force_roundoff(state.system, body.x, 1.0 / dt);  // system: dt^2 K
                state.system.add_diagonal(state.diagonal.data(), 1.0);
                state.solver->factorize(state.system);
                result.factorize_seconds += state.solver->factorize_seconds;
                ++result.factorizations;
                state.factor_valid = reuse;
                state.factor_dt = dt;
                state.factor_matrix_version = body.matrix_version;
                factor_current = true;
                fresh = true;
                stale_solves = 0;
            }
            for (double& r_d : state.residual) r_d = -r_d;
            result.linear_iterations += state.solver->solve(state.system, state.residual.data(), state.delta.data());
            result.solve_seconds += state.solver->solve_seconds;
        } catch (const Error& e) {
            if (e.status() == SH_ERR_NOT_CONVERGED) return fail(e.status(), "the linear solver did not converge");
            if (e.status() == SH_ERR_SOLVER)
                return fail(e.status(), "the sparse factorisation or solve failed (matrix not positive definite, "
                                        "or a non-finite value)");
            restore_start_state(body);  // anything else (capacity, internal) goes up unchanged
            state.factor_valid = false;
            throw;
        } catch (...) {  // out of memory: nothing half done stays behind
            restore_start_state(body);
            state.factor_valid = false;
            throw;
        }
        double largest_change = 0.0, largest_speed = 0.0;
        for (int32_t d = 0; d < dofs; ++d) {
            double& v = body.v[static_cast<size_t>(global[static_cast<size_t>(d)])];
            state.previous_v[static_cast<size_t>(d)] = v;
            v += state.delta[static_cast<size_t>(d)];
            largest_change = std::max(largest_change, std::fabs(state.delta[static_cast<size_t>(d)]));
            largest_speed = std::max(largest_speed, std::fabs(v));
        }
        const double r_new = residual_norm(), r_new_max = largest_residual;
        if (!fresh) {
            ++stale_solves;
            used_stale = true;
            const double floor = state.roundoff_floor;  // nothing to gain below it
            if (!(r_new <= std::max(kStaleContraction * r, floor) &&
                  r_new_max <= std::max(kStaleContraction * r_max, floor))) {
                // The kept factorisation is too far from the current tangent: take the update
                // back and solve again with a new one here.
                for (int32_t d = 0; d < dofs; ++d)
                    body.v[static_cast<size_t>(global[static_cast<size_t>(d)])] = state.previous_v[static_cast<size_t>(d)];
                r = residual_norm();
                r_max = largest_residual;
                factor_current = false;
                continue;
            }
        }
        const bool was_fresh = fresh;
        r = r_new;
        r_max = r_new_max;
        fresh = false;
        factor_current = reuse && allow_stale;  // exact Newton (or CG): a tangent per iterate
        ++result.newton_iterations;
        result.newton_residual = residual0 > 0.0 ? r / residual0 : 0.0;
        if (linearised) {
            // One update with the tangent at its iterate is the linearised step; updates with a
            // kept factorisation go on until they are at least as good as factor_reuse asks.
            const double floor = state.roundoff_floor;
            if (was_fresh || (r <= std::max(target, floor) && r_max <= std::max(target_max, floor))) converged = true;
            continue;
        }
        ++iteration;
        // Near equilibrium of a stiff body the residual is cancellation noise of large element
        // forces, so a negligible velocity correction also ends the iteration.
        const double speed_scale = std::max({largest_speed, dt * gravity_norm, kSpeedFloor});
        if (iteration > 1 && largest_change <= s.newton_tolerance * speed_scale) converged = true;
    }
    end_kinematic_motion(body);
    if (!converged) return fail(SH_ERR_NOT_CONVERGED, "Newton iterations did not reach newton_tolerance");
    if (!body_state_is_sane(body))
        return fail(SH_ERR_UNSTABLE, kRolledBackReason);
    return result;
}

}  // namespace

BodyStepResult step_implicit(Body& body, ImplicitState& state, double dt, const double g[3]) {
    bool used_stale = false;
    BodyStepResult result = attempt_step(body, state, dt, g, true, used_stale);
    if (result.stable || !used_stale) return result;
    // A kept factorisation took this step somewhere bad: the step again, a factorisation at
    // every iterate (the body is back at its start state).
    const BodyStepResult first = result;
    result = attempt_step(body, state, dt, g, false, used_stale);
    result.newton_iterations += first.newton_iterations;
    result.linear_iterations += first.linear_iterations;
    result.factorize_seconds += first.factorize_seconds;
    result.solve_seconds += first.solve_seconds;
    result.factorizations += first.factorizations;
    return result;
}

}  // namespace sh
