// Stable neo-Hookean elasticity (Smith, de Goes, Kim 2018), a row of the material table
// (material_table.hpp).
#pragma once

#include "material/isotropic_law.hpp"
#include "material/isotropic_projection.hpp"

#include <softhap/softhap.h>

#include <cmath>

namespace sh {

/// psi = m/2 (Ic - 3) + l/2 (J - a)^2 - m/2 log(Ic + 1) - psi(I), a = 1 + 3m/(4l),
/// with m = 4/3 mu and l = lambda + 5/6 mu so that small strains match linear elasticity.
struct NeoHookeanMaterial {
    /// Its sh_material_model.
    static constexpr sh_material_model kModel = SH_MATERIAL_NEOHOOKEAN;
    /// dP/dF is indefinite away from rest: projected per element.
    static constexpr bool kProjectTangent = true;
    /// Its state keeps no rotation (see the table's kRotates).
    static constexpr bool kRotates = false;
    /// One element's tangent in a sparse solve's operations (the table's kTangentWork): its
    /// singular frame, analytic eigensystem and projection, about 0.24 us per tet in a step
    /// under large rotation.
    static constexpr double kTangentWork = 800.0;

    /// dP/dF's eigensystem at F's signed singular values s (see PrincipalStiffnessLanes). In
    /// s, Ic = |s|^2 and J = s0 s1 s2, so psi_i = m' s_i + l (J - a) J_i with
    /// m' = m (1 - 1/(Ic + 1)) and J_i = J / s_i the product of the other two.
    static SH_INLINE PrincipalStiffnessLanes principal_stiffness(const Lanes (&s)[3], Lanes lambda, Lanes mu) {
        Lanes m, l, alpha;
        parameters(lambda, mu, m, l, alpha);
        const Lanes inv = 1.0 / (s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + 1.0);
        const Lanes m1 = m * (1.0 - inv), dm1 = 2.0 * m * inv * inv;  // dm'/ds_i = dm1 s_i
        const Lanes pressure = l * (s[0] * s[1] * s[2] - alpha);
        PrincipalStiffnessLanes k;
        for (int a = 0; a < 3; ++a) {
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            k.stretch[a][a] = m1 + dm1 * s[a] * s[a] + l * s[b] * s[b] * s[c] * s[c];
            // d psi_b / d s_c = dm1 s_b s_c + l J_b J_c + l (J - a) s_a.
            k.stretch[b][c] = k.stretch[c][b] = dm1 * s[b] * s[c] + l * s[b] * s[c] * s[a] * s[a] + pressure * s[a];
            // psi_b -+ psi_c = m' (s_b -+ s_c) -+ l (J - a) s_a (s_b -+ s_c).
            k.shear[a] = m1 - pressure * s[a];
            k.turn[a] = m1 + pressure * s[a];
        }
        return k;
    }

    /// Cofactor matrix, Ic = |F|^2 and J = det F, reused by differential().
    struct State {
        Mat3L cof;
        Lanes ic, j;
    };
    /// det F, as stress() computed it.
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
    /// P(F); keeps cof F, Ic and J in state.
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State& state) {
        Lanes m, l, alpha;
        parameters(lambda, mu, m, l, alpha);
        state.ic = ddot(F, F);
        state.cof = cofactor(F);
        state.j = det_from_cofactor(F, state.cof);
        return combine(m * (1.0 - 1.0 / (state.ic + 1.0)), F, l * (state.j - alpha), state.cof);
    }
    /// dP(F)[dF].
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
    /// q - log(1 + q) per lane for q > -1, to round-off relative to itself: near q = 0 the
    /// difference is q^2/2 while each term is q, so it is summed as a series in u = q / (2 + q),
    /// where log(1 + q) = 2 atanh(u) and q = 2u / (1 - u): q - log(1 + q) = 2u^2 / (1 - u) -
    /// 2 sum_k u^(2k+1) / (2k+1), k >= 1, whose terms fall by u^2 < 0.02 each for |q| < 1/4.
    /// The series runs on all lanes at once; lanes outside that range (strong strains) take
    /// the difference itself, one at a time.
    static SH_INLINE Lanes q_minus_log1p(Lanes q) {
        const Lanes u = q / (2.0 + q), u2 = u * u;
        Lanes series = Lanes{};
        for (int k = 12; k >= 1; --k) series = u2 * (1.0 / (2 * k + 1) + series);
        Lanes out = 2.0 * u2 / (1.0 - u) - 2.0 * u * series;
        const LaneMask far = !(abs_lane(q) < 0.25);
        if (any_lane(far))
            for (int k = 0; k < kLanes; ++k)
                if (far[k]) out[k] = q[k] - std::log1p(q[k]);
        return out;
    }
    /// psi(F).
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        Lanes m, l, alpha;
        parameters(lambda, mu, m, l, alpha);
        // Written in the Green strain E = (H + H^T + H^T H) / 2, H = F - I, with the terms of
        // first order in it cancelled by hand, so that psi's round-off is relative to psi
        // itself, near rest and turned alike (a stiff body at rest otherwise carries energy
        // noise of O(mu eps) per element, far above the implicit step's estimate). With
        // l (1 - a) = -3m/4, psi = m/2 (q - log(1 + q)) + 3m/4 (2q - j1) + l/2 j1^2, where
        // q = (Ic - 3)/4 = tr E / 2 and j1 = J - 1. From J^2 = det(I + 2E) =
        // 1 + 2 tr E + 2 (tr^2 E - tr E^2) + 8 det E, both j1 = (J^2 - 1)/(J + 1) and
        // 2q - j1 = (tr E j1 - 2 (tr^2 E - tr E^2) - 8 det E)/(J + 1) are products of small
        // quantities; an element inverted past J = -1/2, whose energy is large, takes them
        // directly.
        const Mat3L H = add_diagonal(F, splat(-1.0));
        Mat3L E;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                E.m[i][j] = 0.5 * (H.m[i][j] + H.m[j][i] + H.m[0][i] * H.m[0][j] + H.m[1][i] * H.m[1][j] + H.m[2][i] * H.m[2][j]);
        const Lanes tr = trace(E), second_invariant = tr * tr - ddot(E, E), third = 8.0 * det(E);
        const Lanes J = det(F), plus = J + 1.0;
        const LaneMask near_rest = plus > 0.5;
        const Lanes safe = select(near_rest, plus, splat(1.0));
        const Lanes j1 = select(near_rest, (2.0 * tr + 2.0 * second_invariant + third) / safe, J - 1.0);
        const Lanes second = select(near_rest, (tr * j1 - 2.0 * second_invariant - third) / safe, tr - j1);
        return 0.5 * m * q_minus_log1p(0.5 * tr) + 0.75 * m * second + 0.5 * l * j1 * j1;
    }
};

}  // namespace sh
