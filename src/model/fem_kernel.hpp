// The explicit FEM force and energy loops over TetBlocks, one instantiation per material.
// Forces follow O'Brien (1999) in matrix form: F = Ds Bm, H = -V0 P(F) Bm^T, whose columns are
// the forces on nodes 1..3 and f0 = -(f1 + f2 + f3).
#pragma once

#include "model/tet_block.hpp"

#include <cstddef>

namespace sh {

/// Per-lane edge matrix [p1 - p0, p2 - p0, p3 - p0] of the block's tets for node array p.
SH_INLINE Mat3L gather_edges(const TetBlock& b, const double* p) {
    Mat3L d;
    for (int i = 0; i < 3; ++i) {
        Lanes p0;
        for (int l = 0; l < kLanes; ++l) p0[l] = p[3 * b.node[0][l] + i];
        for (int a = 1; a < 4; ++a) {
            Lanes pa;
            for (int l = 0; l < kLanes; ++l) pa[l] = p[3 * b.node[a][l] + i];
            d.m[i][a - 1] = pa - p0;
        }
    }
    return d;
}

/// Adds the elastic forces of blocks at positions x into f; when v is not null, adds the
/// stiffness-proportional damping force -beta K(x) v as well.
template <class Material>
void add_fem_forces(const TetBlock* blocks, size_t block_count, const double* x, const double* v, double beta,
                    double* f) {
    for (size_t k = 0; k < block_count; ++k) {
        const TetBlock& b = blocks[k];
        const Mat3L F = mul(gather_edges(b, x), b.Bm);
        typename Material::State state;
        Mat3L P = Material::stress(F, b.lambda, b.mu, state);
        if (v) {
            const Mat3L dF = mul(gather_edges(b, v), b.Bm);
            P = combine(splat(1.0), P, splat(beta), Material::differential(F, state, dF, b.lambda, b.mu));
        }
        const Mat3L H = mul_nt(P, b.Bm);
        const Lanes w = -b.volume;
        Lanes node_force[4][3];
        for (int i = 0; i < 3; ++i) {
            node_force[0][i] = Lanes{};
            for (int a = 1; a < 4; ++a) {
                node_force[a][i] = w * H.m[i][a - 1];
                node_force[0][i] -= node_force[a][i];
            }
        }
        for (int l = 0; l < kLanes; ++l)
            for (int a = 0; a < 4; ++a) {
                double* fa = f + 3 * b.node[a][l];
                for (int i = 0; i < 3; ++i) fa[i] += node_force[a][i][l];
            }
    }
}

/// Elastic energy of blocks at positions x (J).
template <class Material>
double fem_energy(const TetBlock* blocks, size_t block_count, const double* x) {
    Lanes sum = Lanes{};
    for (size_t k = 0; k < block_count; ++k) {
        const TetBlock& b = blocks[k];
        const Mat3L F = mul(gather_edges(b, x), b.Bm);
        sum += b.volume * Material::energy(F, b.lambda, b.mu);
    }
    return lane_sum(sum);
}

}  // namespace sh
