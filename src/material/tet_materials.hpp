// Constitutive laws of tetrahedral elements, evaluated per lane: first Piola-Kirchhoff stress
// P(F), its differential dP(F)[dF] (for stiffness damping) and the energy density psi(F).
// lambda and mu are the Lame parameters of the material's small-strain limit; every model
// reduces to linear elasticity for small strains.
//
// Every law is homogeneous of degree one in (lambda, mu): P, dP and psi scale with them. The
// element kernels use this to pass lambda and mu already multiplied by -V0 (see TetBlock), which
// yields the nodal-force matrix -V0 P and the element energy -V0 psi without extra products.
// The formulas are written out for symmetric tensors (strain, second Piola stress) so the hot
// loops compute each unique entry once.
#pragma once

#include "material/lanes.hpp"
#include "material/polar_decomposition.hpp"

#include <softhap/softhap.h>

#include <cmath>

namespace sh {

/// Symmetric 3x3 per lane: diagonal d[i] and off-diagonal o[0] = (0,1), o[1] = (0,2), o[2] = (1,2).
struct Sym3L {
    Lanes d[3];
    Lanes o[3];
};

/// 2 mu A + lambda tr(A) I for symmetric A (a linear isotropic law).
SH_INLINE Sym3L isotropic_law(const Sym3L& a, Lanes lambda, Lanes mu) {
    const Lanes mu2 = mu + mu;
    const Lanes lt = lambda * (a.d[0] + a.d[1] + a.d[2]);
    Sym3L s;
    for (int i = 0; i < 3; ++i) s.d[i] = mu2 * a.d[i] + lt;
    for (int i = 0; i < 3; ++i) s.o[i] = mu2 * a.o[i];
    return s;
}

/// mu A : A + lambda/2 tr(A)^2 for symmetric A (the energy of isotropic_law).
SH_INLINE Lanes isotropic_energy(const Sym3L& a, Lanes lambda, Lanes mu) {
    const Lanes tr = a.d[0] + a.d[1] + a.d[2];
    const Lanes dd = a.d[0] * a.d[0] + a.d[1] * a.d[1] + a.d[2] * a.d[2];
    const Lanes oo = a.o[0] * a.o[0] + a.o[1] * a.o[1] + a.o[2] * a.o[2];
    return mu * (dd + 2.0 * oo) + 0.5 * lambda * tr * tr;
}

/// sym(A) - s I.
SH_INLINE Sym3L sym_part(const Mat3L& a, double s) {
    Sym3L r;
    for (int i = 0; i < 3; ++i) r.d[i] = a.m[i][i] - s;
    r.o[0] = 0.5 * (a.m[0][1] + a.m[1][0]);
    r.o[1] = 0.5 * (a.m[0][2] + a.m[2][0]);
    r.o[2] = 0.5 * (a.m[1][2] + a.m[2][1]);
    return r;
}

/// A S for symmetric S.
SH_INLINE Mat3L mul_sym(const Mat3L& a, const Sym3L& s) {
    const Lanes c[3][3] = {{s.d[0], s.o[0], s.o[1]}, {s.o[0], s.d[1], s.o[2]}, {s.o[1], s.o[2], s.d[2]}};
    Mat3L r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][0] * c[0][j] + a.m[i][1] * c[1][j] + a.m[i][2] * c[2][j];
    return r;
}

/// Symmetric 3x3 as a full matrix.
SH_INLINE Mat3L full(const Sym3L& s) {
    Mat3L r;
    for (int i = 0; i < 3; ++i) r.m[i][i] = s.d[i];
    r.m[0][1] = r.m[1][0] = s.o[0];
    r.m[0][2] = r.m[2][0] = s.o[1];
    r.m[1][2] = r.m[2][1] = s.o[2];
    return r;
}

