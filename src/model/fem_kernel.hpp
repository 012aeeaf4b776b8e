// The explicit FEM force and energy loops over TetBlocks, one instantiation per material.
// Forces follow O'Brien (1999) in matrix form: F = Ds Bm, H = -V0 P(F) Bm^T, whose columns are
// the forces on nodes 1..3 and f0 = -(f1 + f2 + f3). The blocks carry -V0 lambda and -V0 mu,
// so Material::stress directly returns -V0 P (see TetBlock).
//
// Node data (x, v, f) is 3 doubles per node. With AVX-512 a node's xyz is read, and its force
// added, with one masked 256-bit load (and store) per node and lane, the kLanes rows being
// transposed in registers (edges are formed on the rows, before the transpose). Zen 4 does not forward a masked store to a later load of the same
// node, so tets of one block that share a node would stall on each other: FemBody::adopt
// puts tets far apart along its locality curve into the lanes of a block, and the next
// block's updates of the same nodes come after the stores have retired. Elsewhere the lanes
// are filled and drained one double at a time.
#pragma once

#include "material/polar_decomposition.hpp"
#include "model/tet_block.hpp"

#include <cstddef>

namespace sh {

#if defined(__AVX512F__)

/// Per-lane edge matrix [p1 - p0, p2 - p0, p3 - p0] of the block's tets for node array p.
/// Rows (x, y, z, 0) are read with one masked load per node (never touching the double after
/// z), the edges are formed row by row, and the rows of each edge are transposed to lanes.
SH_INLINE Mat3L gather_edges(const TetBlock& b, const double* p) {
    static_assert(kLanes == 8, "AVX-512 path assumes 8 double lanes");
    auto row = [&](int a, int l) { return _mm256_maskz_loadu_pd(0x7, p + 3 * static_cast<ptrdiff_t>(b.node[a][l])); };
    __m256d r0[8];
    for (int l = 0; l < 8; ++l) r0[l] = row(0, l);
    Mat3L d;
    for (int a = 1; a < 4; ++a) {
        __m256d e[8];
        for (int l = 0; l < 8; ++l) e[l] = _mm256_sub_pd(row(a, l), r0[l]);
        const __m512d a0 = _mm512_insertf64x4(_mm512_castpd256_pd512(e[0]), e[2], 1);
        const __m512d a1 = _mm512_insertf64x4(_mm512_castpd256_pd512(e[1]), e[3], 1);
        const __m512d a2 = _mm512_insertf64x4(_mm512_castpd256_pd512(e[4]), e[6], 1);
        const __m512d a3 = _mm512_insertf64x4(_mm512_castpd256_pd512(e[5]), e[7], 1);
        const __m512d t0 = _mm512_unpacklo_pd(a0, a1);  // x0 x1 | z0 z1 | x2 x3 | z2 z3
        const __m512d t1 = _mm512_unpackhi_pd(a0, a1);  // y0 y1 | 0  0  | y2 y3 | 0  0
        const __m512d t2 = _mm512_unpacklo_pd(a2, a3);  // x4 x5 | z4 z5 | x6 x7 | z6 z7
        const __m512d t3 = _mm512_unpackhi_pd(a2, a3);  // y4 y5 | 0  0  | y6 y7 | 0  0
        d.m[0][a - 1] = _mm512_shuffle_f64x2(t0, t2, 0x88);
        d.m[1][a - 1] = _mm512_shuffle_f64x2(t1, t3, 0x88);
        d.m[2][a - 1] = _mm512_shuffle_f64x2(t0, t2, 0xDD);
    }
    return d;
}

/// f[3 n + i] += (x, y, z)_i of lane l for the nodes n = idx[l], in lane order (lanes may
/// share a node). Subtract: f -= instead.
template <bool Subtract>
SH_INLINE void scatter_add_xyz(double* f, const int32_t* idx, Lanes x, Lanes y, Lanes z) {
    const __m512d t0 = _mm512_unpacklo_pd(x, y);  // x0 y0 | x2 y2 | x4 y4 | x6 y6
    const __m512d t1 = _mm512_unpackhi_pd(x, y);  // x1 y1 | x3 y3 | x5 y5 | x7 y7
    // Two rows (x, y, z, pad) per register: indices 0-7 pick from t, 8-15 from z.
    const __m512d r02 = _mm512_permutex2var_pd(t0, _mm512_set_epi64(10, 10, 3, 2, 8, 8, 1, 0), z);
    const __m512d r46 = _mm512_permutex2var_pd(t0, _mm512_set_epi64(14, 14, 7, 6, 12, 12, 5, 4), z);
    const __m512d r13 = _mm512_permutex2var_pd(t1, _mm512_set_epi64(11, 11, 3, 2, 9, 9, 1, 0), z);
    const __m512d r57 = _mm512_permutex2var_pd(t1, _mm512_set_epi64(15, 15, 7, 6, 13, 13, 5, 4), z);
    const __m256d rows[8] = {_mm512_castpd512_pd256(r02), _mm512_castpd512_pd256(r13),
                             _mm512_extractf64x4_pd(r02, 1), _mm512_extractf64x4_pd(r13, 1),
                             _mm512_castpd512_pd256(r46), _mm512_castpd512_pd256(r57),
                             _mm512_extractf64x4_pd(r46, 1), _mm512_extractf64x4_pd(r57, 1)};
    for (int l = 0; l < 8; ++l) {
        double* q = f + 3 * static_cast<ptrdiff_t>(idx[l]);
        const __m256d old = _mm256_maskz_loadu_pd(0x7, q);  // never touches the double after z
        _mm256_mask_storeu_pd(q, 0x7, Subtract ? _mm256_sub_pd(old, rows[l]) : _mm256_add_pd(old, rows[l]));
    }
}

/// Lanes with det <= 0 among those with weight != 0 (a NaN det is not counted).
SH_INLINE int32_t count_non_positive(Lanes det, Lanes weight) {
    const __m512d zero = _mm512_setzero_pd();
    const __mmask8 m = _mm512_cmp_pd_mask(det, zero, _CMP_LE_OQ) & _mm512_cmp_pd_mask(weight, zero, _CMP_NEQ_UQ);
    return __builtin_popcount(static_cast<unsigned>(m));
}

#else

SH_INLINE void gather_xyz(const double* p, const int32_t* idx, Lanes& x, Lanes& y, Lanes& z) {
    for (int l = 0; l < kLanes; ++l) {
        const double* q = p + 3 * static_cast<ptrdiff_t>(idx[l]);
        x[l] = q[0];
        y[l] = q[1];
        z[l] = q[2];
    }
}

template <bool Subtract>
SH_INLINE void scatter_add_xyz(double* f, const int32_t* idx, Lanes x, Lanes y, Lanes z) {
    // Staged through an array: GCC 12's vectoriser miscompiled a loop that read the vector
    // lanes straight into f (zero forces at -O3).
    double staged[3][kLanes];
    for (int l = 0; l < kLanes; ++l) {
        staged[0][l] = x[l];
        staged[1][l] = y[l];
        staged[2][l] = z[l];
    }
    for (int l = 0; l < kLanes; ++l) {
        double* q = f + 3 * static_cast<ptrdiff_t>(idx[l]);
        for (int i = 0; i < 3; ++i) q[i] = Subtract ? q[i] - staged[i][l] : q[i] + staged[i][l];
    }
}

SH_INLINE int32_t count_non_positive(Lanes det, Lanes weight) {
    int32_t n = 0;
    for (int l = 0; l < kLanes; ++l) n += det[l] <= 0.0 && weight[l] != 0.0;
    return n;
}

/// Per-lane edge matrix [p1 - p0, p2 - p0, p3 - p0] of the block's tets for node array p.
SH_INLINE Mat3L gather_edges(const TetBlock& b, const double* p) {
    Lanes p0[3], pa[3];
    gather_xyz(p, b.node[0], p0[0], p0[1], p0[2]);
    Mat3L d;
    for (int a = 1; a < 4; ++a) {
        gather_xyz(p, b.node[a], pa[0], pa[1], pa[2]);
        for (int i = 0; i < 3; ++i) d.m[i][a - 1] = pa[i] - p0[i];
    }
    return d;
}

#endif

/// Rotations an element loop keeps per block between passes, for laws whose state holds one
/// (the material table's kRotates; other laws ignore it): block k's rotations are found from
/// near[k] (a warm start: the last pass's, or the ones fem_rotations gave), and written to
/// kept[k], each to within settled2 (polar_rotation_near). near and kept may be the same
/// array. near null: found from F alone, and written to kept unless it is null too.
struct KeptRotations {
    const Mat3L* near = nullptr;
    Mat3L* kept = nullptr;
    double settled2 = kRotationSettled2;
};

/// Block k's rotations at F: from rotations.near[k] when there is a warm start (to
/// rotations.settled2), else from F alone; written to rotations.kept[k].
SH_INLINE Mat3L kept_rotation(const Mat3L& F, size_t k, const KeptRotations& rotations) {
    const Mat3L R = rotations.near ? polar_rotation_near(F, rotations.near[k], rotations.settled2) : polar_rotation(F);
    rotations.kept[k] = R;
    return R;
}

/// Block k's -V0 P(F) (the weights carry -V0); a law that keeps a rotation takes it from
/// kept_rotation where the caller keeps them.
template <class Material>
SH_INLINE Mat3L block_stress(const Mat3L& F, const TetBlock& b, size_t k, const KeptRotations& rotations,
                             typename Material::State& state) {
    if constexpr (Material::kRotates)
        if (rotations.kept) return Material::stress_at(F, kept_rotation(F, k, rotations), b.lambda_w, b.mu_w, state);
    return Material::stress(F, b.lambda_w, b.mu_w, state);
}

/// Block k's -V0 psi(F), its rotation kept as block_stress keeps it.
template <class Material>
SH_INLINE Lanes block_energy(const Mat3L& F, const TetBlock& b, size_t k, const KeptRotations& rotations) {
    if constexpr (Material::kRotates)
        if (rotations.kept) return Material::energy_at(F, kept_rotation(F, k, rotations), b.lambda_w, b.mu_w);
    return Material::energy(F, b.lambda_w, b.mu_w);
}

/// -V0 psi(F) of a block whose stress state is known (a law that keeps a rotation takes it
/// from the state, where block_stress put it).
template <class Material>
SH_INLINE Lanes state_energy(const Mat3L& F, const TetBlock& b, const typename Material::State& state) {
    if constexpr (Material::kRotates) return Material::energy_at(F, state.R, b.lambda_w, b.mu_w);
    else return Material::energy(F, b.lambda_w, b.mu_w);
}

/// Elastic energy of some elements and the size of the forces its round-off scales with.
struct EnergySum {
    double value = 0.0;  ///< J
    /// Sum over the elements of the Frobenius norm of their forces on nodes 1-3 (N); a node
    /// moved by dx changes an element's energy by its force there times dx, so rounding the
    /// positions to eps |x| leaves about eps |x| times this in value.
    double force_norm = 0.0;
};

/// The force loop; Damped adds -beta K(x) v through the material's differential; Energy adds
/// the elastic energy and force norms into *energy from the same F and stress state.
template <class Material, bool Damped, bool Energy>
int32_t add_fem_forces_loop(const TetBlock* blocks, size_t block_count, const double* x, const double* v,
                            double beta, double* f, const KeptRotations& rotations, EnergySum* energy) {
    int32_t inverted = 0;  // elements with det F <= 0 (unused lanes weigh 0)
    Lanes energy_sum = Lanes{}, force_norm = Lanes{};
    for (size_t k = 0; k < block_count; ++k) {
        const TetBlock& b = blocks[k];
        const Mat3L F = mul(gather_edges(b, x), b.Bm);
        typename Material::State state;
        Mat3L P = block_stress<Material>(F, b, k, rotations, state);  // -V0 P
        inverted += count_non_positive(Material::jacobian(F, state), b.mu_w);
        if constexpr (Energy) energy_sum -= state_energy<Material>(F, b, state);  // the weights carry -V0
        if (Damped) {
            const Mat3L dF = mul(gather_edges(b, v), b.Bm);
            const Mat3L dP = Material::differential(F, state, dF, b.lambda_w, b.mu_w);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) P.m[i][j] += beta * dP.m[i][j];
        }
        const Mat3L H = mul_nt(P, b.Bm);  // column a-1: force on node a
        if constexpr (Energy) force_norm += lanes_sqrt(ddot(H, H));
        for (int a = 1; a < 4; ++a) scatter_add_xyz<false>(f, b.node[a], H.m[0][a - 1], H.m[1][a - 1], H.m[2][a - 1]);
        // f0 = -(f1 + f2 + f3)
        scatter_add_xyz<true>(f, b.node[0], H.m[0][0] + H.m[0][1] + H.m[0][2], H.m[1][0] + H.m[1][1] + H.m[1][2],
                              H.m[2][0] + H.m[2][1] + H.m[2][2]);
    }
    if constexpr (Energy) {
        energy->value += lane_sum(energy_sum);
        energy->force_norm += lane_sum(force_norm);
    }
    return inverted;
}

