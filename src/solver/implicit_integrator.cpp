#include "solver/implicit_integrator.hpp"

#include "core/error.hpp"
#include "model/external_field.hpp"
#include "linalg/preconditioned_cg.hpp"
#include "solver/newton_problem.hpp"
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

// When an update solved with the kept factorisation fails, the step either factorises the
// tangent afresh or, where that costs more per step (krylov_pays), solves its later updates by
// conjugate gradients on the current tangent preconditioned by the kept factorisation, to a
// relative residual of kKrylovForcing times factor_reuse (an inexact Newton update, more
// accurate than the kept factorisation's accepted updates), spending at most kKrylovBudget of
// the kept factorisation's work before it gives up and factorises afresh. A new factorisation
// costs its assembly and factorisation once and then serves as many steps as its updates last
// (kKeepLife weighs their mean over the factorisations before); CG costs an assembly and a few
// preconditioner solves per step, for at most a factorisation's price on one kept
// factorisation. Under large rotation the tangent drifts away from a new factorisation within
// a step or two, and a factorisation costs as much as 20-26 solves (20 k tets); where the
// motion is slow one serves many steps without an assembly. Costs are work estimated from
// counts (KeptFactorisation), not measured times, so that identical runs take identical
// paths. Not in contact: contacts switch within a step, where Newton with factorisations at
// its iterates converges in fewer iterations (a cube on a 1e9 N/m plane did not converge in
// 20 iterations with CG updates).
// For a body solved alone with at least this many free DOFs and no contact candidates, CG's
// preconditioner is the warped multigrid (linalg/warped_multigrid.hpp) rather than the kept
// factorisation wherever krylov_pays finds it cheaper per step than new factorisations: under
// large rotation a factorisation (20-26 solves at 20 k tets) goes stale within a step or two,
// where 5-7 multigrid iterations cost about one solve and never go stale. Once chosen, steps
// start with it; once a solve fails to cut the residual by factor_reuse within
// kMultigridBudget factorisations' work, the body factorises and the multigrid sits out a
// pause of steps (NewtonMatrix::multigrid_pause) before krylov_pays may weigh it again. Smaller
// bodies factorise in a few ms and keep the direct path.
constexpr int32_t kMultigridMinDofs = 9000;
// The multigrid built for one step size serves steps within this fraction of it (it only
// preconditions; a host alternating 1/60 and 1/61 s would rebuild it every step).
constexpr double kMultigridStepTolerance = 0.25;
// A multigrid solve may cost up to this many factorisations before the body gives it up: where
// new factorisations go stale within a step (the raptor's corotational swing refactorises 23-30
// times in 30 steps, a few steps many times), one step's factorisation and the solves after it
// cost about that much (the raptor's solves need 27-30 iterations).
constexpr double kMultigridBudget = 2.0;
// And at most this many iterations: the bound of a real-time step. Where the multigrid serves
// poorly (the raptor's tail and legs whipping round), CG contracts the residual by about 0.93
// per iteration, so that iterations 30-50 take it from about 0.1 to the tolerance's 0.025 at
// 0.4-0.5 ms each: over 100 steps, 7-9 solves end at this cap with relative residuals of
// 0.025-0.15 (taken, see solve_by_multigrid), and the swing's p99 falls from 26-36 ms to 24-26.
constexpr int kMultigridMaxIterations = 30;
// The most steps the multigrid sits out after a solve it could not bring to a usable residual
// (the pause doubles with each such failure in a row, from 1).
constexpr int kMaxMultigridPause = 64;
// Nodes that turn by less than this (rad) per update for NewtonMatrix::multigrid_calm_needed
// multigrid updates in a row (10 at first) have settled: the body goes back to factorisations,
// which then last many steps with one solve each, where the multigrid keeps costing an assembly
// and 5-6 iterations. Where the new factorisation goes stale sooner than that count anyway (a
// slow swing), the count doubles, up to kMaxCalmSteps: such probes cost a factorisation each.
constexpr double kCalmTurn = 0.005;
constexpr int kMaxCalmSteps = 640;
// Only where the assembly and factorisation that leaving costs come to at most this many
// multigrid steps' work: that step is a spike of its size in a real-time loop, which at 20 k
// tets (a factorisation of about eight multigrid steps: 70 ms against 8.5 in the standing
// cube at 60 Hz) misses every deadline. Such a body stays on the multigrid.
constexpr double kMaxCalmExitSpike = 3.0;
constexpr double kKrylovForcing = 0.1;
constexpr double kKrylovBudget = 0.5;
constexpr int kKrylovMinIterations = 2, kKrylovMaxIterations = 50;
constexpr double kKeepLife = 0.5;

// Newton iterations allowed to a body with contact candidates, whatever its settings.
constexpr int kContactNewtonIterations = 20;

// Halvings of a Newton update in the line search before the loop counts as stalled, and
// Armijo's sufficient-decrease fraction.
constexpr int kMaxHalvings = 30;
constexpr double kArmijo = 1e-4;

// A Newton direction that cannot lower the potential from an iterate whose residual is within
// this factor of the forces' estimated round-off counts as converged: the estimate is an order
// of magnitude, and the residual there is noise rather than a gradient to follow.
constexpr double kStalledRoundoffFactor = 8.0;

// Along an update whose predicted decrease of Phi is below Phi's round-off estimate, Phi cannot
// judge it (a stiff body at rest: the update removes a residual of cancellation noise plus a
// slow creep, and changes Phi by 1e-19 J): the update is kept if it halves the residual and Phi
// rises by at most this many times the estimate, which is an order of magnitude.
constexpr double kBlindRoundoffFactor = 16.0;

// The runaway guard's bound: a step with no outside work may not raise the bodies' mechanical
// energy by more than this times the magnitude of its terms at the start.
constexpr double kEnergyGrowth = 1.0;

// A linearised step with no outside work that raises the mechanical energy by more than this
// times its terms' magnitude is not accepted: it goes on iterating towards the minimiser.
// Stricter than the runaway guard, which an iterate it accepted therefore passes too.
constexpr double kLinearisedEnergyGain = 1e-6;
static_assert(kLinearisedEnergyGain <= kEnergyGrowth, "an accepted linearised update must pass the runaway guard");

