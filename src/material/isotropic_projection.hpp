// The projection of an isotropic material's stress derivative dP/dF to positive
// semi-definite, in the frame of F's singular value decomposition, where it falls apart into a
// 3x3 and three 2x2 blocks (Teran et al. 2005, "Robust quasistatic finite elements and flesh
// simulation"; Smith et al. 2019, "Analytic eigensystems for isotropic distortion energies").
#pragma once

#include <Eigen/Core>

namespace sh {

/// dP/dF as a 9x9 matrix: row 3 i + j is dP_ij, column 3 k + l the direction dF_kl.
using StressDerivative = Eigen::Matrix<double, 9, 9>;

/// Replaces c, the symmetric dP/dF of an isotropic law at F, by its projection onto the
/// positive semi-definite matrices (its negative eigenvalues set to zero). With F = U S V^T,
/// the basis u_k v_l^T turns c block diagonal: the stretches u_k v_k^T couple among themselves
/// (a 3x3 block) and each pair u_k v_l^T, u_l v_k^T (k < l) in a 2x2 block, whatever the
/// singular values (their sign symmetries forbid the other couplings). So the eigenpairs come
/// from a 3x3 and three 2x2 problems, and each negative one is removed by a rank-one update:
/// a fraction of a 9x9 eigensolve's cost. Returns the number of eigenvalues removed.
int project_isotropic_tangent(StressDerivative& c, const Eigen::Matrix3d& f);

}  // namespace sh
