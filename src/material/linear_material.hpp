// Small-strain linear elasticity, a row of the material table (material_table.hpp).
#pragma once

#include "material/isotropic_law.hpp"

#include <softhap/softhap.h>

namespace sh {

/// eps = sym(F) - I, P = 2 mu eps + lambda tr(eps) I. Not rotation invariant.
struct LinearMaterial {
    /// Its sh_material_model.
    static constexpr sh_material_model kModel = SH_MATERIAL_LINEAR;
    /// dP/dF is the constant isotropic elasticity tensor: positive semi-definite as it is.
    static constexpr bool kProjectTangent = false;
    /// Its state keeps no rotation (see the table's kRotates).
    static constexpr bool kRotates = false;
    /// One element's tangent in a sparse solve's operations (the table's kTangentWork): a
    /// constant dP/dF, estimated as the corotational tangent (measured) without its rotation.
    /// A linear body's matrix does not change, so its steps seldom weigh it.
    static constexpr double kTangentWork = 500.0;

    /// Nothing of stress() is reused by differential().
    struct State {};
    /// det F (for the inverted-element count).
    static SH_INLINE Lanes jacobian(const Mat3L& F, const State&) { return det(F); }
    /// P(F).
    static SH_INLINE Mat3L stress(const Mat3L& F, Lanes lambda, Lanes mu, State&) {
        return full(isotropic_law(sym_part(F, 1.0), lambda, mu));
    }
    /// dP(F)[dF].
    static SH_INLINE Mat3L differential(const Mat3L&, const State&, const Mat3L& dF, Lanes lambda, Lanes mu) {
        return full(isotropic_law(sym_part(dF, 0.0), lambda, mu));
    }
    /// psi(F).
    static SH_INLINE Lanes energy(const Mat3L& F, Lanes lambda, Lanes mu) {
        return isotropic_energy(sym_part(F, 1.0), lambda, mu);
    }
};

}  // namespace sh
