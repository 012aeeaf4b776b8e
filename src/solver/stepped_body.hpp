// SteppedBody: a body as the solvers step it. The body owns its state and physics; how it is
// stepped (integrator, guards, implicit settings) and the solvers' scratch for it live here,
// one per body, owned by the world.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <softhap/softhap.h>

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

/// For a scope, bodies[0..count) use states[0..count) as their implicit states (a static
/// solve's fresh ones, the error estimate's own); their own come back when it ends, also when
/// it ends by an exception.
class LentImplicitStates {
public:
    LentImplicitStates(SteppedBody* const* bodies, ImplicitState* const* states, int32_t count)
        : bodies_(bodies), kept_(static_cast<size_t>(count)) {
        for (int32_t m = 0; m < count; ++m) {
            kept_[static_cast<size_t>(m)] = bodies[m]->implicit;
            bodies[m]->implicit = states[m];
        }
    }
    ~LentImplicitStates() {
        for (size_t m = 0; m < kept_.size(); ++m) bodies_[m]->implicit = kept_[m];
    }
    LentImplicitStates(const LentImplicitStates&) = delete;
    LentImplicitStates& operator=(const LentImplicitStates&) = delete;

private:
    SteppedBody* const* bodies_;
    vec<ImplicitState*> kept_;
};

}  // namespace sh