// Per free DOF of body: m (1 + dt (alpha + c_node)), the mass part of the step's matrix.
void fill_mass_diagonal(const Body& body, NewtonBodyState& state, double dt) {
    const vec<int32_t>& global = state.matrix.system.dof_to_global();
    for (size_t d = 0; d < global.size(); ++d) {
        const size_t node = static_cast<size_t>(global[d]) / 3;
        state.diagonal[d] = body.mass[node] * (1.0 + dt * body.mass_damping(node));
    }
}

// The step's incremental potential at one iterate, and the terms it was summed from.
struct Potential {
    double value = 0.0;  ///< J
    double scale = 0.0;  ///< sum of the terms' magnitudes: the round-off of value is eps times it
    /// Both value and scale are finite.
    bool finite() const { return std::isfinite(value) && std::isfinite(scale); }
};

// One body's part of the residual's norms and of Phi (body_residual).
struct ResidualSums {
    double sum2 = 0.0;  ///< sum of the residual's squares
    double max = 0.0;   ///< its largest magnitude
    Potential phi;      ///< the kinetic, mass-damping, lagged internal damping and load terms
};

// Per free DOF d of stepped's body: the residual m (v - v0) + h m c v - h (f + f_d + f_ext + m g)
// into residual[d] (damping: the lagged internal damping force f_d, or null), and its sums.
// In the nodes' order: the free order (solver/free_node_order.hpp) would scatter the reads of
// every node array; only the residual's writes jump. The sums are local, where sums kept
// through the caller's members would be stored and reloaded at every DOF (the residual's writes
// might alias them).
ResidualSums body_residual(const SteppedBody& stepped, const double* f, const double* damping, const double g[3],
                           double h, double* residual) {
    const Body& body = *stepped.body;
    const vec<int32_t>& free_index = stepped.newton->free_index;
    const double* v0 = stepped.workspace.v0.data();
    ResidualSums sums;
    for (size_t j = 0; j < body.x.size(); ++j) {
        const size_t node = j / 3;
        if (free_index[node] < 0) continue;
        const size_t d = 3 * static_cast<size_t>(free_index[node]) + j % 3;
        const double m = body.mass[node], v = body.v[j], dv = v - v0[j];
        const double c = body.mass_damping(node);
        const double load = body.applied_load(j, g), fd = damping ? damping[j] : 0.0;
        const double r_d = m * dv + h * m * c * v - h * (f[j] + fd + load);
        residual[d] = r_d;
        sums.sum2 += r_d * r_d;
        sums.max = std::max(sums.max, std::fabs(r_d));
        const double terms[4] = {0.5 * m * dv * dv, 0.5 * h * m * c * v * v, -0.5 * h * v * fd, -h * v * load};
        for (const double t : terms) {
            sums.phi.value += t;
            sums.phi.scale += std::fabs(t);
        }
    }
    return sums;
}

// One implicit step of the bodies of a NewtonProblem as the minimisation of its incremental
// potential over the end-of-step velocities v (x = x0 + h v):
//   Phi(v) = 1/2 (v - v0)^T M (v - v0) + h/2 v^T C v + h/2 v^T D0 v + E(x) + P(x) + h W(v)
//            - h v^T (f_ext + m g)
// C: mass and node damping; D0: the bodies' internal damping at the step's start (lagged, so
// that it has a potential); E: elastic energy; P: the contact potential of the step's law
// (its damping is in the depth, see hunt_crossley_step_law); W: friction's dissipation
// potential with the normal force lagged. Every force of the step is minus the gradient of a
// term, so the residual g(v) = M (v - v0) - h F is grad Phi, and projected Newton (the PSD
// tangent M + h D + h^2 K) with a backtracking line search never accepts an iterate that
// raises Phi. Its minimum is the backward Euler step.
class NewtonStep {
public:
    /// The step of problem's bodies by dt under gravity g with settings s; allow_stale: it may
    /// solve with a factorisation kept from earlier iterations or steps.
    NewtonStep(NewtonProblem& problem, const sh_implicit_settings& s, double dt, const double g[3], bool allow_stale)
        : problem_(problem), matrix_(problem.matrix()), s_(s), dt_(dt), g_(g), allow_stale_(allow_stale) {}

    /// Runs the step. keep_best: a loop that does not converge keeps its last iterate (the
    /// lowest potential found) instead of failing.
    BodyStepResult run(bool keep_best);

