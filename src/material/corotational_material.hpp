// Corotational linear elasticity, a row of the material table (material_table.hpp).
#pragma once

#include "material/isotropic_law.hpp"
#include "material/polar_decomposition.hpp"

#include <softhap/softhap.h>

namespace sh {

/// F = R S, eps = sym(R^T F) - I, P = R (2 mu eps + lambda tr(eps) I). The differential holds
/// R fixed (the usual corotational tangent).
struct CorotationalMaterial {
    /// Its sh_material_model.
    static constexpr sh_material_model kModel = SH_MATERIAL_COROTATIONAL;
    /// With R held fixed, dP/dF is a rotated isotropic tensor: positive semi-definite as it is.
    static constexpr bool kProjectTangent = false;
    /// Its state keeps the element's rotation R, which stress_at() and energy_at() take given.
    static constexpr bool kRotates = true;
    /// One element's tangent in a sparse solve's operations (the table's kTangentWork): R and a
    /// rotated constant dP/dF, about 0.19 us per tet where a solve takes 0.3 ns per operation.
    static constexpr double kTangentWork = 650.0;

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
    /// dP(F)[dF] with R fixed.
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
