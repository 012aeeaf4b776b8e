#include "model/element_stiffness.hpp"

namespace sh {

void element_stiffness(const StressDerivativeLanes& C, const Lanes (&g)[3][3], StiffnessLanes& K) {
    for (int b = 1; b < 4; ++b) {
        Lanes cg[9][3];  // cg[q][l] = sum_m C(q, (l, m)) g_b[m]
        for (int q = 0; q < 9; ++q)
            for (int l = 0; l < 3; ++l)
                cg[q][l] = C.c[q][3 * l] * g[b - 1][0] + C.c[q][3 * l + 1] * g[b - 1][1] + C.c[q][3 * l + 2] * g[b - 1][2];
        for (int a = 1; a <= b; ++a)
            for (int k = 0; k < 3; ++k)
                for (int l = 0; l < 3; ++l)
                    K.block[a][b][k][l] = K.block[b][a][l][k] =
                        g[a - 1][0] * cg[3 * k][l] + g[a - 1][1] * cg[3 * k + 1][l] + g[a - 1][2] * cg[3 * k + 2][l];
    }
}

// Mode Q (a 3x3 matrix) moves node a's force by Q g_a. With h_a = V^T g_a, the stretch mode
// u_c v_c^T gives u_c h_ac and pair (i, j)'s shear and turn (u_i v_j^T +- u_j v_i^T) / sqrt 2
// give (u_i h_aj +- u_j h_ai) / sqrt 2. So K_ab = U M_ab U^T with, for P_cd = h_ac h_bd and
// A = (shear + turn) / 2, B = (shear - turn) / 2 of the pair of axes c != d:
//   M_ab[c][c] = stretch_cc P_cc + sum over d != c of A_cd P_dd,
//   M_ab[c][d] = stretch_cd P_cd + B_cd P_dc.
void modal_element_stiffness(const PrincipalStiffnessLanes& k, const SingularFrameLanes& frame,
                             const Lanes (&g)[3][3], StiffnessLanes& K) {
    Lanes h[3][3];  // h[a][c] = v_c . g_(a+1)
    for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c)
            h[a][c] = g[a][0] * frame.v.m[0][c] + g[a][1] * frame.v.m[1][c] + g[a][2] * frame.v.m[2][c];
    Lanes A[3], B[3];  // per pair, named by the axis it leaves out
    for (int m = 0; m < 3; ++m) {
        A[m] = 0.5 * (k.shear[m] + k.turn[m]);
        B[m] = 0.5 * (k.shear[m] - k.turn[m]);
    }
    for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b) {
            Lanes P[3][3], M[3][3];
            for (int c = 0; c < 3; ++c)
                for (int d = 0; d < 3; ++d) P[c][d] = h[a][c] * h[b][d];
            for (int c = 0; c < 3; ++c) {
                const int d1 = (c + 1) % 3, d2 = (c + 2) % 3;
                M[c][c] = k.stretch[c][c] * P[c][c] + A[d1] * P[d2][d2] + A[d2] * P[d1][d1];
                for (int d = 0; d < 3; ++d)
                    if (d != c) M[c][d] = k.stretch[c][d] * P[c][d] + B[3 - c - d] * P[d][c];
            }
            Lanes UM[3][3];
            for (int i = 0; i < 3; ++i)
                for (int d = 0; d < 3; ++d)
                    UM[i][d] = frame.u.m[i][0] * M[0][d] + frame.u.m[i][1] * M[1][d] + frame.u.m[i][2] * M[2][d];
            for (int i = 0; i < 3; ++i)
                for (int l = 0; l < 3; ++l)
                    K.block[a + 1][b + 1][i][l] = K.block[b + 1][a + 1][l][i] =
                        UM[i][0] * frame.u.m[l][0] + UM[i][1] * frame.u.m[l][1] + UM[i][2] * frame.u.m[l][2];
        }
}

void complete_node_zero(StiffnessLanes& K) {
    for (int b = 1; b < 4; ++b)
        for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l)
                K.block[0][b][k][l] = K.block[b][0][l][k] =
                    -(K.block[1][b][k][l] + K.block[2][b][k][l] + K.block[3][b][k][l]);
    for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l)
            K.block[0][0][k][l] = -(K.block[0][1][k][l] + K.block[0][2][k][l] + K.block[0][3][k][l]);
}

}  // namespace sh
