// Symmetric 3x3 tensors per lane and the linear isotropic law on them: the pieces the
// constitutive laws of tetrahedral elements (material_table.hpp) are written with. The
// formulas work on symmetric tensors (strain, second Piola stress) so that the hot loops
// compute each unique entry once.
#pragma once

#include "material/lanes.hpp"

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

}  // namespace sh
