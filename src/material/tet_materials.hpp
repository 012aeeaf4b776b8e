// Constitutive laws of tetrahedral elements, evaluated per lane: first Piola-Kirchhoff stress
// P(F), its differential dP(F)[dF] (for stiffness damping) and the energy density psi(F).
// lambda and mu are the Lame parameters of the material's small-strain limit; every model
// reduces to linear elasticity for small strains.
#pragma once

#include "material/lanes.hpp"
#include "material/polar_decomposition.hpp"

#include <cmath>

namespace sh {

/// Small-strain linear elasticity: eps = sym(F) - I, P = 2 mu eps + lambda tr(eps) I.
struct LinearMaterial {
    struct State {};
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State&) {
        const Mat3L eps = add_diagonal(sym(F), splat(-1.0));
        return add_diagonal(combine(2.0 * mu, eps, Lanes{}, eps), lambda * trace(eps));
    }
    static SH_INLINE Mat3L differential(const Mat3L&, const State&, const Mat3L& dF, Lanes lambda, Lanes mu) {
        const Mat3L deps = sym(dF);
        return add_diagonal(combine(2.0 * mu, deps, Lanes{}, deps), lambda * trace(deps));
    }
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        const Mat3L eps = add_diagonal(sym(F), splat(-1.0));
        const Lanes tr = trace(eps);
        return mu * ddot(eps, eps) + 0.5 * lambda * tr * tr;
    }
};

/// St. Venant-Kirchhoff: E = (F^T F - I)/2, S = lambda tr(E) I + 2 mu E, P = F S.
struct StvkMaterial {
    struct State {
        Mat3L S;
    };
    static SH_INLINE Mat3L second_piola(const Mat3L& E, Lanes lambda, Lanes mu) {
        return add_diagonal(combine(2.0 * mu, E, Lanes{}, E), lambda * trace(E));
    }
    static SH_INLINE Mat3L green_strain(const Mat3L& F) {
        Mat3L E = mul_tn(F, F);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) E.m[i][j] = 0.5 * E.m[i][j];
        return add_diagonal(E, splat(-0.5));
    }
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State& state) {
        state.S = second_piola(green_strain(F), lambda, mu);
        return mul(F, state.S);
    }
    static SH_INLINE Mat3L differential(const Mat3L& F, const State& state, const Mat3L& dF, Lanes lambda, Lanes mu) {
        const Mat3L dE = sym(mul_tn(F, dF));
        const Mat3L a = mul(dF, state.S), b = mul(F, second_piola(dE, lambda, mu));
        return combine(splat(1.0), a, splat(1.0), b);
    }
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        const Mat3L E = green_strain(F);
        const Lanes tr = trace(E);
        return mu * ddot(E, E) + 0.5 * lambda * tr * tr;
    }
};

/// Corotational linear elasticity: F = R S, eps = sym(R^T F) - I, P = R (2 mu eps + lambda tr(eps) I).
/// The differential holds R fixed (the usual corotational tangent).
struct CorotationalMaterial {
    struct State {
        Mat3L R;
    };
    static SH_INLINE Mat3L rotated_stress(const Mat3L& R, const Mat3L& G, Lanes lambda, Lanes mu, bool subtract_identity) {
        Mat3L eps = sym(mul_tn(R, G));
        if (subtract_identity) eps = add_diagonal(eps, splat(-1.0));
        return mul(R, add_diagonal(combine(2.0 * mu, eps, Lanes{}, eps), lambda * trace(eps)));
    }
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State& state) {
        state.R = polar_rotation(F);
        return rotated_stress(state.R, F, lambda, mu, true);
    }
    static SH_INLINE Mat3L differential(const Mat3L&, const State& state, const Mat3L& dF, Lanes lambda, Lanes mu) {
        return rotated_stress(state.R, dF, lambda, mu, false);
    }
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        const Mat3L eps = add_diagonal(sym(mul_tn(polar_rotation(F), F)), splat(-1.0));
        const Lanes tr = trace(eps);
        return mu * ddot(eps, eps) + 0.5 * lambda * tr * tr;
    }
};

/// Stable neo-Hookean (Smith, de Goes, Kim 2018):
/// psi = m/2 (Ic - 3) + l/2 (J - a)^2 - m/2 log(Ic + 1) - psi(I), a = 1 + 3m/(4l),
/// with m = 4/3 mu and l = lambda + 5/6 mu so that small strains match linear elasticity.
struct NeoHookeanMaterial {
    struct State {
        Mat3L cof;
        Lanes ic, j;
    };
    static SH_INLINE void parameters(Lanes lambda, Lanes mu, Lanes& m, Lanes& l, Lanes& alpha) {
        m = (4.0 / 3.0) * mu;
        l = lambda + (5.0 / 6.0) * mu;
        alpha = 1.0 + 0.75 * m / l;
    }
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State& state) {
        Lanes m, l, alpha;
        parameters(lambda, mu, m, l, alpha);
        state.ic = ddot(F, F);
        state.cof = cofactor(F);
        state.j = det(F);
        return combine(m * (1.0 - 1.0 / (state.ic + 1.0)), F, l * (state.j - alpha), state.cof);
    }
    static SH_INLINE Mat3L differential(const Mat3L& F, const State& state, const Mat3L& dF, Lanes lambda, Lanes mu) {
        Lanes m, l, alpha;
        parameters(lambda, mu, m, l, alpha);
        const Lanes inv = 1.0 / (state.ic + 1.0);
        // d cof(F)[dF]: cofactor is bilinear, so its differential is cof(F + dF) - cof(F) - cof(dF).
        Mat3L F_plus = F;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) F_plus.m[i][j] += dF.m[i][j];
        const Mat3L c_plus = cofactor(F_plus), c_d = cofactor(dF);
        Mat3L dcof;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) dcof.m[i][j] = c_plus.m[i][j] - state.cof.m[i][j] - c_d.m[i][j];
        const Mat3L a = combine(m * (1.0 - inv), dF, 2.0 * m * inv * inv * ddot(F, dF), F);
        const Mat3L b = combine(l * ddot(state.cof, dF), state.cof, l * (state.j - alpha), dcof);
        return combine(splat(1.0), a, splat(1.0), b);
    }
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        Lanes m, l, alpha;
        parameters(lambda, mu, m, l, alpha);
        const Lanes ic = ddot(F, F), jm = det(F) - alpha, rest = 1.0 - alpha;
        Lanes logs;
        for (int k = 0; k < kLanes; ++k) logs[k] = std::log((ic[k] + 1.0) / 4.0);
        return 0.5 * m * (ic - 3.0) + 0.5 * l * (jm * jm - rest * rest) - 0.5 * m * logs;
    }
};

}  // namespace sh
