// Tangent stiffness of FEM bodies for the implicit and static solvers:
// K_e = V0 G^T C G with C = dP/dF (9x9) and G the map from nodal displacements to F
// (dF_kj / dx_ak = g_a[j], g_a the shape-function gradients). For the laws whose C can be
// indefinite (kProjectTangent in the material table; all isotropic), C is formed already
// projected to positive semi-definite, from the law's analytic eigensystem in F's singular
// frame; for the others, from the law's differential on the unit basis of F.
#include "model/fem_body.hpp"

#include "material/material_params.hpp"
#include "material/isotropic_projection.hpp"
#include "material/material_table.hpp"
#include "linalg/sparse_system.hpp"
#include "model/fem_kernel.hpp"

#include <algorithm>

namespace sh {
namespace {

// One element's stiffness per lane, by 3x3 node blocks: block[a][b][k][l] = K((a, k), (b, l)).
struct StiffnessLanes {
    Lanes block[4][4][3][3];
};

// dP/dF per lane of a batch of elements of one material model (a law that does not project:
// see the material table), from its differential on the unit basis of F, symmetrised.
template <class Material>
void stress_derivatives(const Mat3L& F, Lanes lambda, Lanes mu, StressDerivativeLanes& C) {
    static_assert(!Material::kRotates, "a law that keeps a rotation projects its tangent");
    typename Material::State state;
    Material::stress(F, lambda, mu, state);
    for (int q = 0; q < 9; ++q) {
        Mat3L dF{};
        dF.m[q / 3][q % 3] = splat(1.0);
        const Mat3L dP = Material::differential(F, state, dF, lambda, mu);
        for (int p = 0; p < 9; ++p) C.c[p][q] = dP.m[p / 3][p % 3];
    }
    for (int p = 0; p < 9; ++p)
        for (int q = p + 1; q < 9; ++q) C.c[p][q] = C.c[q][p] = 0.5 * (C.c[p][q] + C.c[q][p]);
}

// dP/dF of a law that projects (all isotropic: see the material table's kProjectTangent) per
// lane, projected to positive semi-definite: from the law's analytic eigensystem in F's
// singular frame, whose polar rotation starts from near where the body keeps its elements'
// rotations (the last force pass's: see BlockRotations).
// count (1 or 2) batches at once: their frames are found together (singular_frame_pair).
template <class Material>
void law_projected_derivatives(int count, const Mat3L (&F)[2], const Lanes (&lambda)[2], const Lanes (&mu)[2],
                               const Mat3L* const (&near)[2], StressDerivativeLanes (&C)[2]) {
    SingularFrameLanes frame[2];
    if (count == 2) singular_frame_pair(F, near, frame);
    else frame[0] = singular_frames(F[0], near[0]);
    for (int n = 0; n < count; ++n)
        projected_stress_derivatives(Material::principal_stiffness(frame[n].s, lambda[n], mu[n]), frame[n], C[n]);
}

// K = V0 G^T C G per lane, for symmetric C and the shape-function gradients g[a - 1] of nodes
// a = 1..3 (rows of the inverse rest edge matrix): the blocks (a, b), 1 <= a <= b, from
// K((a, k), (b, l)) = V0 sum_jm g_a[j] C((k, j), (l, m)) g_b[m]; their mirror images below the
// diagonal; and node 0's, whose gradient is -(g_1 + g_2 + g_3), as minus the sums of the others.
void element_stiffness(const StressDerivativeLanes& C, const Lanes (&g)[3][3], Lanes volume, StiffnessLanes& K) {
    for (int b = 1; b < 4; ++b) {
        Lanes cg[9][3];  // cg[q][l] = sum_m C(q, (l, m)) g_b[m]
        for (int q = 0; q < 9; ++q)
            for (int l = 0; l < 3; ++l)
                cg[q][l] = C.c[q][3 * l] * g[b - 1][0] + C.c[q][3 * l + 1] * g[b - 1][1] + C.c[q][3 * l + 2] * g[b - 1][2];
        for (int a = 1; a <= b; ++a)
            for (int k = 0; k < 3; ++k)
                for (int l = 0; l < 3; ++l) {
                    const Lanes v = volume * (g[a - 1][0] * cg[3 * k][l] + g[a - 1][1] * cg[3 * k + 1][l] +
                                              g[a - 1][2] * cg[3 * k + 2][l]);
                    K.block[a][b][k][l] = K.block[b][a][l][k] = v;
                }
    }
    for (int b = 1; b < 4; ++b)
        for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l)
                K.block[0][b][k][l] = K.block[b][0][l][k] =
                    -(K.block[1][b][k][l] + K.block[2][b][k][l] + K.block[3][b][k][l]);
    for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l)
            K.block[0][0][k][l] = -(K.block[0][1][k][l] + K.block[0][2][k][l] + K.block[0][3][k][l]);
}

}  // namespace

