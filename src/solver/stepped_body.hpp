// SteppedBody: a body as the solvers step it. The body owns its state and physics; how it is
// stepped (integrator, guards, implicit settings), the solvers' scratch for it and the Newton
// solves' per-body data (NewtonBodyState) live here, one per body, owned by the world.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <softhap/softhap.h>

#include <utility>

namespace sh {

struct NewtonBodyState;

/// How a body is stepped, chosen when it is created.
struct StepSettings {
    sh_integrator integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;  ///< the time-stepping scheme
    sh_unstable_policy on_unstable = SH_UNSTABLE_SUBSTEP;      ///< what a failed step does
    sh_implicit_settings implicit{};  ///< read for SH_INTEGRATOR_IMPLICIT_EULER
    double runaway_speed = 1e4;       ///< m/s: a faster node rolls the step back
};

/// Most stages of an explicit Runge-Kutta method in the integrator table.
constexpr int kMaxStages = 4;

/// Scratch arrays of the integrators and solvers, 3 values per node.
struct IntegratorWorkspace {
    vec<double> x0, v0;                     ///< state at the start of the step (rollback)
    vec<double> xs, vs;                     ///< a stage's state
    vec<double> stage_v[kMaxStages];        ///< stage velocities (dx/dt of each stage)
    vec<double> stage_a[kMaxStages];        ///< stage accelerations (dv/dt of each stage)

    /// Sizes every array for node_count nodes.
    void resize(int32_t node_count);

    /// Makes room in every array for node_count nodes (reserve_growing), so that a later
    /// resize to at most that many allocates nothing. Throws std::bad_alloc.
    void reserve(int32_t node_count);
};

/// A body with its step settings, scratch and the Newton solves' data for it.
struct SteppedBody {
    Body* body = nullptr;            ///< the body stepped (owned by the world)
    StepSettings settings;           ///< how it is stepped
    IntegratorWorkspace workspace;   ///< the integrators' scratch
    NewtonBodyState* newton = nullptr;  ///< its Newton solves' data, built on the first implicit step
};

/// For a scope, bodies[0..count) and states[0..count) trade Newton states (a static solve's
/// fresh ones, the error estimate's own), and trade back when it ends, also by an exception.
/// A state a body creates in the scope (step_implicit makes one if it has none) ends up in
/// states[m].
class SwappedNewtonStates {
public:
    /// Swaps bodies[m]->newton with states[m] for every m < count.
    SwappedNewtonStates(SteppedBody* const* bodies, NewtonBodyState** states, int32_t count)
        : bodies_(bodies), states_(states), count_(count) {
        swap();
    }
    /// Swaps them back.
    ~SwappedNewtonStates() { swap(); }
    SwappedNewtonStates(const SwappedNewtonStates&) = delete;             ///< a scope guard
    SwappedNewtonStates& operator=(const SwappedNewtonStates&) = delete;  ///< a scope guard

private:
    /// Trades every body's state with its entry of states_.
    void swap() {
        for (int32_t m = 0; m < count_; ++m) std::swap(bodies_[m]->newton, states_[m]);
    }
    SteppedBody* const* bodies_;  ///< the bodies
    NewtonBodyState** states_;    ///< their states for the scope, theirs outside it
    int32_t count_;               ///< how many
};

}  // namespace sh