/// Small-strain linear elasticity: eps = sym(F) - I, P = 2 mu eps + lambda tr(eps) I.
struct LinearMaterial {
    struct State {};
    /// det F after stress() (for the inverted-element count).
    static SH_INLINE Lanes jacobian(const Mat3L& F, const State&) { return det(F); }
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State&) {
        return full(isotropic_law(sym_part(F, 1.0), lambda, mu));
    }
    static SH_INLINE Mat3L differential(const Mat3L&, const State&, const Mat3L& dF, Lanes lambda, Lanes mu) {
        return full(isotropic_law(sym_part(dF, 0.0), lambda, mu));
    }
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        return isotropic_energy(sym_part(F, 1.0), lambda, mu);
    }
};

/// St. Venant-Kirchhoff: E = (F^T F - I)/2, S = lambda tr(E) I + 2 mu E, P = F S.
struct StvkMaterial {
    struct State {
        Sym3L S;
    };
    static SH_INLINE Lanes jacobian(const Mat3L& F, const State&) { return det(F); }
    /// sym(A^T B) for the differential (A^T B + B^T A)/2 of F^T F / 2.
    static SH_INLINE Sym3L sym_tn(const Mat3L& a, const Mat3L& b) {
        auto dot = [&](int i, int j) { return a.m[0][i] * b.m[0][j] + a.m[1][i] * b.m[1][j] + a.m[2][i] * b.m[2][j]; };
        Sym3L r;
        for (int i = 0; i < 3; ++i) r.d[i] = dot(i, i);
        r.o[0] = 0.5 * (dot(0, 1) + dot(1, 0));
        r.o[1] = 0.5 * (dot(0, 2) + dot(2, 0));
        r.o[2] = 0.5 * (dot(1, 2) + dot(2, 1));
        return r;
    }
    static SH_INLINE Sym3L green_strain(const Mat3L& F) {
        auto dot = [&](int i, int j) { return F.m[0][i] * F.m[0][j] + F.m[1][i] * F.m[1][j] + F.m[2][i] * F.m[2][j]; };
        Sym3L E;
        for (int i = 0; i < 3; ++i) E.d[i] = 0.5 * dot(i, i) - 0.5;
        E.o[0] = 0.5 * dot(0, 1);
        E.o[1] = 0.5 * dot(0, 2);
        E.o[2] = 0.5 * dot(1, 2);
        return E;
    }
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State& state) {
        // S = 2 mu E + lambda tr(E) I with E = (C - I)/2, C = F^T F: S = mu (C - I) + lambda tr(E) I.
        auto dot = [&](int i, int j) { return F.m[0][i] * F.m[0][j] + F.m[1][i] * F.m[1][j] + F.m[2][i] * F.m[2][j]; };
        const Lanes c0 = dot(0, 0), c1 = dot(1, 1), c2 = dot(2, 2);
        const Lanes lt = lambda * (0.5 * ((c0 + c1) + c2) - 1.5);
        state.S.d[0] = mu * (c0 - 1.0) + lt;
        state.S.d[1] = mu * (c1 - 1.0) + lt;
        state.S.d[2] = mu * (c2 - 1.0) + lt;
        state.S.o[0] = mu * dot(0, 1);
        state.S.o[1] = mu * dot(0, 2);
        state.S.o[2] = mu * dot(1, 2);
        return mul_sym(F, state.S);
    }
    static SH_INLINE Mat3L differential(const Mat3L& F, const State& state, const Mat3L& dF, Lanes lambda, Lanes mu) {
        const Mat3L a = mul_sym(dF, state.S), b = mul_sym(F, isotropic_law(sym_tn(F, dF), lambda, mu));
        Mat3L r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][j] + b.m[i][j];
        return r;
    }
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        return isotropic_energy(green_strain(F), lambda, mu);
    }
};

