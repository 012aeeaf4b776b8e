// The contact law: Hunt-Crossley normal force, regularised Coulomb friction, and the stable
// explicit step they allow.
#pragma once

#include <softhap/softhap.h>

#include <algorithm>
#include <cmath>

namespace sh {

/// The normal force of a contact and its derivatives.
struct NormalForce {
    double force = 0.0;      ///< F >= 0 (N)
    double stiffness = 0.0;  ///< dF/dx (N/m), the part that keeps the tangent positive
    double damping = 0.0;    ///< dF/dx' (N s/m)
};

/// x^n for x > 0: the usual exponents (1, 1.5, 2, 2.5, 3) by multiplications and a square
/// root (correctly rounded, so within an ulp or two of std::pow), any other by std::pow, which
/// costs several times more and is called for every contact evaluation.
inline double depth_power(double x, double n) {
    if (n == 1.0) return x;
    if (n == 1.5) return x * std::sqrt(x);
    if (n == 2.0) return x * x;
    if (n == 2.5) return x * x * std::sqrt(x);
    if (n == 3.0) return x * x * x;
    return std::pow(x, n);
}

/// F = max(0, lambda x^n + mu x' x^n), mu = 3/2 alpha lambda, at depth x (m) and depth rate
/// x' (m/s, > 0 going deeper). Zero for x <= 0 and wherever the damping would pull.
inline NormalForce hunt_crossley(const sh_contact_params& p, double x, double rate) {
    NormalForce out;
    if (!(x > 0.0)) return out;
    const double xn = depth_power(x, p.exponent);
    const double mu = 1.5 * p.damping * p.stiffness;
    const double factor = 1.0 + 1.5 * p.damping * rate;  // (lambda + mu x') / lambda
    if (!(factor > 0.0)) return out;
    out.force = p.stiffness * xn * factor;
    out.stiffness = p.exponent * out.force / x;
    out.damping = mu * xn;
    return out;
}

/// The Hunt-Crossley law over one implicit (backward Euler) step of length h (s): the depth
/// rate is the step's backward difference (x - x_start) / h, x_start the depth at the step's
/// start (0 if it did not touch then), so the force F(x) = max(0, x^n (lambda + mu (x -
/// x_start) / h)) depends on the depth alone. It is then the derivative of a potential
/// (hunt_crossley_step_energy) and dF/dx >= 0 wherever it acts, which a line search on the
/// step's incremental potential needs. h = 0 gives the law at rest, lambda x^n.
struct StepLaw {
    double a = 0.0;  ///< F = x^n (a + b x) where positive (N/m^n)
    double b = 0.0;  ///< (N/m^(n+1))
    double lower = 0.0;  ///< depth (m) below which F is 0 (the damping would pull)
};

inline StepLaw hunt_crossley_step_law(const sh_contact_params& p, double x_start, double h) {
    StepLaw law;
    const double mu = 1.5 * p.damping * p.stiffness;
    law.b = h > 0.0 ? mu / h : 0.0;
    law.a = p.stiffness - law.b * (x_start > 0.0 ? x_start : 0.0);
    law.lower = law.a < 0.0 ? -law.a / law.b : 0.0;
    return law;
}

/// F and dF/dx of law at depth x (m); no damping term (the rate is in x).
inline NormalForce hunt_crossley_step(const sh_contact_params& p, const StepLaw& law, double x) {
    NormalForce out;
    if (!(x > law.lower) || !(x > 0.0)) return out;
    const double xn = depth_power(x, p.exponent);
    const double factor = law.a + law.b * x;
    out.force = xn * factor;
    out.stiffness = p.exponent * xn / x * factor + law.b * xn;
    return out;
}

/// The potential of hunt_crossley_step: the integral of F from 0 to x (J).
inline double hunt_crossley_step_energy(const sh_contact_params& p, const StepLaw& law, double x) {
    if (!(x > law.lower) || !(x > 0.0)) return 0.0;
    const double n = p.exponent;
    const auto primitive = [&](double s) {
        if (!(s > 0.0)) return 0.0;
        const double s1 = depth_power(s, n + 1.0);
        return law.a * s1 / (n + 1.0) + law.b * s1 * s / (n + 2.0);
    };
    return primitive(x) - primitive(law.lower);
}

/// Magnitude (N) of the regularised Coulomb friction at tangential speed s >= 0 (m/s) under
/// normal force fn (N): below the slip velocity s0 it is viscous, mu_s fn s / s0 (sticking, at
/// most mu_s fn); above, it falls from mu_s fn at s0 towards mu_d fn as
/// (mu_d + (mu_s - mu_d) s0 / s) fn. Continuous at s0.
inline double friction_magnitude(const sh_contact_params& p, double fn, double s) {
    const double s0 = p.slip_velocity;
    if (s <= s0) return p.static_friction * fn * s / s0;
    return (p.dynamic_friction + (p.static_friction - p.dynamic_friction) * s0 / s) * fn;
}

/// Friction on a point sliding at tangential velocity vt (relative to the other side, m/s)
/// under normal force fn (N): friction_magnitude against vt. Writes the force into out and
/// returns the viscous coefficient |F| / |vt| (N s/m; mu_s fn / s0 while sticking).
inline double coulomb_friction(const sh_contact_params& p, double fn, const double vt[3], double out[3]) {
    const double speed = std::sqrt(vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]);
    const double coefficient =
        speed <= p.slip_velocity ? p.static_friction * fn / p.slip_velocity : friction_magnitude(p, fn, speed) / speed;
    for (int k = 0; k < 3; ++k) out[k] = -coefficient * vt[k];
    return coefficient;
}

