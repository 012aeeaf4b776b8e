// The stress derivative dP/dF of an isotropic law, projected to positive semi-definite, from the
// law's analytic eigensystem (Smith, de Goes, Kim 2019, "Analytic eigensystems for isotropic
// distortion energies"; Teran et al. 2005, "Robust quasistatic finite elements and flesh
// simulation"). In F's singular frame (F = U diag(s) V^T) dP/dF falls apart into the
// stretches' 3x3 block and, for each pair of axes, a shear and a turn whose eigenvalues the law
// writes in closed form: no 9x9 matrix is formed, differentiated or decomposed numerically.
#pragma once

#include <Eigen/Core>

namespace sh {

/// dP/dF as a 9x9 matrix: row 3 i + j is dP_ij, column 3 k + l the direction dF_kl.
using StressDerivative = Eigen::Matrix<double, 9, 9>;

/// F's singular frame: orthonormal u, v and the signed singular values s with F = u diag(s)
/// v^T. With det F < 0 one of s is negative (u = r v keeps u's orientation v's, r a rotation).
struct SingularFrame {
    Eigen::Matrix3d u, v;
    Eigen::Vector3d s;
};

/// F's singular frame from its polar rotation r (F = r S, S symmetric, det r = +1): v and s
/// are S's eigenvectors and eigenvalues and u = r v. S is symmetric and about as large as F, so
/// its direct 3x3 eigensolve is accurate where one of F^T F (whose entries square F's) would
/// lose the small singular values, and it costs a fraction of an SVD's Jacobi sweeps.
SingularFrame singular_frame(const Eigen::Matrix3d& f, const Eigen::Matrix3d& r);

/// An isotropic law's dP/dF in its singular frame, from its energy psi(s) as a function of the
/// signed singular values s (psi_i = d psi / d s_i):
/// - stretch: the block d2 psi / ds_a ds_b of the modes u_a v_a^T;
/// - for pair k, the axes i < j other than k, the eigenvalues of its two modes:
///   shear[k], of (u_i v_j^T + u_j v_i^T) / sqrt 2, equals (psi_i - psi_j) / (s_i - s_j);
///   turn[k], of (u_i v_j^T - u_j v_i^T) / sqrt 2, equals (psi_i + psi_j) / (s_i + s_j).
/// Each law writes the quotients with the division carried out, so that they stay exact where
/// singular values meet (the rest shape, uniform compression).
struct PrincipalStiffness {
    Eigen::Matrix3d stretch;
    Eigen::Vector3d shear, turn;
};

/// dP/dF with its negative eigenvalues set to zero: the sum over the nine modes q of
/// max(eigenvalue, 0) q q^T, in the frame's basis. Exactly dP/dF where it is positive
/// semi-definite; the nearest positive semi-definite matrix elsewhere.
StressDerivative projected_stress_derivative(const PrincipalStiffness& stiffness, const SingularFrame& frame);

}  // namespace sh
