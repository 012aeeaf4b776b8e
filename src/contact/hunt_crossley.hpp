// The contact law: Hunt-Crossley normal force, regularised Coulomb friction, and the stable
// explicit step they allow.
#pragma once

#include <softhap/softhap.h>

#include <cmath>

namespace sh {

/// The normal force of a contact and its derivatives.
struct NormalForce {
    double force = 0.0;      ///< F >= 0 (N)
    double stiffness = 0.0;  ///< dF/dx (N/m), the part that keeps the tangent positive
    double damping = 0.0;    ///< dF/dx' (N s/m)
};

/// F = max(0, lambda x^n + mu x' x^n), mu = 3/2 alpha lambda, at depth x (m) and depth rate
/// x' (m/s, > 0 going deeper). Zero for x <= 0 and wherever the damping would pull.
inline NormalForce hunt_crossley(const sh_contact_params& p, double x, double rate) {
    NormalForce out;
    if (!(x > 0.0)) return out;
    const double xn = p.exponent == 1.0 ? x : std::pow(x, p.exponent);
    const double mu = 1.5 * p.damping * p.stiffness;
    const double factor = 1.0 + 1.5 * p.damping * rate;  // (lambda + mu x') / lambda
    if (!(factor > 0.0)) return out;
    out.force = p.stiffness * xn * factor;
    out.stiffness = p.exponent * out.force / x;
    out.damping = mu * xn;
    return out;
}

/// Potential of the elastic part lambda x^n at depth x: lambda x^(n+1) / (n + 1) (J).
inline double hunt_crossley_energy(const sh_contact_params& p, double x) {
    if (!(x > 0.0)) return 0.0;
    return p.stiffness * std::pow(x, p.exponent + 1.0) / (p.exponent + 1.0);
}

/// Friction on a point sliding at tangential velocity vt (relative to the collider, m/s) under
/// normal force fn (N): below slip_velocity s0 it is viscous, -mu_s fn vt / s0 (sticking, at
/// most mu_s fn); above, its magnitude falls from mu_s fn at s0 towards mu_d fn as
/// (mu_d + (mu_s - mu_d) s0 / |vt|) fn, against vt. Writes the force into out and returns the
/// viscous coefficient |F| / max(|vt|, s0) (N s/m) that the implicit tangent uses.
inline double coulomb_friction(const sh_contact_params& p, double fn, const double vt[3], double out[3]) {
    const double speed = std::sqrt(vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]);
    const double s0 = p.slip_velocity;
    const double mu = speed <= s0 ? p.static_friction : p.dynamic_friction + (p.static_friction - p.dynamic_friction) * s0 / speed;
    const double coefficient = mu * fn / (speed <= s0 ? s0 : speed);
    for (int k = 0; k < 3; ++k) out[k] = -coefficient * vt[k];
    return coefficient;
}

/// Largest symplectic-Euler step stable for a mass m (kg) on a spring k (N/m) with a dashpot c
/// (N s/m): 2 / omega (sqrt(1 + zeta^2) - zeta); INFINITY with neither.
inline double damped_stable_step(double k, double c, double m) {
    if (!(m > 0.0)) return INFINITY;
    if (!(k > 0.0)) return c > 0.0 ? 2.0 * m / c : INFINITY;
    const double omega = std::sqrt(k / m);
    const double zeta = c / (2.0 * m * omega);
    return 2.0 / omega / (std::sqrt(1.0 + zeta * zeta) + zeta);
}

}  // namespace sh