    bool used_stale = false;  ///< an update was solved with a kept factorisation

private:
    /// Saves the start state, starts kinematic motion, measures the start's energy and decides
    /// whether the kept factorisation serves this step.
    void begin();
    /// Diagonal of the bodies' bounding box at the current iterate (m).
    double extent() const;
    /// Moves the bodies to the current velocities' positions; residual, its norms and Phi there.
    void evaluate();
    /// One body's m (1 + dt c) + dt D + dt^2 K at positions x into its own matrix; its force
    /// round-off.
    double assemble_body(Body& body, NewtonBodyState& state, const double* x);
    /// Solves for the Newton update, factorising first unless a kept factorisation serves.
    bool factorize_and_solve(bool& failed);
    /// Assembles the bodies' tangent at the current iterate into matrix_.system.
    void assemble_tangent();
    /// The update by conjugate gradients on the current tangent preconditioned by the kept
    /// factorisation (see kKrylovForcing); false if they did not converge within budget.
    bool solve_by_krylov();
    /// After an update solved with the kept factorisation failed: true if CG preconditioned by
    /// it costs less per step than new factorisations do, as long as they last.
    bool krylov_pays();
    /// CG failed this step: no more of it; the next update comes with a new factorisation.
    void give_up_krylov();
    /// True if the warped multigrid serves this step (kMultigridMinDofs), built first if the
    /// step size or the matrix version changed.
    bool use_multigrid();
    /// Builds matrix_.multigrid from the step's matrix at the rest shape; false if it failed.
    bool build_multigrid();
    /// The multigrid does not serve this body until its matrix version or step size changes.
    void drop_multigrid();
    /// The update by CG preconditioned by the multigrid on the assembled tangent; false (out of
    /// multigrid mode) if it did not reach a usable residual within its cap (two
    /// factorisations' work, at most kMultigridMaxIterations).
    bool solve_by_multigrid();
    /// After a multigrid update: leaves multigrid mode once the nodes have turned by less than
    /// kCalmTurn per update for multigrid_calm_needed updates (a new factorisation would then
    /// last).
    void note_multigrid_motion(double turn);
    /// One CG iteration's work: a solve with the kept factorisation and a product with the
    /// tangent (4 operations per stored entry of its upper triangle).
    double cg_iteration_work() const;
    /// Returns solve(-g, delta), which solves for the update into matrix_.delta, with -g laid
    /// in matrix_.residual for the call (and g back after it).
    template <class Solve>
    auto solve_for_update(Solve&& solve) {
        for (double& r_d : matrix_.residual) r_d = -r_d;
        struct Restore {  // g comes back also if the solve throws
            vec<double>& residual;
            ~Restore() {
                for (double& r_d : residual) r_d = -r_d;
            }
        } restore{matrix_.residual};
        return solve(matrix_.residual.data(), matrix_.delta.data());
    }
    /// Sets v = previous_v + scale delta and evaluates there.
    void take_update(double scale);
    /// Backtracking line search along delta; false if no step length qualifies.
    bool line_search(double slope, bool fresh);
    /// d Phi / d scale along delta at the current iterate: the residual (grad Phi) dotted with it.
    double slope_along_update() const;
    /// After a fresh full update Phi accepted: moves it towards Phi's minimum along it where it
    /// ends far from it (move_update_towards_line_minimum; roundoff: Phi's round-off along it).
    void settle_update(double slope, double roundoff);
    /// Newton iterations the step may take.
    int iteration_cap() const;
    /// The scale the residual's tolerance is relative to.
    double residual_scale() const;
    /// Copies the current free velocities into the matrix's previous_v.
    void keep_velocities();
    /// The Newton loop; true if it converged.
    bool iterate(bool& solver_failed);
    /// The step's outcome after the loop.
    BodyStepResult finish(bool converged, bool solver_failed, bool keep_best);
    /// Restores the bodies and reports status and reason.
    BodyStepResult fail(sh_status status, const char* reason);
    /// Where mechanical_energy is taken: at the step's start; at the current iterate, which
    /// the last evaluate() left and whose elastic and field energies it found; at the current
    /// positions, computed afresh (after something else moved the bodies).
    enum class EnergyAt { kStart, kLastEvaluation, kNow };
    /// Kinetic + potential energy of the bodies (J); scale, if not null, gets the terms'
    /// magnitudes (at kStart or kNow: the last evaluation keeps its energies only).
    double mechanical_energy(EnergyAt at, double* scale) const;
    /// True if the energy (at: kLastEvaluation or kNow) rose by more than fraction of its
    /// start scale with no outside work.
    bool energy_rose(double fraction, EnergyAt at) const;

    NewtonProblem& problem_;        // the bodies stepped
    NewtonMatrix& matrix_;          // problem_.matrix(): assembled, factorised and solved
    const sh_implicit_settings& s_; // tolerance, iteration cap, factor_reuse
    const double dt_;               // step size (s)
    const double* g_;               // gravity (m/s^2)
    const bool allow_stale_;        // a kept factorisation may serve
    BodyStepResult result_;         // what the step did so far
    bool reuse_ = false;           // factorisations are kept
    bool factor_current_ = false;  // matrix_ holds a factorisation usable for this step
    bool fresh_ = false;           // it is of the tangent at the current iterate
    bool krylov_ = false;          // the kept factorisation preconditions CG on the tangent
    bool krylov_update_ = false;   // the last update came from such CG (it counts as fresh_)
    bool krylov_failed_ = false;   // CG failed this step: no more of it
    bool multigrid_ = false;       // CG is preconditioned by the multigrid, not the kept factorisation
    bool multigrid_resting_ = false;  // this step is one of a pause of the multigrid's
    bool assembled_ = false;       // matrix_.system holds the tangent at the current iterate
    bool in_contact_ = false;      // a body has contact candidates (a field) this step
    uint64_t matrix_version_ = 0;  // the bodies' matrix version at the step's start
    int stale_solves_ = 0;         // solves with the current factorisation since it was made
    Potential phi_;                // at the current iterate
    double r_ = 0.0, r_max_ = 0.0; // residual norms (2 and max) at the current iterate
    double largest_change_ = 0.0, largest_speed_ = 0.0;  // of the last update taken
    double energy0_ = 0.0, energy_scale0_ = 0.0;  // mechanical energy at the start, its scale
    // The elastic and field energies at the positions the last evaluate() left.
    double evaluated_energy_ = 0.0;
    double field_push_ = 0.0;  // norm of the fields' push at the first iterate (N)
    // A contact field pushed on a body or held energy at some evaluation this step (a body
    // with contact candidates that have not touched steps as one without them).
    bool touched_ = false;
    bool first_evaluation_ = true;  // the next evaluate() is the step's first: it measures field_push_
    bool work_done_ = false;  // prescribed nodes move: they work on the bodies
    bool field_work_ = false;  // moving tools or other bodies work on the bodies once they touch
    bool energy_checked_ = false;  // the final iterate passed the linearised energy check
};

// Kinetic + potential energy (NewtonProblem::potential_energy) of the bodies, at the step's
// start (x0, v0) or now.
double NewtonStep::mechanical_energy(EnergyAt at, double* scale) const {
    const bool at_start = at == EnergyAt::kStart;
    double kinetic = 0.0;
    problem_.each([&](const SteppedBody& stepped, size_t) {
        const Body& body = *stepped.body;
        const NewtonBodyState& state = *stepped.newton;
        const double* v = at_start ? stepped.workspace.v0.data() : body.v.data();
        for (const int32_t j : state.matrix.system.dof_to_global()) {
            const size_t k = static_cast<size_t>(j);
            kinetic += 0.5 * body.mass[k / 3] * v[k] * v[k];
        }
    });
    double potential_scale = 0.0;
    const double potential =
        at == EnergyAt::kLastEvaluation
            ? problem_.potential_energy_from(g_, 1.0, evaluated_energy_)
            : problem_.potential_energy(g_, 1.0, at_start, potential_scale);
    if (scale) *scale = potential_scale + kinetic;
    return kinetic + potential;
}

