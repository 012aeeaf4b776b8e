// SteppedBody: a body as the solvers step it. The body owns its state and physics; how it is
// stepped (integrator, guards, implicit settings) and the solvers' scratch for it live here,
// one per body, owned by the world.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <softhap/softhap.h>

#include <utility>

namespace sh {

struct ImplicitState;

/// How a body is stepped, chosen when it is created.
struct StepSettings {
    sh_integrator integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
    sh_unstable_policy on_unstable = SH_UNSTABLE_SUBSTEP;
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
};

/// A body with its step settings, scratch and implicit solver state.
struct SteppedBody {
    Body* body = nullptr;
    StepSettings settings;
    IntegratorWorkspace workspace;
    ImplicitState* implicit = nullptr;  ///< built on the first implicit step
};

/// For a scope, bodies[0..count) and states[0..count) trade implicit states (a static solve's
/// fresh ones, the error estimate's own), and trade back when it ends, also by an exception.
/// A state a body creates in the scope (step_implicit makes one if it has none) ends up in
/// states[m].
class SwappedImplicitStates {
public:
    SwappedImplicitStates(SteppedBody* const* bodies, ImplicitState** states, int32_t count)
        : bodies_(bodies), states_(states), count_(count) {
        swap();
    }
    ~SwappedImplicitStates() { swap(); }
    SwappedImplicitStates(const SwappedImplicitStates&) = delete;
    SwappedImplicitStates& operator=(const SwappedImplicitStates&) = delete;

private:
    void swap() {
        for (int32_t m = 0; m < count_; ++m) std::swap(bodies_[m]->implicit, states_[m]);
    }
    SteppedBody* const* bodies_;
    ImplicitState** states_;
    int32_t count_;
};

}  // namespace sh
