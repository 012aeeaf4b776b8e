// Corotational linear elasticity, a row of the material table (material_table.hpp).
#pragma once

#include "material/isotropic_law.hpp"
#include "material/isotropic_projection.hpp"
#include "material/polar_decomposition.hpp"

#include <softhap/softhap.h>

namespace sh {

/// F = R S, eps = sym(R^T F) - I, P = R (2 mu eps + lambda tr(eps) I). In F's signed singular
/// values s, psi = mu |s - 1|^2 + lambda/2 (sum s - 3)^2.
struct CorotationalMaterial {
    /// Its sh_material_model.
    static constexpr sh_material_model kModel = SH_MATERIAL_COROTATIONAL;
    /// The tangent stiffness is the exact dP/dF, with R's own change, projected: where R
    /// turns, a stretched element resists turning further (the geometric stiffness that
    /// holding R fixed leaves out), and a compressed one's turn modes are negative. Without
    /// the first, the implicit step of a fast-turning body overshoots its turns and iterates
    /// towards its minimiser at a linear rate (the raptor's swing refactorised 24 times in 30
    /// steps). differential() still holds R fixed: positive semi-definite, so that the
    /// stiffness-proportional damping it serves only dissipates.
    static constexpr bool kProjectTangent = true;
    /// Its state keeps the element's rotation R, which stress_at() and energy_at() take given.
    static constexpr bool kRotates = true;
    /// One element's tangent in a sparse solve's operations (the table's kTangentWork): its
    /// singular frame (R warm-started from the last force pass) and projection.
    static constexpr double kTangentWork = 750.0;

    /// dP/dF's eigensystem at F's signed singular values s (see PrincipalStiffnessLanes):
    /// psi_i = 2 mu (s_i - 1) + lambda (sum s - 3), so the stretches' block is
    /// 2 mu I + lambda 1 1^T, every shear mode 2 mu, and the turn mode of axes b, c
    /// (psi_b + psi_c) / (s_b + s_c) = 2 mu + (2 lambda (sum s - 3) - 4 mu) / (s_b + s_c). As a
    /// pair's stretches cancel (an element flattened or inverted across them) that grows
    /// without bound, negative (which projecting drops) or, where the third axis is stretched
    /// past about 3 + 2 mu / lambda, positive: the sum is taken as at least kTurnFloor of the
    /// largest stretch there, so that one degenerate element cannot make the matrix
    /// arbitrarily stiff (nor its round-off estimate, which the diagonal sets).
    static SH_INLINE PrincipalStiffnessLanes principal_stiffness(const Lanes (&s)[3], Lanes lambda, Lanes mu) {
        const Lanes volumetric = 2.0 * lambda * (s[0] + s[1] + s[2] - 3.0) - 4.0 * mu;
        const Lanes size = max_lane(max_lane(abs_lane(s[0]), abs_lane(s[1])), abs_lane(s[2]));
        const Lanes floor = select(size > 0.0, kTurnFloor * size, splat(kTurnFloor));
        PrincipalStiffnessLanes k;
        for (int a = 0; a < 3; ++a) {
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            k.stretch[a][a] = 2.0 * mu + lambda;
            k.stretch[b][c] = k.stretch[c][b] = lambda;
            k.shear[a] = 2.0 * mu;
            const Lanes sum = s[b] + s[c];
            k.turn[a] = 2.0 * mu + volumetric / select(sum > floor, sum, floor);
        }
        return k;
    }
    /// The least stretch sum of a pair that principal_stiffness divides by, relative to the
    /// largest stretch: the turn stiffness stays below about 2000 (lambda + mu) there.
    static constexpr double kTurnFloor = 1e-3;

    /// The polar rotation, reused by differential().
    struct State {
        Mat3L R;
    };
    /// det F (for the inverted-element count).
    static SH_INLINE Lanes jacobian(const Mat3L& F, const State&) { return det(F); }
    /// R (2 mu eps + lambda tr(eps) I) with eps = sym(R^T G) (- I if subtract_identity).
    static SH_INLINE Mat3L rotated_stress(const Mat3L& R, const Mat3L& G, Lanes lambda, Lanes mu, bool subtract_identity) {
        const Sym3L eps = sym_part(mul_tn(R, G), subtract_identity ? 1.0 : 0.0);
        return mul_sym(R, isotropic_law(eps, lambda, mu));
    }
    /// P(F); keeps R in state.
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State& state) {
        return stress_at(F, polar_rotation(F), lambda, mu, state);
    }
    /// P(F) with R, F's polar rotation, already found (a caller that keeps each element's R
    /// refines the last one: fem_kernel.hpp's kept_rotation); keeps R in state.
    static SH_INLINE Mat3L stress_at(const Mat3L& F, const Mat3L& R, Lanes lambda, Lanes mu, State& state) {
        state.R = R;
        return rotated_stress(R, F, lambda, mu, true);
    }
    /// dP(F)[dF] with R fixed (the stiffness-proportional damping's: see kProjectTangent).
    static SH_INLINE Mat3L differential(const Mat3L&, const State& state, const Mat3L& dF, Lanes lambda, Lanes mu) {
        return rotated_stress(state.R, dF, lambda, mu, false);
    }
    /// psi(F).
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) { return energy_at(F, polar_rotation(F), lambda, mu); }
    /// psi(F) with R, F's polar rotation, already found.
    static SH_INLINE Lanes energy_at(const Mat3L& F, const Mat3L& R, Lanes lambda, Lanes mu) {
        return isotropic_energy(sym_part(mul_tn(R, F), 1.0), lambda, mu);
    }
};

}  // namespace sh