/// D = -dF/dvt of coulomb_friction at tangential speed s (m/s) under a normal force fn (N)
/// held fixed, on the tangent plane, as across (I - t t^T) + along t t^T with t = vt / s:
/// sticking (s <= s0) it is mu_s fn / s0 in every tangent direction; sliding, the force turns
/// with vt (across = |F| / s) and its magnitude changes along t by d|F|/ds =
/// -(mu_s - mu_d) fn s0 / s^2 <= 0 (friction weakens as the slip speeds up), a negative part
/// that is dropped (along = 0) to keep D positive semi-definite. chord >= 0 replaces along
/// while sliding (see BodyContacts::friction_chord).
struct FrictionTangent {
    double across = 0.0;  ///< N s/m
    double along = 0.0;   ///< N s/m
};

inline FrictionTangent friction_tangent(const sh_contact_params& p, double fn, double s, double chord = -1.0) {
    FrictionTangent out;
    if (!(fn > 0.0)) return out;
    if (s <= p.slip_velocity) {
        out.across = out.along = p.static_friction * fn / p.slip_velocity;
    } else {
        out.across = friction_magnitude(p, fn, s) / s;
        out.along = chord >= 0.0 ? chord : 0.0;
    }
    return out;
}

/// Dissipation potential (W) of the friction at tangential speed s (m/s) under a normal force
/// fn (N) held fixed: the integral of friction_magnitude from 0 to s, whose gradient in vt is
/// -F. With the normal force lagged, an implicit step's friction is its gradient: a line
/// search on the step's incremental potential would add h times it.
inline double friction_potential(const sh_contact_params& p, double fn, double s) {
    const double s0 = p.slip_velocity;
    if (s <= s0) return 0.5 * p.static_friction * fn * s * s / s0;
    return 0.5 * p.static_friction * fn * s0 + p.dynamic_friction * fn * (s - s0) +
           (p.static_friction - p.dynamic_friction) * fn * s0 * std::log(s / s0);
}

/// Tangential speed (m/s) at the end of an explicit step of length h (s) in which the friction
/// acts implicitly (backward Euler) on a contact whose tangential speed would be s_free without
/// it: the s >= 0 with s + wh friction_magnitude(s) = s_free, wh = h times the contact's
/// effective inverse mass (s/kg). Sticking, s = s_free / (1 + wh mu_s fn / s0) when that is at
/// most s0; otherwise the sliding root, which is then unique (above s0) even where the slip
/// branch weakens (mu_s > mu_d). Stable for any h: the speed never grows nor reverses.
inline double implicit_slip_speed(const sh_contact_params& p, double fn, double s_free, double wh) {
    const double s0 = p.slip_velocity;
    const double stick = s_free / (1.0 + wh * p.static_friction * fn / s0);
    if (stick <= s0) return stick;
    // s^2 - b s + a0 = 0 with b = s_free - wh mu_d fn, a0 = wh (mu_s - mu_d) fn s0; it is
    // negative at s0 here, so its larger root is the one above s0.
    const double b = s_free - wh * p.dynamic_friction * fn;
    const double a0 = wh * (p.static_friction - p.dynamic_friction) * fn * s0;
    const double root = std::sqrt(std::max(0.0, b * b - 4.0 * a0));
    return std::max(s0, 0.5 * (b + root));
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
