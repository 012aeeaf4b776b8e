// St. Venant-Kirchhoff elasticity, a row of the material table (material_table.hpp).
#pragma once

#include "material/isotropic_law.hpp"
#include "material/isotropic_projection.hpp"

#include <softhap/softhap.h>

namespace sh {

/// E = (F^T F - I)/2, S = lambda tr(E) I + 2 mu E, P = F S.
struct StvkMaterial {
    /// Its sh_material_model.
    static constexpr sh_material_model kModel = SH_MATERIAL_STVK;
    /// dP/dF loses definiteness under compression: projected per element.
    static constexpr bool kProjectTangent = true;
    /// Its state keeps no rotation (see the table's kRotates).
    static constexpr bool kRotates = false;
    /// One element's tangent in a sparse solve's operations (the table's kTangentWork): its
    /// singular frame, analytic eigensystem and projection, about 0.32 us per tet in a step
    /// under large rotation (more of its elements' stretch blocks project than neo-Hookean's).
    static constexpr double kTangentWork = 1050.0;

    /// dP/dF's eigensystem at F's signed singular values s (see PrincipalStiffnessLanes). In
    /// s, E_i = (s_i^2 - 1)/2 and psi_i = (2 mu E_i + lambda tr E) s_i.
    static SH_INLINE PrincipalStiffnessLanes principal_stiffness(const Lanes (&s)[3], Lanes lambda, Lanes mu) {
        const Lanes tr = 0.5 * (s[0] * s[0] + s[1] * s[1] + s[2] * s[2] - 3.0);
        PrincipalStiffnessLanes k;
        for (int a = 0; a < 3; ++a) {
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            k.stretch[a][a] = (2.0 * mu + lambda) * s[a] * s[a] + mu * (s[a] * s[a] - 1.0) + lambda * tr;
            k.stretch[b][c] = k.stretch[c][b] = lambda * s[b] * s[c];
            // psi_b -+ psi_c = (s_b -+ s_c) (mu (s_b^2 +- s_b s_c + s_c^2 - 1) + lambda tr E).
            const Lanes squares = s[b] * s[b] + s[c] * s[c] - 1.0;
            k.shear[a] = mu * (squares + s[b] * s[c]) + lambda * tr;
            k.turn[a] = mu * (squares - s[b] * s[c]) + lambda * tr;
        }
        return k;
    }

    /// The second Piola stress, reused by differential().
    struct State {
        Sym3L S;
    };
    /// det F (for the inverted-element count).
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
    /// Green-Lagrange strain E = (F^T F - I)/2.
    static SH_INLINE Sym3L green_strain(const Mat3L& F) {
        auto dot = [&](int i, int j) { return F.m[0][i] * F.m[0][j] + F.m[1][i] * F.m[1][j] + F.m[2][i] * F.m[2][j]; };
        Sym3L E;
        for (int i = 0; i < 3; ++i) E.d[i] = 0.5 * dot(i, i) - 0.5;
        E.o[0] = 0.5 * dot(0, 1);
        E.o[1] = 0.5 * dot(0, 2);
        E.o[2] = 0.5 * dot(1, 2);
        return E;
    }
    /// P(F); keeps S in state.
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
    /// dP(F)[dF] = dF S + F dS.
    static SH_INLINE Mat3L differential(const Mat3L& F, const State& state, const Mat3L& dF, Lanes lambda, Lanes mu) {
        const Mat3L a = mul_sym(dF, state.S), b = mul_sym(F, isotropic_law(sym_tn(F, dF), lambda, mu));
        Mat3L r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][j] + b.m[i][j];
        return r;
    }
    /// psi(F).
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        return isotropic_energy(green_strain(F), lambda, mu);
    }
};

}  // namespace sh
