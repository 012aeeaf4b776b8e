#include "solver/implicit_integrator.hpp"

#include "core/error.hpp"
#include "model/external_field.hpp"
#include "solver/newton_group.hpp"
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

// Halvings of an update of bodies solved together before it is taken anyway.
constexpr int kMaxHalvings = 20;

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

LinearSolverPtr make_analysed_solver(const SparseSystem& system, const sh_implicit_settings& s) {
    LinearSolverPtr solver = make_linear_solver(solver_kind(s.linear_solver), s.cg_tolerance, s.cg_max_iterations);
    solver->analyze(system);
    return solver;
}

int32_t prepare_implicit_state(const Body& body, ImplicitState& state, const sh_implicit_settings& s, bool own_solver) {
    const int32_t n = body.node_count();
    bool changed = state.free_count < 0;
    int32_t free_count = 0;
    if (!changed)
        for (int32_t i = 0; i < n && !changed; ++i) changed = (state.free_index[static_cast<size_t>(i)] >= 0) != body.is_free(i);
    if (!changed) {
        if (own_solver && !state.solver) state.solver = make_analysed_solver(state.system, s);
        return 3 * state.free_count;
    }

    vec<int32_t> free_index(static_cast<size_t>(n), -1);
    for (int32_t i = 0; i < n; ++i)
        if (body.is_free(i)) free_index[static_cast<size_t>(i)] = free_count++;
    SparseSystem system;
    system.build_pattern(body.element_nodes(), static_cast<size_t>(body.element_count()), body.nodes_per_element(),
                         free_index.data(), n, free_count);
    LinearSolverPtr solver = own_solver ? make_analysed_solver(system, s) : nullptr;
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

double assemble_body_tangent(const Body& body, ImplicitState& state, double stiffness_scale, double damping_scale,
                             const double* v, const double* diagonal, double roundoff_scale) {
    state.system.clear_values();
    body.add_tangent(body.x.data(), stiffness_scale, damping_scale, state.system);
    if (body.field)
        body.field->add_tangent(body.x.data(), v, stiffness_scale, damping_scale, state.free_index.data(), state.system);
    const double roundoff = force_roundoff(state.system, body.x, roundoff_scale);
    if (diagonal) state.system.add_diagonal(diagonal, 1.0);
    return roundoff;
}

namespace {

// Per free DOF of body: m (1 + dt (alpha + c_node)), the mass part of the step's matrix.
void fill_mass_diagonal(const Body& body, ImplicitState& state, double dt) {
    const vec<int32_t>& global = state.system.dof_to_global();
    const bool per_node = !body.node_damping.empty();
    for (size_t d = 0; d < global.size(); ++d) {
        const size_t node = static_cast<size_t>(global[d]) / 3;
        const double c = body.settings.damping_mass + (per_node ? body.node_damping[node] : 0.0);
        state.diagonal[d] = body.mass[node] * (1.0 + dt * c);
    }
}

// One attempt at the step; allow_stale: updates may use a kept factorisation. used_stale
// tells whether any did.
BodyStepResult attempt_step(const NewtonGroup& group, const sh_implicit_settings& s, double dt, const double g[3],
                            bool allow_stale, bool& used_stale) {
    BodyStepResult result;
    result.dt_critical = INFINITY;
    NewtonSystem& ns = group.newton;

    group.each([&](Body& body, ImplicitState&, size_t) {
        save_start_state(body);
        begin_kinematic_motion(body, dt);
    });
    const bool reuse = s.factor_reuse > 0.0 && ns.solver->is_direct();  // keep factorisations
    const uint64_t matrix_version = group.matrix_version();
    bool factor_current = reuse && allow_stale && ns.factor_valid && ns.factor_dt == dt &&
                          ns.factor_matrix_version == matrix_version;

    double applied_load = 0.0;  // |f_ext + m g| over the free DOFs (N)
    group.each([&](Body& body, ImplicitState& state, size_t) {
        for (const int32_t j : state.system.dof_to_global()) {
            const double load = body.applied_load(static_cast<size_t>(j), g);
            applied_load += load * load;
        }
    });
    applied_load = std::sqrt(applied_load);
    const double gravity_norm = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);

    // Newton on g(v) = M (v - v0) - dt F(x0 + dt v, v) over the free DOFs, from v = v0.
    double largest_residual = 0.0;  // max norm of the last residual_norm()
    auto residual_norm = [&] {
        // Every body moves first: the forces between bodies solved together see both ends.
        group.each([&](Body& body, ImplicitState&, size_t) {
            for (size_t j = 0; j < body.x.size(); ++j) body.x[j] = body.workspace.x0[j] + dt * body.v[j];
        });
        largest_residual = 0.0;
        group.each([&](Body& body, ImplicitState& state, size_t offset) {
            double* a = body.workspace.a[0].data();
            compute_accelerations(body, body.x.data(), body.v.data(), g, a);
            const vec<int32_t>& global = state.system.dof_to_global();
            for (size_t d = 0; d < global.size(); ++d) {
                const size_t j = static_cast<size_t>(global[d]);
                const double r_d = body.mass[j / 3] * (body.v[j] - body.workspace.v0[j] - dt * a[j]);
                ns.residual[offset + d] = r_d;
                largest_residual = std::max(largest_residual, std::fabs(r_d));
            }
        });
        return norm(ns.residual);
    };
    auto restore = [&] {
        group.each([](Body& body, ImplicitState&, size_t) { restore_start_state(body); });
        ns.factor_valid = false;  // built at an iterate that went wrong
    };
    auto fail = [&](sh_status status, const char* reason) {
        restore();
        result.stable = false;
        result.status = status;
        result.reason = reason;
        return result;
    };
    // m (1 + dt c) + dt D + dt^2 K of one body into its own system; its force round-off.
    auto assemble_member = [&](Body& body, ImplicitState& state) {
        fill_mass_diagonal(body, state, dt);
        return assemble_body_tangent(body, state, dt * dt, dt, body.v.data(), state.diagonal.data(), 1.0 / dt);
    };

    // The incremental potential whose minimum the step is, at the bodies' current v (and x):
    // 1/2 (v - v0)^T M (v - v0) + dt/2 v^T C v (mass and node damping) + elastic and field
    // energy at x - dt v^T (f_ext + m g), over the free DOFs. Its gradient is the residual but
    // for the internal, contact and friction damping, which have no potential.
    auto step_potential = [&] {
        double total = 0.0;
        group.each([&](const Body& body, const ImplicitState& state, size_t) {
            const vec<int32_t>& global = state.system.dof_to_global();
            const bool per_node = !body.node_damping.empty();
            for (size_t d = 0; d < global.size(); ++d) {
                const size_t j = static_cast<size_t>(global[d]), node = j / 3;
                const double m = body.mass[node], dv = body.v[j] - body.workspace.v0[j];
                const double c = body.settings.damping_mass + (per_node ? body.node_damping[node] : 0.0);
                total += 0.5 * m * dv * dv + 0.5 * dt * m * c * body.v[j] * body.v[j] - dt * body.v[j] * body.applied_load(j, g);
            }
            total += body.elastic_energy(body.x.data()) + (body.field ? body.field->energy(body.x.data()) : 0.0);
        });
        return total;
    };

    // Contacts switch on and off within a step, which a single linearised update cannot
    // follow (it cycles between too deep and too shallow): a body in contact iterates.
    bool in_contact = false;
    group.each([&](const Body& body, const ImplicitState&, size_t) { in_contact |= body.field != nullptr; });
    const int max_iterations = std::max(in_contact ? kContactNewtonIterations : 1, s.newton_max_iterations);
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
        if (iteration > 0 && r <= std::max(s.newton_tolerance * residual0, ns.roundoff_floor)) {
            converged = true;
            break;
        }
        if (iteration == max_iterations) break;

        try {
            if (!factor_current || stale_solves == kMaxStaleSolves) {
                ns.factor_valid = false;
                ns.roundoff_floor = group.assemble(assemble_member, dt * dt, dt, false);
                ns.solver->factorize(ns.system);
                result.factorize_seconds += ns.solver->factorize_seconds;
                ++result.factorizations;
                ns.factor_valid = reuse;
                ns.factor_dt = dt;
                ns.factor_matrix_version = matrix_version;
                factor_current = true;
                fresh = true;
                stale_solves = 0;
            }
            for (double& r_d : ns.residual) r_d = -r_d;
            result.linear_iterations += ns.solver->solve(ns.system, ns.residual.data(), ns.delta.data());
            result.solve_seconds += ns.solver->solve_seconds;
        } catch (const Error& e) {
            if (e.status() == SH_ERR_NOT_CONVERGED) return fail(e.status(), "the linear solver did not converge");
            if (e.status() == SH_ERR_SOLVER)
                return fail(e.status(), "the sparse factorisation or solve failed (matrix not positive definite, "
                                        "or a non-finite value)");
            restore();  // anything else (capacity, internal) goes up unchanged
            throw;
        } catch (...) {  // out of memory: nothing half done stays behind
            restore();
            throw;
        }
        group.each([&](Body& body, ImplicitState& state, size_t offset) {
            const vec<int32_t>& global = state.system.dof_to_global();
            for (size_t d = 0; d < global.size(); ++d) ns.previous_v[offset + d] = body.v[static_cast<size_t>(global[d])];
        });
        double largest_change = 0.0, largest_speed = 0.0;
        // v = previous_v + scale delta.
        auto take_update = [&](double scale) {
            largest_change = largest_speed = 0.0;
            group.each([&](Body& body, ImplicitState& state, size_t offset) {
                const vec<int32_t>& global = state.system.dof_to_global();
                for (size_t d = 0; d < global.size(); ++d) {
                    double& v = body.v[static_cast<size_t>(global[d])];
                    v = ns.previous_v[offset + d] + scale * ns.delta[offset + d];
                    largest_change = std::max(largest_change, std::fabs(scale * ns.delta[offset + d]));
                    largest_speed = std::max(largest_speed, std::fabs(v));
                }
            });
        };
        // Bodies solved together: the update backtracks until the incremental potential falls
        // (Armijo) or the residual does. Contacts that switch within an update make the
        // residual a poor guide on its own (two-sided contact between soft bodies has contacts
        // resting at zero depth), the potential is not.
        const bool search = group.coupled && fresh;
        double potential0 = 0.0, slope = 0.0;  // at the iterate, and along delta
        if (search) {
            potential0 = step_potential();
            for (size_t d = 0; d < ns.delta.size(); ++d) slope += ns.residual[d] * ns.delta[d];  // residual holds -g
            slope = -slope;
        }
        double scale = 1.0;
        take_update(scale);
        double r_new = residual_norm(), r_new_max = largest_residual;
        for (int halving = 0; search && halving < kMaxHalvings; ++halving) {
            if (r_new < r || step_potential() <= potential0 + 1e-4 * scale * slope) break;
            scale *= 0.5;
            take_update(scale);
            r_new = residual_norm();
            r_new_max = largest_residual;
        }
        if (!fresh) {
            ++stale_solves;
            used_stale = true;
            const double floor = ns.roundoff_floor;  // nothing to gain below it
            if (!(r_new <= std::max(kStaleContraction * r, floor) &&
                  r_new_max <= std::max(kStaleContraction * r_max, floor))) {
                // The kept factorisation is too far from the current tangent: take the update
                // back and solve again with a new one here.
                take_update(0.0);
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
            const double floor = ns.roundoff_floor;
            if (was_fresh || (r <= std::max(target, floor) && r_max <= std::max(target_max, floor))) converged = true;
            continue;
        }
        ++iteration;
        // Near equilibrium of a stiff body the residual is cancellation noise of large element
        // forces, so a negligible velocity correction (a whole one) also ends the iteration.
        const double speed_scale = std::max({largest_speed, dt * gravity_norm, kSpeedFloor});
        if (iteration > 1 && scale == 1.0 && largest_change <= s.newton_tolerance * speed_scale) converged = true;
    }
    bool sane = true;
    group.each([&](Body& body, ImplicitState&, size_t) {
        end_kinematic_motion(body);
        sane = sane && body_state_is_sane(body);
    });
    if (!converged) return fail(SH_ERR_NOT_CONVERGED, "Newton iterations did not reach newton_tolerance");
    if (!sane) return fail(SH_ERR_UNSTABLE, kRolledBackReason);
    return result;
}

// The step, retried with a factorisation at every iterate if a kept one took it somewhere bad.
BodyStepResult run_step(const NewtonGroup& group, const sh_implicit_settings& s, double dt, const double g[3]) {
    bool used_stale = false;
    BodyStepResult result = attempt_step(group, s, dt, g, true, used_stale);
    if (result.stable || !used_stale) return result;
    // The bodies are back at their start state.
    const BodyStepResult first = result;
    result = attempt_step(group, s, dt, g, false, used_stale);
    result.newton_iterations += first.newton_iterations;
    result.linear_iterations += first.linear_iterations;
    result.factorize_seconds += first.factorize_seconds;
    result.solve_seconds += first.solve_seconds;
    result.factorizations += first.factorizations;
    return result;
}

}  // namespace

BodyStepResult step_implicit(Body& body, ImplicitState& state, double dt, const double g[3]) {
    prepare_implicit_state(body, state, body.settings.implicit);
    return run_step(NewtonGroup::alone(body, state), body.settings.implicit, dt, g);
}

BodyStepResult step_implicit_coupled(CoupledSystem& system, double dt, const double g[3]) {
    sh_implicit_settings s = system.member(0).body->settings.implicit;
    for (int32_t m = 1; m < system.member_count(); ++m) {
        const sh_implicit_settings& other = system.member(m).body->settings.implicit;
        s.newton_tolerance = std::min(s.newton_tolerance, other.newton_tolerance);
        s.newton_max_iterations = std::max(s.newton_max_iterations, other.newton_max_iterations);
    }
    return run_step(NewtonGroup::together(system), s, dt, g);
}

}  // namespace sh