/// Corotational linear elasticity: F = R S, eps = sym(R^T F) - I, P = R (2 mu eps + lambda tr(eps) I).
/// The differential holds R fixed (the usual corotational tangent).
struct CorotationalMaterial {
    struct State {
        Mat3L R;
    };
    static SH_INLINE Lanes jacobian(const Mat3L& F, const State&) { return det(F); }
    static SH_INLINE Mat3L rotated_stress(const Mat3L& R, const Mat3L& G, Lanes lambda, Lanes mu, bool subtract_identity) {
        const Sym3L eps = sym_part(mul_tn(R, G), subtract_identity ? 1.0 : 0.0);
        return mul_sym(R, isotropic_law(eps, lambda, mu));
    }
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State& state) {
        state.R = polar_rotation(F);
        return rotated_stress(state.R, F, lambda, mu, true);
    }
    static SH_INLINE Mat3L differential(const Mat3L&, const State& state, const Mat3L& dF, Lanes lambda, Lanes mu) {
        return rotated_stress(state.R, dF, lambda, mu, false);
    }
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        return isotropic_energy(sym_part(mul_tn(polar_rotation(F), F), 1.0), lambda, mu);
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
    static SH_INLINE Lanes jacobian(const Mat3L&, const State& state) { return state.j; }
    /// m, l and alpha; alpha only depends on the ratio mu/lambda, and lanes with lambda = mu = 0
    /// (block padding) get alpha = 1 so that they stay finite (and, having zero moduli, inert).
    static SH_INLINE void parameters(Lanes lambda, Lanes mu, Lanes& m, Lanes& l, Lanes& alpha) {
        m = (4.0 / 3.0) * mu;
        l = lambda + (5.0 / 6.0) * mu;
        alpha = select(l != 0.0, 1.0 + 0.75 * m / l, splat(1.0));
    }
    /// det F from its cofactor matrix (first row expansion).
    static SH_INLINE Lanes det_from_cofactor(const Mat3L& F, const Mat3L& cof) {
        return F.m[0][0] * cof.m[0][0] + F.m[0][1] * cof.m[0][1] + F.m[0][2] * cof.m[0][2];
    }
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State& state) {
        Lanes m, l, alpha;
        parameters(lambda, mu, m, l, alpha);
        state.ic = ddot(F, F);
        state.cof = cofactor(F);
        state.j = det_from_cofactor(F, state.cof);
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
        Mat3L r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][j] + b.m[i][j];
        return r;
    }
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        Lanes m, l, alpha;
        parameters(lambda, mu, m, l, alpha);
        // Written in H = F - I so that no O(lambda) constants cancel near rest:
        // Ic - 3 = 2 tr H + |H|^2, J - 1 = tr H + i2(H) + det H,
        // (J - a)^2 - (1 - a)^2 = (J - 1)(J - 1 + 2 (1 - a)).
        const Mat3L H = add_diagonal(F, splat(-1.0));
        const Lanes tr = trace(H), hh = ddot(H, H);
        Lanes h2 = Lanes{};  // tr(H H)
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) h2 += H.m[i][j] * H.m[j][i];
        const Lanes ic3 = 2.0 * tr + hh, j1 = tr + 0.5 * (tr * tr - h2) + det(H);
        Lanes logs;
        for (int k = 0; k < kLanes; ++k) logs[k] = std::log1p(0.25 * ic3[k]);
        return 0.5 * m * (ic3 - logs) + 0.5 * l * j1 * (j1 + 2.0 * (1.0 - alpha));
    }
};

/// Calls visit(material_tag, model) for each sh_material_model and its kernel tag type.
template <class Visit>
void for_each_material(Visit&& visit) {
    visit(LinearMaterial{}, SH_MATERIAL_LINEAR);
    visit(StvkMaterial{}, SH_MATERIAL_STVK);
    visit(CorotationalMaterial{}, SH_MATERIAL_COROTATIONAL);
    visit(NeoHookeanMaterial{}, SH_MATERIAL_NEOHOOKEAN);
}

}  // namespace sh
