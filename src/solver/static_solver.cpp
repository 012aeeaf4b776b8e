#include "solver/static_solver.hpp"

#include "core/error.hpp"
#include "model/external_field.hpp"
#include "solver/newton_problem.hpp"
#include "solver/step_support.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// True if body has a fixed or prescribed node.
bool is_anchored(const Body& body) {
    for (const uint8_t k : body.kinematic)
        if (k) return true;
    return false;
}

// A body without fixed nodes, held by its contacts with others, gets the diagonal of its
// elastic tangent times this fraction times the relative residual (at most 1) added to its
// tangent, a pseudo-transient continuation: the matrix stays positive definite along what
// nothing holds (contacts not acting yet, sliding along frictionless contact); a step there is
// at most the body's elastic deflection under the residual over the shift, which the line
// search (30 halvings) can bring back even against contacts far stiffer than the body; and as
// the residual falls the shift fades and Newton's convergence returns. On a cube resting on a
// smaller block (as in tests/test_body_pairs.c), 1e-4 to 1e-2 took 8 to 10 iterations from a
// gap, a touch or an overlap; 1e-6 could not leave a start touching at zero depth, 1e-1 took
// 24 to 29.
constexpr double kFloatingShift = 1e-3;

// K of a body at rest into its own matrix, with the shift above if the body has no fixed node;
// its force round-off.
double assemble_static_tangent(Body& body, NewtonBodyState& state, double shift) {
    const bool floating = !is_anchored(body);
    if (floating) {  // the shift scales with the body's own stiffness, not its contacts'
        SparseSystem& k = state.matrix.system;
        k.clear_values();
        body.add_tangent(body.x.data(), 1.0, 0.0, k);
        for (int32_t d = 0; d < k.dof_count(); ++d)
            state.diagonal[static_cast<size_t>(d)] = shift * k.values()[static_cast<size_t>(k.diagonal_slot(d))];
    }
    return state.assemble_tangent(body, body.x.data(), 1.0, 0.0, nullptr, floating ? state.diagonal.data() : nullptr, 1.0);
}

// Out-of-balance force f(x) + load_factor * (f_ext + m g) on the free DOFs into out, and its
// norm. Each body's workspace.stage_a[0] is scratch.
double out_of_balance(const NewtonProblem& problem, const double g[3], double load_factor, vec<double>& out) {
    problem.each([&](SteppedBody& stepped, size_t offset) {
        Body& body = *stepped.body;
        vec<double>& force = stepped.workspace.stage_a[0];
        std::fill(force.begin(), force.end(), 0.0);
        body.add_internal_forces(body.x.data(), nullptr, force.data());
        if (body.field) body.field->add_forces(body.x.data(), nullptr, force.data());
        const vec<int32_t>& global = stepped.newton->matrix.system.dof_to_global();
        for (size_t d = 0; d < global.size(); ++d) {
            const size_t j = static_cast<size_t>(global[d]);
            out[offset + d] = force[j] + load_factor * body.applied_load(j, g);
        }
    });
    double s = 0.0;
    for (const double f : out) s += f * f;
    return std::sqrt(s);
}

// Moves the problem's bodies to their saved positions (workspace.xs) plus alpha times the
// step (matrix.delta).
void place_along_step(NewtonProblem& problem, double alpha) {
    const vec<double>& step = problem.matrix().delta;
    problem.each([&](SteppedBody& stepped, size_t offset) {
        Body& body = *stepped.body;
        const vec<int32_t>& global = stepped.newton->matrix.system.dof_to_global();
        for (size_t d = 0; d < global.size(); ++d) {
            const size_t j = static_cast<size_t>(global[d]);
            body.x[j] = stepped.workspace.xs[j] + alpha * step[offset + d];
        }
    });
}

// The potential's slope along the step at the current residual (matrix.residual).
double slope_along_step(const NewtonMatrix& matrix) {
    double slope = 0.0;
    for (size_t d = 0; d < matrix.residual.size(); ++d) slope -= matrix.residual[d] * matrix.delta[d];
    return slope;
}