/// Adds the elastic forces of blocks at positions x into f; when v is not null, adds the
/// stiffness-proportional damping force -beta K(x) v as well. rotations: see KeptRotations.
/// Returns the number of elements with det F <= 0 (inverted or flat).
template <class Material>
int32_t add_fem_forces(const TetBlock* blocks, size_t block_count, const double* x, const double* v, double beta,
                       double* f, const KeptRotations& rotations = KeptRotations{}) {
    if (v) return add_fem_forces_loop<Material, true, false>(blocks, block_count, x, v, beta, f, rotations, nullptr);
    return add_fem_forces_loop<Material, false, false>(blocks, block_count, x, nullptr, 0.0, f, rotations, nullptr);
}

/// add_fem_forces without damping, adding the blocks' elastic energy and force norms into
/// *energy from the same pass: one gather, F and stress per element where fem_energy would
/// repeat them.
template <class Material>
int32_t add_fem_forces_and_energy(const TetBlock* blocks, size_t block_count, const double* x, double* f,
                                  const KeptRotations& rotations, EnergySum* energy) {
    return add_fem_forces_loop<Material, false, true>(blocks, block_count, x, nullptr, 0.0, f, rotations, energy);
}

/// The rotations of blocks' elements at positions x into out[k], found from F alone, for a
/// law that keeps them (kRotates; nothing otherwise): a later pass's warm start.
template <class Material>
void fem_rotations(const TetBlock* blocks, size_t block_count, const double* x, Mat3L* out) {
    if constexpr (Material::kRotates)
        for (size_t k = 0; k < block_count; ++k) out[k] = polar_rotation(mul(gather_edges(blocks[k], x), blocks[k].Bm));
}

/// Elastic energy of blocks at positions x (J). rotations: see KeptRotations.
template <class Material>
double fem_energy(const TetBlock* blocks, size_t block_count, const double* x,
                  const KeptRotations& rotations = KeptRotations{}) {
    Lanes sum = Lanes{};
    for (size_t k = 0; k < block_count; ++k) {
        const TetBlock& b = blocks[k];
        const Mat3L F = mul(gather_edges(b, x), b.Bm);
        sum -= block_energy<Material>(F, b, k, rotations);  // the weights carry -V0
    }
    return lane_sum(sum);
}

}  // namespace sh