// With no work done on the bodies from outside (prescribed motion, or moving tools and other
// bodies once they touch: candidates that have not touched did nothing), the minimiser of the
// step's potential does not raise their mechanical energy: true if the current iterate raised
// it by more than fraction times its start's scale (or to non-finite).
bool NewtonStep::energy_rose(double fraction, EnergyAt at) const {
    if (work_done_ || (field_work_ && touched_)) return false;
    const double energy = mechanical_energy(at, nullptr);
    return !std::isfinite(energy) || energy - energy0_ > fraction * energy_scale0_ + 1e-12;
}

// Diagonal of the bodies' bounding box at the current iterate (m).
double NewtonStep::extent() const {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    problem_.each([&](const SteppedBody& stepped, size_t) {
        const Body& body = *stepped.body;
        for (size_t j = 0; j < body.x.size(); ++j) {
            lo[j % 3] = std::min(lo[j % 3], body.x[j]);
            hi[j % 3] = std::max(hi[j % 3], body.x[j]);
        }
    });
    if (!(hi[0] >= lo[0])) return 0.0;
    const double d[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    return std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

void NewtonStep::begin() {
    work_done_ = field_work_ = false;
    krylov_ = krylov_update_ = krylov_failed_ = assembled_ = in_contact_ = touched_ = false;
    problem_.each([&](const SteppedBody& stepped, size_t) { in_contact_ |= stepped.body->field != nullptr; });
    energy_checked_ = false;
    first_evaluation_ = true;
    problem_.each([&](SteppedBody& stepped, size_t) {
        Body& body = *stepped.body;
        save_start_state(stepped);
        begin_kinematic_motion(body, dt_);
        for (size_t j = 0; j < body.v.size() && !work_done_; ++j) work_done_ = body.kinematic[j / 3] && body.v[j] != 0.0;
        field_work_ = field_work_ || (body.field && body.field->does_work());
        // The internal damping's lagged base: elastic forces at the start state.
        if (!body.has_internal_damping()) return;
        vec<double>& base = stepped.workspace.stage_a[1];
        std::fill(base.begin(), base.end(), 0.0);
        body.add_internal_forces(stepped.workspace.x0.data(), nullptr, base.data());
    });
    if (!work_done_) energy0_ = mechanical_energy(EnergyAt::kStart, &energy_scale0_);
    reuse_ = s_.factor_reuse > 0.0 && matrix_.solver->is_direct();
    matrix_version_ = problem_.matrix_version();
    factor_current_ = reuse_ && allow_stale_ && matrix_.kept.valid && matrix_.kept.dt == dt_ &&
                      matrix_.kept.matrix_version == matrix_version_;
    if (factor_current_) ++matrix_.kept.steps_served;
    multigrid_resting_ = matrix_.multigrid_pause > 0;
    if (multigrid_resting_) --matrix_.multigrid_pause;
}

bool NewtonStep::use_multigrid() {
    if (!allow_stale_ || !reuse_ || in_contact_ || problem_.body_count() != 1 ||
        matrix_.system.dof_count() < kMultigridMinDofs)
        return false;
    const bool current = std::fabs(matrix_.multigrid_dt / dt_ - 1.0) <= kMultigridStepTolerance &&
                         matrix_.multigrid_version == matrix_version_;
    if (current && (matrix_.multigrid_failed || multigrid_resting_)) return false;
    if (current && matrix_.multigrid.built_for(matrix_.system)) return true;
    return build_multigrid();
}

void NewtonStep::drop_multigrid() {
    matrix_.multigrid.clear();
    matrix_.multigrid_failed = true;
    matrix_.multigrid_mode = multigrid_ = false;
}

bool NewtonStep::build_multigrid() {
    SteppedBody& stepped = problem_.body(0);
    Body& body = *stepped.body;
    drop_multigrid();  // until the build succeeds: not tried again for this dt and version
    matrix_.multigrid_dt = dt_;
    matrix_.multigrid_version = matrix_version_;
    matrix_.multigrid_calm_steps = 0;
    matrix_.multigrid_pause = 0;
    matrix_.multigrid_pause_length = 1;
    const vec<int32_t>& global = matrix_.system.dof_to_global();
    vec<double> rest(global.size());
    for (size_t d = 0; d < global.size(); ++d) rest[d] = body.rest[static_cast<size_t>(global[d])];
    assembled_ = false;  // the matrix holds the rest shape's from here
    try {
        matrix_.rotations.reset(body, global);
        // The step's matrix at the rest shape, where every law is linear elasticity.
        assemble_body(body, *stepped.newton, body.rest.data());
        matrix_.multigrid.build(matrix_.system, rest.data());
    } catch (const Error& e) {
        matrix_.multigrid.clear();
        if (e.status() != SH_ERR_SOLVER) throw;
        return false;
    } catch (...) {
        matrix_.multigrid.clear();
        throw;
    }
    matrix_.multigrid_failed = false;
    return true;
}

// Moves every body to x = x0 + h v, then fills matrix_.residual with g(v), r_, r_max_ and phi_.
// Every body moves first: the forces between bodies solved together see both ends.
void NewtonStep::evaluate() {
    const double h = dt_;
    problem_.each([&](SteppedBody& stepped, size_t) {
        Body& body = *stepped.body;
        for (size_t j = 0; j < body.x.size(); ++j) body.x[j] = stepped.workspace.x0[j] + h * body.v[j];
    });
    Potential phi;
    double sum2 = 0.0, push2 = 0.0;
    r_max_ = 0.0;
    evaluated_energy_ = 0.0;
    problem_.each([&](SteppedBody& stepped, size_t offset) {
        Body& body = *stepped.body;
        const NewtonBodyState& state = *stepped.newton;
        double* f = stepped.workspace.stage_a[0].data();
        std::fill(f, f + body.x.size(), 0.0);
        // The field first: its push on the free DOFs, for the step's first evaluation
        // (iterate()) and until it has touched.
        double body_push2 = 0.0;
        if (body.field) {
            body.field->add_forces(body.x.data(), body.v.data(), f);
            if (first_evaluation_ || !touched_)
                for (const int32_t j : state.matrix.system.dof_to_global())
                    body_push2 += f[static_cast<size_t>(j)] * f[static_cast<size_t>(j)];
        }
        push2 += body_push2;
        const Body::ElasticEnergy elastic = body.add_elastic_forces_and_energy(body.x.data(), f);
        body.remember_elastic_energy(body.x.data(), elastic.value);
        double* damping = nullptr;  // -D0 v, the lagged internal damping force
        if (body.has_internal_damping()) {
            damping = stepped.workspace.stage_a[2].data();
            std::fill(damping, damping + body.x.size(), 0.0);
            body.add_internal_forces(stepped.workspace.x0.data(), body.v.data(), damping);
            const double* base = stepped.workspace.stage_a[1].data();
            for (size_t j = 0; j < body.x.size(); ++j) damping[j] -= base[j];
        }
        const double field_energy = body.field ? body.field->energy(body.x.data()) : 0.0;
        touched_ = touched_ || body_push2 > 0.0 || field_energy != 0.0;
        const double field = body.field ? field_energy + h * body.field->dissipation(body.v.data()) : 0.0;
        evaluated_energy_ += elastic.value + field_energy;
        phi.value += elastic.value + field;
        phi.scale += elastic.scale + std::fabs(field);  // what its round-off is relative to
        const ResidualSums sums = body_residual(stepped, f, damping, g_, h, matrix_.residual.data() + offset);
        sum2 += sums.sum2;
        r_max_ = std::max(r_max_, sums.max);
        phi.value += sums.phi.value;
        phi.scale += sums.phi.scale;
    });
    r_ = std::sqrt(sum2);
    phi_ = phi;
    if (first_evaluation_) field_push_ = std::sqrt(push2);
    first_evaluation_ = false;
}

// m (1 + dt c) + dt D + dt^2 K of one body into its own matrix; its force round-off.
double NewtonStep::assemble_body(Body& body, NewtonBodyState& state, const double* x) {
    fill_mass_diagonal(body, state, dt_);
    return state.assemble_tangent(body, x, dt_ * dt_, dt_, body.v.data(), state.diagonal.data(), 1.0 / dt_);
}

void NewtonStep::assemble_tangent() {
    matrix_.kept.roundoff_floor =
        problem_.assemble([&](SteppedBody& m) { return assemble_body(*m.body, *m.newton, m.body->x.data()); }, dt_ * dt_,
                          dt_, false);
    double work = 0.0;
    problem_.each([&](const SteppedBody& stepped, size_t) { work += stepped.body->tangent_work(); });
    matrix_.kept.assemble_work = work;
    assembled_ = true;
}

double NewtonStep::cg_iteration_work() const {
    return matrix_.kept.solve_work + 4.0 * static_cast<double>(matrix_.system.nonzero_count());
}

bool NewtonStep::krylov_pays() {
    KeptFactorisation& kept = matrix_.kept;
    if (!kept.failed) {  // its first failure: how long its updates served
        kept.failed = true;
        const double life = kept.steps_served;
        kept.mean_life = kept.mean_life < 0.0 ? life : kKeepLife * kept.mean_life + (1.0 - kKeepLife) * life;
    }
    // A factorisation's price; CG pays at most that much on one before buying a new one (so
    // that a wrong estimate of the lives costs at most a factorisation per factorisation).
    const double price = kept.assemble_work + kept.factorize_work;
    const double direct = price / std::max(kept.mean_life, 1.0);
    if (use_multigrid()) {
        const double multigrid = kept.assemble_work + matrix_.multigrid_iterations * matrix_.multigrid.iteration_work();
        multigrid_ = matrix_.multigrid_mode = multigrid < direct + kept.solve_work;
        if (multigrid_) {
            int& needed = matrix_.multigrid_calm_needed;
            if (matrix_.multigrid_left_calm && kept.mean_life < needed) needed = std::min(2 * needed, kMaxCalmSteps);
            matrix_.multigrid_left_calm = false;
            return true;
        }
    }
    const double krylov = kept.assemble_work + kept.krylov_iterations[kept.steps_served > 0] * cg_iteration_work();
    return kept.mean_life >= 0.0 && krylov < direct && kept.krylov_spent < price;
}

void NewtonStep::give_up_krylov() {
    krylov_ = multigrid_ = false;
    krylov_failed_ = true;
    factor_current_ = false;
}

bool NewtonStep::solve_by_multigrid() {
    WarpedMultigrid& multigrid = matrix_.multigrid;
    SH_REQUIRE(matrix_.rotations.size() == static_cast<size_t>(matrix_.system.dof_count() / 3), SH_ERR_INTERNAL,
               "multigrid: rotations for %zu nodes, system of %d DOFs", matrix_.rotations.size(),
               matrix_.system.dof_count());
    try {
        multigrid.prepare(matrix_.system, matrix_.rotations.update(*problem_.body(0).body));
    } catch (const Error& e) {
        if (e.status() != SH_ERR_SOLVER) throw;
        drop_multigrid();
        return false;  // a diagonal block not positive definite: the factorisation will say where
    }
    // At most as many iterations as kMultigridBudget factorisations cost, once that is known,
    // and kMultigridMaxIterations.
    const double factorisation = matrix_.kept.factorize_work;
    const int cap = factorisation > 0.0
                        ? std::clamp(static_cast<int>(kMultigridBudget * factorisation / multigrid.iteration_work()),
                                     kKrylovMinIterations, kMultigridMaxIterations)
                        : kMultigridMaxIterations;
    PreconditionedCgResult cg;
    try {
        cg = solve_for_update([&](const double* minus_g, double* delta) {
            return solve_preconditioned_cg(
                matrix_.system.dof_count(), [&](const double* x, double* y) { multigrid.multiply(x, y); },
                multigrid, minus_g, delta, true, kKrylovForcing * s_.factor_reuse, cap, matrix_.cg);
        });
    } catch (const Error& e) {
        if (e.status() != SH_ERR_SOLVER) throw;
        cg = PreconditionedCgResult{};  // a non-finite coarse solve: not usable, as below
    }
    result_.linear_iterations += cg.iterations;
    result_.solve_seconds += cg.seconds;
    used_stale = true;  // an inexact update: a failed step retries with factorisations
    double& mean = matrix_.multigrid_iterations;
    // At the cap, an update that cuts the linearised residual by factor_reuse is as good as a
    // linearised step asks (see iterate()): the line search judges it as any other. One that
    // does not (a thin body whipping round: the raptor's swing would need 40-50 iterations at
    // its fastest) is solved by a factorisation, and the multigrid sits out the next steps
    // (NewtonMatrix::multigrid_pause) before krylov_pays may weigh it again.
    const bool acceptable = cg.converged || cg.relative_residual <= s_.factor_reuse;
    mean = kKeepLife * mean + (1.0 - kKeepLife) * cg.iterations;
    int& pause = matrix_.multigrid_pause_length;
    if (!acceptable) {
        matrix_.multigrid_mode = multigrid_ = false;
        matrix_.multigrid_pause = pause;
        pause = std::min(2 * pause, kMaxMultigridPause);
        return false;
    }
    pause = 1;
    note_multigrid_motion(matrix_.rotations.last_turn());
    return true;
}

void NewtonStep::note_multigrid_motion(double turn) {
    int& calm = matrix_.multigrid_calm_steps;
    calm = turn < kCalmTurn ? calm + 1 : 0;
    if (calm < matrix_.multigrid_calm_needed) return;
    const KeptFactorisation& kept = matrix_.kept;
    const double multigrid_step = kept.assemble_work + matrix_.multigrid_iterations * matrix_.multigrid.iteration_work();
    if (kept.assemble_work + kept.factorize_work > kMaxCalmExitSpike * multigrid_step) return;
    // The next update factorises afresh, and how long that one lasts is measured anew.
    matrix_.multigrid_mode = false;
    matrix_.multigrid_left_calm = true;
    matrix_.kept.valid = false;
    matrix_.kept.mean_life = -1.0;
    calm = 0;
}

bool NewtonStep::solve_by_krylov() {
    assemble_tangent();
    if (multigrid_) return solve_by_multigrid();
    KeptFactorisation& kept = matrix_.kept;
    const double per_iteration = cg_iteration_work();
    const int cap = std::clamp(static_cast<int>(kKrylovBudget * kept.factorize_work / per_iteration),
                               kKrylovMinIterations, kKrylovMaxIterations);
    const PreconditionedCgResult cg = solve_for_update([&](const double* minus_g, double* delta) {
        return solve_preconditioned_cg(matrix_.system, *matrix_.solver, minus_g, delta, kKrylovForcing * s_.factor_reuse,
                                       cap, matrix_.cg);
    });
    result_.linear_iterations += cg.iterations;
    result_.solve_seconds += cg.seconds;
    // The iterations CG takes, a running mean over its solves with factorisations of this
    // step and of earlier ones apart (within a step the tangent moves less). Out of budget on a
    // factorisation a step old, CG cannot keep up with the tangent: that solve counts four
    // times the budget (cap solves cost half a factorisation), where CG costs more than a
    // factorisation and does not pay until solves that converged bring the mean down. On an
    // older one, age may be the cause.
    const bool outpaced = !cg.converged && kept.steps_served <= 1;
    const double iterations = outpaced ? 4.0 * cap : cg.iterations;
    double& mean = kept.krylov_iterations[kept.steps_served > 0];
    mean = kKeepLife * mean + (1.0 - kKeepLife) * iterations;
    kept.krylov_spent += kept.assemble_work + cg.iterations * per_iteration;
    used_stale = true;  // the kept factorisation steered it: a failed step retries without it
    return cg.converged;
}

// Solves the tangent system for the update delta = -H^-1 g into matrix_.delta: by CG
// preconditioned with the kept factorisation where krylov_pays chose it this step, else with a
// new factorisation at the current iterate unless a kept one may serve. False (failed set) if
// the factorisation or solve failed; throws what is not a solver failure.
bool NewtonStep::factorize_and_solve(bool& failed) {
    failed = false;
    krylov_update_ = false;
    try {
        if (krylov_ && (multigrid_ || factor_current_)) {
            if (solve_by_krylov()) {
                fresh_ = krylov_update_ = true;
                return true;
            }
            give_up_krylov();  // the tangent is assembled: factorise it below
        }
        if (!factor_current_ || stale_solves_ == kMaxStaleSolves) {
            matrix_.kept.valid = false;
            if (!assembled_) assemble_tangent();
            matrix_.solver->factorize(matrix_.system);
            matrix_.kept.factorize_work = matrix_.solver->work().factorize;
            matrix_.kept.solve_work = matrix_.solver->work().solve;
            matrix_.kept.steps_served = 0;
            matrix_.kept.failed = false;
            matrix_.kept.krylov_spent = 0.0;
            result_.factorize_seconds += matrix_.solver->factorize_seconds;
            ++result_.factorizations;
            matrix_.kept.valid = reuse_;
            matrix_.kept.dt = dt_;
            matrix_.kept.matrix_version = matrix_version_;
            factor_current_ = true;
            fresh_ = true;
            stale_solves_ = 0;
        }
        result_.linear_iterations += solve_for_update(
            [&](const double* minus_g, double* delta) { return matrix_.solver->solve(matrix_.system, minus_g, delta); });
        result_.solve_seconds += matrix_.solver->solve_seconds;
    } catch (const Error& e) {
        if (e.status() != SH_ERR_NOT_CONVERGED && e.status() != SH_ERR_SOLVER) throw;
        result_.status = e.status();
        failed = true;
    }
    return !failed;
}

// v = previous_v + scale delta, then evaluate().
void NewtonStep::take_update(double scale) {
    largest_change_ = largest_speed_ = 0.0;
    assembled_ = false;
    problem_.each([&](SteppedBody& stepped, size_t offset) {
        Body& body = *stepped.body;
        const vec<int32_t>& global = stepped.newton->matrix.system.dof_to_global();
        for (size_t d = 0; d < global.size(); ++d) {
            double& v = body.v[static_cast<size_t>(global[d])];
            v = matrix_.previous_v[offset + d] + scale * matrix_.delta[offset + d];
            largest_change_ = std::max(largest_change_, std::fabs(scale * matrix_.delta[offset + d]));
            largest_speed_ = std::max(largest_speed_, std::fabs(v));
        }
    });
    evaluate();
}

double NewtonStep::slope_along_update() const {
    double slope = 0.0;
    for (size_t d = 0; d < matrix_.delta.size(); ++d) slope += matrix_.residual[d] * matrix_.delta[d];
    return slope;
}

void NewtonStep::settle_update(double slope, double roundoff) {
    move_update_towards_line_minimum(
        slope, phi_.value, roundoff, [&] { return slope_along_update(); },
        [&](double scale) {
            take_update(scale);
            return phi_.finite() ? phi_.value : NAN;
        });
}

// Backtracks along delta from the iterate in previous_v (potential phi0 = phi_, slope
// g^T delta < 0) until Phi falls by Armijo's rule (to round-off), or, where the fall Phi should
// show is below its round-off, until the residual halves. A kept factorisation's
// update must also be full length and cut the residual by kStaleContraction. Returns false,
// back at the iterate, if no step length qualifies.
bool NewtonStep::line_search(double slope, bool fresh) {
    const Potential phi0 = phi_;
    const double r0 = r_, r0_max = r_max_;
    // Phi's round-off: of its sum, and of the forces (kept.roundoff_floor, in residual units)
    // along the update, which element energies computed from position differences carry.
    double length = 0.0;
    for (const double d : matrix_.delta) length += d * d;
    length = std::sqrt(length);
    double scale = 1.0;
    for (int halving = 0; halving <= (fresh ? kMaxHalvings : 0); ++halving, scale *= 0.5) {
        take_update(scale);
        const double roundoff = sum_roundoff(phi0.scale) + 4.0 * matrix_.kept.roundoff_floor * scale * length;
        if (!phi_.finite()) continue;
        if (fresh && -scale * slope <= roundoff && r_ <= kStaleContraction * r0 &&
            phi_.value <= phi0.value + kBlindRoundoffFactor * roundoff)
            return true;  // Phi is blind along this update: the residual judges it
        if (phi_.value > phi0.value + kArmijo * scale * slope + roundoff) continue;
        if (fresh && halving == 0) settle_update(slope, roundoff);
        if (fresh) return true;
        const double floor = matrix_.kept.roundoff_floor;
        if (r_ <= std::max(kStaleContraction * r0, floor) && r_max_ <= std::max(kStaleContraction * r0_max, floor)) return true;
    }
    take_update(0.0);
    phi_ = phi0;
    r_ = r0;
    r_max_ = r0_max;
    return false;
}

BodyStepResult NewtonStep::fail(sh_status status, const char* reason) {
    problem_.each([](SteppedBody& stepped, size_t) { restore_start_state(stepped); });
    matrix_.kept.valid = false;  // built at an iterate that went wrong
    result_.stable = false;
    result_.status = status;
    result_.reason = reason;
    return result_;
}

BodyStepResult NewtonStep::run(bool keep_best) {
    result_.dt_critical = INFINITY;
    begin();
    bool converged = false, solver_failed = false;
    try {
        // Built at the first step (beside the first factorisation and symbolic analysis), so
        // that the step that switches to it pays no more than its solve.
        const bool multigrid = use_multigrid();
        multigrid_ = krylov_ = matrix_.multigrid_mode && multigrid;
        evaluate();
        converged = iterate(solver_failed);
    } catch (...) {
        fail(SH_ERR_INTERNAL, "");  // out of memory or an internal error: nothing half done stays
        throw;
    }
    return finish(converged, solver_failed, keep_best);
}

// Newton iterations the step may take. Contacts switch on and off within a step, which a
// single update cannot follow: a body in contact iterates. Candidates that have not touched
// (a tool hovering near the organ) cost nothing: the step runs as without them until an
// iterate touches, then iterate() raises the cap.
int NewtonStep::iteration_cap() const {
    return std::max(touched_ ? kContactNewtonIterations : 1, s_.newton_max_iterations);
}

// The residual's scale: the first one, or the impulse of the loads over the step, the field's
// push at the first iterate counted with f_ext. A body held still against a tool balances that
// push: relative to the tiny residual of a step that starts at rest, the tolerance would sit
// below what the contact's and friction's kinks let Newton reach.
double NewtonStep::residual_scale() const {
    const double loads = std::hypot(problem_.applied_load_norm(g_), field_push_);
    return std::max(r_, dt_ * loads);
}

// matrix_.previous_v := the free velocities of the current iterate (the line search's start).
void NewtonStep::keep_velocities() {
    problem_.each([&](SteppedBody& stepped, size_t offset) {
        const vec<int32_t>& global = stepped.newton->matrix.system.dof_to_global();
        for (size_t d = 0; d < global.size(); ++d)
            matrix_.previous_v[offset + d] = stepped.body->v[static_cast<size_t>(global[d])];
    });
}

// The Newton loop from the evaluated start iterate; true if it converged. solver_failed: it
// stopped because the linear solver failed.
bool NewtonStep::iterate(bool& solver_failed) {
    int max_iterations = iteration_cap();
    bool linearised = max_iterations == 1, contact_mode = touched_;
    const double residual0 = residual_scale();
    const double gravity_norm = std::sqrt(g_[0] * g_[0] + g_[1] * g_[1] + g_[2] * g_[2]);
    // A linearised step's updates with a kept factorisation go on until both norms are down
    // by factor_reuse (the max norm keeps a small badly-solved region from hiding in the sum).
    const double target = s_.factor_reuse * r_, target_max = s_.factor_reuse * r_max_;
    const auto small = [&] { return r_ <= std::max(s_.newton_tolerance * residual0, matrix_.kept.roundoff_floor); };
    result_.newton_residual = -1.0;
    if (residual0 == 0.0) return true;
    bool towards_minimiser = false;  // a linearised step that went on iterating (see below)
    for (int iteration = 0;;) {
        // Converged: the residual is small against the first one or the applied load's
        // impulse, or down to the round-off of the element forces themselves.
        if (iteration > 0 && small()) return true;
        // A linearised step asked for no more than its lowest potential so far. A loop at its
        // cap may be creeping over the kinks of friction and contact (sticking nodes at rest,
        // where the speeds above vanish): its last correction is negligible if it is tol of
        // the bodies' size per step.
        if (iteration == max_iterations)
            return towards_minimiser || largest_change_ <= s_.newton_tolerance * extent() / dt_;
        bool failed = false;
        if (!factorize_and_solve(failed)) {
            solver_failed = true;
            return false;
        }
        keep_velocities();
        const double slope = slope_along_update();  // at scale 0
        const bool fresh = fresh_;
        if (!(slope < 0.0) || !line_search(slope, fresh)) {
            if (!fresh) {  // the kept factorisation is too far from the current tangent
                krylov_ = !krylov_failed_ && !touched_ && krylov_pays();
                factor_current_ = krylov_;
                continue;
            }
            if (krylov_update_) {  // an inexact update: factorise the tangent and solve exactly
                give_up_krylov();
                continue;
            }
            // No descent left along Newton's direction: converged if the residual is as small
            // as asked or within a few times the forces' round-off estimate (a fresh Newton
            // direction that cannot lower Phi there shows the residual is that round-off),
            // else stalled.
            return r_ <= std::max(s_.newton_tolerance * residual0, kStalledRoundoffFactor * matrix_.kept.roundoff_floor);
        }
        if (!fresh) {
            ++stale_solves_;
            used_stale = true;
        }
        fresh_ = false;
        factor_current_ = reuse_ && allow_stale_;  // exact Newton (or CG): a tangent per iterate
        ++result_.newton_iterations;
        result_.newton_residual = residual0 > 0.0 ? r_ / residual0 : 0.0;
        if (!contact_mode && touched_) {  // an update reached a contact: converge it as contact does
            contact_mode = true;
            linearised = towards_minimiser = false;
            max_iterations = iteration_cap();
            if (krylov_) give_up_krylov();  // contact's updates are exact, as they always were
        }
        if (linearised) {
            // One update with the tangent at its iterate is the linearised step; updates with
            // a kept factorisation go on until they are as good as factor_reuse asks.
            const double floor = matrix_.kept.roundoff_floor;
            if (!fresh && !(r_ <= std::max(target, floor) && r_max_ <= std::max(target_max, floor))) continue;
            if (!energy_rose(kLinearisedEnergyGain, EnergyAt::kLastEvaluation)) return energy_checked_ = true;
            // One update gained energy from nothing (large rotations, elements near inversion):
            // iterate towards the step's minimiser instead, as far as the iterations allow.
            linearised = false;
            towards_minimiser = true;
            max_iterations = kContactNewtonIterations;
            continue;
        }
        // On the way there, the first iterate that no longer gains energy is the linearised
        // step's answer: converging further (to newton_tolerance) would cost a dozen updates.
        if (towards_minimiser && !energy_rose(kLinearisedEnergyGain, EnergyAt::kLastEvaluation))
            return energy_checked_ = true;
        ++iteration;
        // Near equilibrium of a stiff body the residual is cancellation noise of large
        // element forces, so a negligible whole velocity correction also ends the loop.
        const double speed_scale = std::max({largest_speed_, dt_ * gravity_norm, kSpeedFloor});
        if (iteration > 1 && largest_change_ <= s_.newton_tolerance * speed_scale) return true;
    }
}

// The step's outcome: converged, or (keep_best, after some progress) its last iterate, the
// lowest potential the line search reached; otherwise restored with the reason.
BodyStepResult NewtonStep::finish(bool converged, bool solver_failed, bool keep_best) {
    const bool progressed = result_.newton_iterations > 0;
    if (!converged && !(keep_best && progressed)) {
        if (solver_failed && result_.status == SH_ERR_SOLVER)
            return fail(SH_ERR_SOLVER, "the sparse factorisation or solve failed (matrix not positive definite, or a "
                                       "non-finite value)");
        if (solver_failed) return fail(SH_ERR_NOT_CONVERGED, "the linear solver did not converge");
        return fail(SH_ERR_NOT_CONVERGED, "Newton iterations did not reach newton_tolerance");
    }
    result_.not_converged = !converged;
    result_.status = SH_OK;
    bool sane = true;
    problem_.each([&](SteppedBody& stepped, size_t) {
        Body& body = *stepped.body;
        end_kinematic_motion(body);
        sane = sane && body_state_is_sane(stepped);
    });
    if (!sane) return fail(SH_ERR_UNSTABLE, kRolledBackReason);
    if (!energy_checked_ && energy_rose(kEnergyGrowth, EnergyAt::kNow)) {  // the kinematic nodes may have moved
        // The last attempt keeps its finite iterate, as one that did not converge.
        if (!keep_best)
            return fail(SH_ERR_UNSTABLE, "the mechanical energy grew with no work done on the body (runaway); rolled back");
        result_.not_converged = true;
    }
    return result_;
}

// The step, retried with a factorisation at every iterate if a kept one took it somewhere bad.
BodyStepResult run_step(NewtonProblem& problem, const sh_implicit_settings& s, double dt, const double g[3],
                        bool keep_best) {
    NewtonStep first(problem, s, dt, g, true);
    const BodyStepResult result = first.run(keep_best);
    if (result.stable || !first.used_stale) return result;
    // The bodies are back at their start state.
    NewtonStep again(problem, s, dt, g, false);
    BodyStepResult sum = again.run(keep_best);
    sum.newton_iterations += result.newton_iterations;
    sum.linear_iterations += result.linear_iterations;
    sum.factorize_seconds += result.factorize_seconds;
    sum.solve_seconds += result.solve_seconds;
    sum.factorizations += result.factorizations;
    return sum;
}

}  // namespace

BodyStepResult step_implicit(SteppedBody& stepped, double dt, const double g[3], bool keep_best) {
    if (!stepped.newton) stepped.newton = sh::create<NewtonBodyState>();
    stepped.newton->prepare(*stepped.body, stepped.settings.implicit);
    NewtonProblem alone(stepped);
    return run_step(alone, stepped.settings.implicit, dt, g, keep_best);
}

BodyStepResult step_implicit_coupled(NewtonProblem& problem, double dt, const double g[3], bool keep_best) {
    sh_implicit_settings s = problem.body(0).settings.implicit;
    for (int32_t m = 1; m < problem.body_count(); ++m) {
        const sh_implicit_settings& other = problem.body(m).settings.implicit;
        s.newton_tolerance = std::min(s.newton_tolerance, other.newton_tolerance);
        s.newton_max_iterations = std::max(s.newton_max_iterations, other.newton_max_iterations);
    }
    return run_step(problem, s, dt, g, keep_best);
}

}  // namespace sh