// Line search along the solved step (matrix.delta) from the bodies' positions, residual
// matrix.residual and relative residual r: halves from the full step until Armijo's decrease
// (or a smaller residual where the potential is flat to its round-off; never an iterate
// that raises the potential: a smaller residual there can lead the iteration round in a
// cycle over a kink of the contact potential), then moves a full step towards the
// potential's minimum along it where it ends far from it (move_update_towards_line_minimum).
// Leaves the bodies there (or where they were if nothing helps) and returns the relative
// residual.
double search_along_step(NewtonProblem& problem, const double g[3], double factor, double load_norm, double r) {
    NewtonMatrix& matrix = problem.matrix();
    const double slope = slope_along_step(matrix);  // d potential / d alpha at alpha = 0
    double scale = 0.0;
    const double energy0 = problem.potential_energy(g, factor, false, scale), r0 = r;
    problem.each([](SteppedBody& stepped, size_t) {
        std::copy(stepped.body->x.begin(), stepped.body->x.end(), stepped.workspace.xs.begin());
    });
    double alpha = 1.0, energy = energy0;
    bool accepted = false;
    for (int trial = 0; trial < 30 && !accepted; ++trial, alpha *= 0.5) {
        place_along_step(problem, alpha);
        r = out_of_balance(problem, g, factor, matrix.residual) / load_norm;
        energy = problem.potential_energy(g, factor, false, scale);
        accepted = std::isfinite(energy) && (energy <= energy0 + 1e-4 * alpha * slope ||
                                             (r < r0 && energy <= energy0 + sum_roundoff(scale)));
    }
    if (!accepted) {  // no step helped: stay where the iteration was
        place_along_step(problem, 0.0);
        return out_of_balance(problem, g, factor, matrix.residual) / load_norm;
    }
    if (2.0 * alpha < 1.0) return r;  // the accepted step (alpha is the one after it) was halved
    move_update_towards_line_minimum(
        slope, energy, sum_roundoff(scale), [&] { return slope_along_step(matrix); },
        [&](double s) {
            place_along_step(problem, s);
            r = out_of_balance(problem, g, factor, matrix.residual) / load_norm;
            return problem.potential_energy(g, factor, false, scale);
        });
    return r;
}

// Newton-Raphson with line search for the problem's bodies, their states prepared.
void solve_problem(NewtonProblem& problem, const double g[3], const sh_static_def& def, sh_static_report& report) {
    NewtonMatrix& matrix = problem.matrix();
    problem.each([](SteppedBody& stepped, size_t) {
        Body& body = *stepped.body;
        end_kinematic_motion(body);  // fixed and prescribed nodes on their targets
        std::fill(body.v.begin(), body.v.end(), 0.0);
    });
    if (matrix.system.dof_count() == 0) return;

    vec<double>& residual = matrix.residual;
    vec<double>& step = matrix.delta;
    // Scale of the residual: the full applied load, or 1 N if nothing is applied.
    double load_norm = problem.applied_load_norm(g);
    if (!(load_norm > 0.0)) load_norm = 1.0;

    for (int32_t load_step = 1; load_step <= def.load_steps; ++load_step) {
        const double factor = static_cast<double>(load_step) / def.load_steps;
        double r = out_of_balance(problem, g, factor, residual) / load_norm;
        bool converged = r <= def.tolerance;
        double floor = 0.0;
        for (int32_t iteration = 0; iteration < def.max_iterations && !converged; ++iteration) {
            const auto assemble_body = [&](SteppedBody& stepped) {
                return assemble_static_tangent(*stepped.body, *stepped.newton, kFloatingShift * std::min(r, 1.0));
            };
            // Below the round-off of the internal forces the residual cannot fall further.
            floor = std::max(floor, problem.assemble(assemble_body, 1.0, 0.0, true) / load_norm);
            matrix.solver->factorize(matrix.system);
            matrix.solver->solve(matrix.system, residual.data(), step.data());
            r = search_along_step(problem, g, factor, load_norm, r);
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

// The linear solver of a static solve.
sh_implicit_settings static_solver_settings(const sh_static_def& def) {
    sh_implicit_settings solver{};
    solver.linear_solver = def.linear_solver;
    solver.cg_tolerance = std::max(1e-3 * def.tolerance, 1e-15);  // well below the Newton tolerance
    solver.cg_max_iterations = 20000;
    return solver;
}

}  // namespace

void solve_static_body(SteppedBody& stepped, const double g[3], const sh_static_def& def, sh_static_report& report) {
    require(is_anchored(*stepped.body), SH_ERR_SOLVER,
            "a body has no fixed or prescribed node: it can float freely, so its stiffness is singular and it has "
            "no static equilibrium (fix or prescribe nodes first)");
    NewtonBodyState state;
    NewtonBodyState* states[1] = {&state};
    SteppedBody* const bodies[1] = {&stepped};
    const SwappedNewtonStates lent(bodies, states, 1);
    state.prepare(*stepped.body, static_solver_settings(def));
    NewtonProblem alone(stepped);
    solve_problem(alone, g, def, report);
}

void solve_static_coupled(NewtonProblem& problem, SteppedBody* const* bodies, int32_t count, const double g[3],
                          const sh_static_def& def, sh_static_report& report) {
    bool anchored = false;
    for (int32_t m = 0; m < count; ++m) anchored |= is_anchored(*bodies[m]->body);
    require(anchored, SH_ERR_SOLVER,
            "bodies in contact with each other have no fixed or prescribed node among them: they can float "
            "freely, so their stiffness is singular and they have no static equilibrium (fix or prescribe nodes "
            "of one of them first)");
    vec<NewtonBodyState> fresh(static_cast<size_t>(count));  // as for a body alone
    vec<NewtonBodyState*> states;
    for (NewtonBodyState& state : fresh) states.push_back(&state);
    const SwappedNewtonStates lent(bodies, states.data(), count);
    problem.prepare(bodies, count, static_solver_settings(def));
    solve_problem(problem, g, def, report);
}

}  // namespace sh