const vec<int32_t>& FemBody::tets_by_lane() const {
    if (lane_tets_version_ == matrix_version) return lane_tets_;  // every element change bumps it
    size_t slots = 0;
    size_t first[SH_MATERIAL_COUNT];
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model) {
        first[model] = slots;
        slots += blocks_[model].size() * kLanes;
    }
    lane_tets_.assign(slots, -1);
    for (size_t t = 0; t < volume_.size(); ++t)
        lane_tets_[first[materials_[t].model] + static_cast<size_t>(lane_of_[t])] = static_cast<int32_t>(t);
    tangent_order_.clear();
    tangent_order_.reserve(volume_.size());
    for (const int32_t t : lane_tets_)
        if (t >= 0) tangent_order_.push_back(t);
    lane_tets_version_ = matrix_version;
    return lane_tets_;
}

const int32_t* FemBody::tangent_order() const { return tets_by_lane().size() ? tangent_order_.data() : nullptr; }

void FemBody::add_block_tangent(int model, const TetBlock* b, int count, const Mat3L* near, const int32_t* tets,
                                const double* xs, double scale, size_t& position, SparseSystem& system) const {
    // The block's weights are -V0 lambda and -V0 mu, and every law's dP/dF is linear in
    // (lambda, mu) (projected or not: the projection commutes with a positive scale), so the
    // tangent is formed with them as the Lame parameters and a unit volume.
    Mat3L F[2];
    Lanes lambda[2], mu[2];
    const Mat3L* frame_near[2] = {};
    for (int n = 0; n < count; ++n) {
        F[n] = mul(gather_edges(b[n], xs), b[n].Bm);
        lambda[n] = -b[n].lambda_w, mu[n] = -b[n].mu_w;
        frame_near[n] = near ? &near[n] : nullptr;
    }
    StressDerivativeLanes C[2];
    visit_material(model, [&](auto law) {
        using Law = decltype(law);
        if constexpr (Law::kProjectTangent)
            law_projected_derivatives<Law>(count, F, lambda, mu, frame_near, C);
        else
            for (int n = 0; n < count; ++n) stress_derivatives<Law>(F[n], lambda[n], mu[n], C[n]);
    });
    StiffnessLanes K;
    const double* blocks = reinterpret_cast<const double*>(&K.block[0][0][0][0]);  // a vector aliases a double
    for (int n = 0; n < count; ++n) {
        element_stiffness(C[n], b[n].Bm.m, splat(1.0), K);
        for (int l = 0; l < kLanes; ++l, ++tets)
            if (*tets >= 0) system.add_element_lane(static_cast<size_t>(*tets), position++, blocks + l, kLanes, scale);
    }
}

void FemBody::add_tangent(const double* xs, double stiffness_scale, double damping_scale, SparseSystem& system) const {
    const double scale = stiffness_scale + damping_scale * damping_stiffness_;  // D = beta K
    if (scale == 0.0) return;
    // Block by block, as the force passes run: a block's data lie together, the blocks follow
    // each lane's stretch of the elements' locality order, and the scatter then writes near
    // where the last block wrote (the free nodes are numbered by position too:
    // solver/free_node_order.hpp). The file's order of the tets would jump across the matrix.
    const vec<int32_t>& lane_tets = tets_by_lane();
    size_t slot = 0, position = 0;  // position: in tangent_order(), as the pattern expects it
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model) {
        const Mat3L* near = rotations_.last(model);
        // Two blocks at a time: their frames are found together (law_projected_derivatives).
        const size_t count = blocks_[model].size();
        for (size_t k = 0; k < count; k += 2) {
            const int pair = count - k >= 2 ? 2 : 1;
            add_block_tangent(model, &blocks_[model][k], pair, near ? &near[k] : nullptr, &lane_tets[slot], xs, scale,
                              position, system);
            slot += static_cast<size_t>(pair) * kLanes;
        }
    }
}

}  // namespace sh
