// One tetrahedron's tangent stiffness K_e = V0 G^T C G per lane, with C = dP/dF (9x9) and G the
// map from nodal displacements to F (dF_kj / dx_ak = g_a[j], g_a node a's shape-function
// gradient). Two routes: from C itself, for the laws whose dP/dF is formed entry by entry, and
// from C's modes in F's singular frame, for the laws whose projected eigensystem is analytic
// (material/isotropic_projection.hpp), which never forms C.
#pragma once

#include "material/isotropic_projection.hpp"

namespace sh {

/// One element's stiffness per lane, by 3x3 node blocks: block[a][b][k][l] = K((a, k), (b, l)).
struct StiffnessLanes {
    Lanes block[4][4][3][3];
};

/// K = G^T C G per lane (unit volume) for symmetric C and the shape-function gradients g[a - 1]
/// of nodes a = 1..3 (rows of the inverse rest edge matrix): the blocks of nodes 1..3, as
/// K((a, k), (b, l)) = sum_jm g_a[j] C((k, j), (l, m)) g_b[m]. Node 0's: complete_node_zero.
void element_stiffness(const StressDerivativeLanes& C, const Lanes (&g)[3][3], StiffnessLanes& K);

/// The same K for the C whose modes lie in frame (F = U diag(s) V^T) with eigenvalues k (as
/// projected_principal_stiffness gives them), without forming C: about two thirds of the
/// multiplications of element_stiffness after forming C. Node 0's blocks: complete_node_zero.
void modal_element_stiffness(const PrincipalStiffnessLanes& k, const SingularFrameLanes& frame,
                             const Lanes (&g)[3][3], StiffnessLanes& K);

/// Node 0's blocks from those of nodes 1..3: its shape-function gradient is -(g_1 + g_2 + g_3),
/// so its blocks are minus the sums of the others'.
void complete_node_zero(StiffnessLanes& K);

}  // namespace sh
