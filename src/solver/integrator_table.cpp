#include "solver/integrator_table.hpp"

#include "model/external_field.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// Stability factors on the imaginary axis relative to leapfrog's 2/omega: RK4 reaches
// 2 sqrt(2)/omega. Forward Euler and RK2 have no undamped stable step at all (their energy
// grows at every dt); they get the leapfrog limit, beyond which growth is explosive.
const IntegratorKind kIntegrators[SH_INTEGRATOR_COUNT] = {
    {"forward_euler", StepScheme::RungeKutta, {1, {}, {1.0}}, 1.0},
    {"symplectic_euler", StepScheme::SymplecticEuler, {}, 1.0},
    {"rk2", StepScheme::RungeKutta, {2, {{0.0}, {0.5}}, {0.0, 1.0}}, 1.0},  // explicit midpoint
    {"rk4",
     StepScheme::RungeKutta,
     {4, {{0.0}, {0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}}, {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0}},
     1.4142135623730951},
    {"implicit_euler", StepScheme::ImplicitEuler, {}, INFINITY},
};

}  // namespace

bool is_integrator(int integrator) { return integrator >= 0 && integrator < SH_INTEGRATOR_COUNT; }

const IntegratorKind& integrator_kind(sh_integrator integrator) { return kIntegrators[static_cast<int>(integrator)]; }

double critical_step(const Body& body, sh_integrator integrator) {
    const double factor = integrator_kind(integrator).stability_factor;
    if (std::isinf(factor)) return INFINITY;
    const double own = factor * body.stable_step(body.x.data());
    return body.field ? std::min(own, factor * body.field->stable_step(body.x.data(), body.v.data(), body.mass.data()))
                      : own;
}

}  // namespace sh
