#include "solver/explicit_integrator.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// More sub-steps than this means dt_crit is unreasonably small for dt: reject instead.
constexpr double kMaxSubsteps = 1 << 20;

// y = x + h z over n values.
void axpy(double* y, const double* x, double h, const double* z, size_t n) {
    for (size_t i = 0; i < n; ++i) y[i] = x[i] + h * z[i];
}

void integrate(Body& body, double h, const double g[3]) {
    IntegratorWorkspace& w = body.workspace;
    double* x = body.x.data();
    double* v = body.v.data();
    const size_t n = body.x.size();
    double* a0 = w.a[0].data();
    switch (body.settings.integrator) {
        case SH_INTEGRATOR_FORWARD_EULER:
            compute_accelerations(body, x, v, g, a0);
            for (size_t i = 0; i < n; ++i) {
                x[i] += h * v[i];
                v[i] += h * a0[i];
            }
            break;
        case SH_INTEGRATOR_SYMPLECTIC_EULER:
            compute_accelerations(body, x, v, g, a0);
            for (size_t i = 0; i < n; ++i) {
                v[i] += h * a0[i];
                x[i] += h * v[i];
            }
            break;
        case SH_INTEGRATOR_RK2: {  // explicit midpoint
            double *xs = w.xs.data(), *vs = w.vs.data(), *a1 = w.a[1].data();
            compute_accelerations(body, x, v, g, a0);
            axpy(xs, x, 0.5 * h, v, n);
            axpy(vs, v, 0.5 * h, a0, n);
            compute_accelerations(body, xs, vs, g, a1);
            for (size_t i = 0; i < n; ++i) {
                x[i] += h * vs[i];
                v[i] += h * a1[i];
            }
            break;
        }
        case SH_INTEGRATOR_RK4: {
            double *xs = w.xs.data(), *vs = w.vs.data(), *dx = w.dx.data(), *dv = w.a[3].data();
            double *a1 = w.a[1].data(), *a2 = w.a[2].data();
            compute_accelerations(body, x, v, g, a0);                 // k1 = (v, a0)
            axpy(xs, x, 0.5 * h, v, n);
            axpy(vs, v, 0.5 * h, a0, n);
            for (size_t i = 0; i < n; ++i) dx[i] = v[i] + 2.0 * vs[i];
            compute_accelerations(body, xs, vs, g, a1);               // k2 = (vs, a1)
            axpy(xs, x, 0.5 * h, vs, n);
            axpy(vs, v, 0.5 * h, a1, n);
            for (size_t i = 0; i < n; ++i) dx[i] += 2.0 * vs[i];
            compute_accelerations(body, xs, vs, g, a2);               // k3 = (vs, a2)
            for (size_t i = 0; i < n; ++i) dv[i] = a0[i] + 2.0 * a1[i] + 2.0 * a2[i];
            axpy(xs, x, h, vs, n);
            axpy(vs, v, h, a2, n);
            for (size_t i = 0; i < n; ++i) dx[i] += vs[i];
            compute_accelerations(body, xs, vs, g, a1);               // k4 = (vs, a1)
            for (size_t i = 0; i < n; ++i) {
                x[i] += h / 6.0 * dx[i];
                v[i] += h / 6.0 * (dv[i] + a1[i]);
            }
            break;
        }
    }
}

bool state_is_sane(const Body& body) {
    const double limit2 = body.settings.runaway_speed * body.settings.runaway_speed;
    const size_t n = body.mass.size();
    bool sane = true;
    for (size_t i = 0; i < n; ++i) {
        const double* xi = &body.x[3 * i];
        const double* vi = &body.v[3 * i];
        const double speed2 = vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2];
        // NaN fails every comparison, so !(a <= b) also catches it.
        sane &= speed2 <= limit2 && std::isfinite(xi[0] + xi[1] + xi[2]);
    }
    return sane;
}

}  // namespace

void compute_accelerations(const Body& body, const double* x, const double* v, const double g[3], double* a) {
    const size_t n = body.mass.size();
    std::fill(a, a + 3 * n, 0.0);
    body.add_internal_forces(x, v, a);
    const double alpha = body.settings.damping_mass;
    const bool per_node = !body.node_damping.empty();
    for (size_t i = 0; i < n; ++i) {
        const double inv_m = body.inverse_mass[i];
        const double c = alpha + (per_node ? body.node_damping[i] : 0.0);
        for (int k = 0; k < 3; ++k) {
            const size_t j = 3 * i + k;
            a[j] = inv_m > 0.0 ? (a[j] + body.external_force[j]) * inv_m + g[k] - c * v[j] : 0.0;
        }
    }
}

BodyStepResult step_explicit(Body& body, double dt, const double g[3]) {
    BodyStepResult result;
    result.dt_critical = body.critical_dt();
    double substeps = 1.0;
    if (dt > result.dt_critical) {
        substeps = std::ceil(dt / result.dt_critical);
        if (body.settings.on_unstable == SH_UNSTABLE_REJECT || !(substeps <= kMaxSubsteps)) {
            result.stable = false;
            result.rejected = true;
            return result;
        }
    }
    result.substeps = static_cast<int32_t>(substeps);

    IntegratorWorkspace& w = body.workspace;
    std::copy(body.x.begin(), body.x.end(), w.x0.begin());
    std::copy(body.v.begin(), body.v.end(), w.v0.begin());
    const size_t n = body.mass.size();
    for (size_t i = 0; i < n; ++i) {
        if (!body.kinematic[i]) continue;
        for (int k = 0; k < 3; ++k) body.v[3 * i + k] = (body.target[3 * i + k] - body.x[3 * i + k]) / dt;
    }

    const double h = dt / substeps;
    for (int32_t s = 0; s < result.substeps; ++s) integrate(body, h, g);

    for (size_t i = 0; i < n; ++i) {
        if (!body.kinematic[i] && body.mass[i] > 0.0) continue;
        for (int k = 0; k < 3; ++k) {
            if (body.kinematic[i]) body.x[3 * i + k] = body.target[3 * i + k];
            body.v[3 * i + k] = 0.0;
        }
    }

    if (!state_is_sane(body)) {
        std::copy(w.x0.begin(), w.x0.end(), body.x.begin());
        std::copy(w.v0.begin(), w.v0.end(), body.v.begin());
        result.stable = false;
    }
    return result;
}

}  // namespace sh
