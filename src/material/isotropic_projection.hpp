// The stress derivative dP/dF of an isotropic law, projected to positive semi-definite, from the
// law's analytic eigensystem (Smith, de Goes, Kim 2019, "Analytic eigensystems for isotropic
// distortion energies"; Teran et al. 2005, "Robust quasistatic finite elements and flesh
// simulation"). In F's singular frame (F = U diag(s) V^T) dP/dF falls apart into the
// stretches' 3x3 block and, for each pair of axes, a shear and a turn whose eigenvalues the law
// writes in closed form: no 9x9 matrix is differentiated or decomposed numerically. Everything
// runs on kLanes elements at once, as the element loops do.
#pragma once

#include "material/lanes.hpp"

namespace sh {

/// dP/dF per lane: c[p][q] = dP_p / dF_q with p, q = 3 i + j.
struct StressDerivativeLanes {
    Lanes c[9][9];
};

/// F's singular frame per lane: orthonormal u, v and the signed singular values s with
/// F = u diag(s) v^T. Where det F < 0 one of s is negative (u = r v with r a rotation).
struct SingularFrameLanes {
    Mat3L u, v;
    Lanes s[3];
};

/// F's singular frames, to round-off of |F|. Where every lane's F is well-conditioned (det F > 0,
/// singular values within a factor of about 3) from F^T F: v its eigenvectors (cyclic Jacobi)
/// and u = F v / s made orthonormal. Elsewhere from F's polar rotations r (F = r S, S symmetric,
/// det r = +1): v and s are S's eigenvectors and eigenvalues and u = r v; S is about as large as
/// F, so its eigenvalues are as accurate as F's entries, where those of F^T F (which square F's)
/// would lose the small singular values. near, if not null, holds rotations close to r (an
/// earlier pass's) to start the polar iteration from.
SingularFrameLanes singular_frames(const Mat3L& F, const Mat3L* near = nullptr);

/// singular_frames of two batches at once (near[n]: as near there, per batch): the same frames,
/// sooner, as the eigen-solves' turns of one batch run while the other's wait (a batch's turns
/// are a chain of square roots and divisions; the polar iterations still run one after the
/// other). Measured on 2,048 batches of strains up to 5 %: 0.9 of the time of two calls.
void singular_frame_pair(const Mat3L (&F)[2], const Mat3L* const (&near)[2], SingularFrameLanes (&out)[2]);

/// An isotropic law's dP/dF in its singular frame per lane, from its energy psi(s) as a
/// function of the signed singular values s (psi_i = d psi / d s_i):
/// - stretch: the block d2 psi / ds_a ds_b of the modes u_a v_a^T;
/// - for pair k, the axes i < j other than k, the eigenvalues of its two modes:
///   shear[k], of (u_i v_j^T + u_j v_i^T) / sqrt 2, equals (psi_i - psi_j) / (s_i - s_j);
///   turn[k], of (u_i v_j^T - u_j v_i^T) / sqrt 2, equals (psi_i + psi_j) / (s_i + s_j).
/// Each law writes the quotients with the division carried out, so that they stay exact where
/// singular values meet (the rest shape, uniform compression).
struct PrincipalStiffnessLanes {
    Lanes stretch[3][3];
    Lanes shear[3], turn[3];
};

/// stiffness with its negative eigenvalues set to zero, per lane: the stretch block projected to
/// positive semi-definite where it is not positive definite, shear and turn clamped at zero.
/// With the frame's modes these give the projected dP/dF, the sum over the nine modes q of
/// max(eigenvalue, 0) q q^T: exactly dP/dF where it is positive semi-definite, the nearest
/// positive semi-definite matrix elsewhere. The element stiffness contracts them with its own
/// map without forming dP/dF (model/element_stiffness.hpp: modal_element_stiffness).
PrincipalStiffnessLanes projected_principal_stiffness(const PrincipalStiffnessLanes& stiffness);

}  // namespace sh
