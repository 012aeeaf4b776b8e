#include "model/body.hpp"

#include "model/external_field.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

Body::Body(IntegrationSettings s, vec<double> rest_positions) : settings(s), x(std::move(rest_positions)) {
    rest = x;
    const size_t n = x.size() / 3;
    v.assign(3 * n, 0.0);
    mass.assign(n, 0.0);
    inverse_mass.assign(n, 0.0);
    kinematic.assign(n, 0);
    target = x;
    external_force.assign(3 * n, 0.0);
    IntegratorWorkspace& w = workspace;
    w.x0.resize(3 * n);
    w.v0.resize(3 * n);
    w.xs.resize(3 * n);
    w.vs.resize(3 * n);
    for (auto& a : w.a) a.resize(3 * n);
    w.dx.resize(3 * n);
}

void Body::update_inverse_mass() {
    for (size_t i = 0; i < mass.size(); ++i)
        inverse_mass[i] = (mass[i] > 0.0 && !kinematic[i]) ? 1.0 / mass[i] : 0.0;
}

void Body::set_node_damping(const double* coefficients) {
    if (coefficients)
        node_damping.assign(coefficients, coefficients + mass.size());
    else
        node_damping = vec<double>();
    ++matrix_version;
}

double Body::critical_dt() const {
    if (settings.integrator == SH_INTEGRATOR_IMPLICIT_EULER) return INFINITY;  // unconditionally stable
    // Stability limits on the imaginary axis relative to leapfrog's 2/omega: RK4 reaches
    // 2*sqrt(2)/omega. Forward Euler and RK2 have no undamped stable step at all (their energy
    // grows at every dt); they get the leapfrog limit, beyond which growth is explosive.
    const double factor = settings.integrator == SH_INTEGRATOR_RK4 ? 1.4142135623730951 : 1.0;
    const double own = factor * stable_step(x.data());
    return field ? std::min(own, factor * field->stable_step(x.data(), v.data(), mass.data())) : own;
}

}  // namespace sh
