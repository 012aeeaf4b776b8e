// Tangent stiffness of FEM bodies for the implicit and static solvers:
// K_e = V0 G^T C G with C = dP/dF (9x9) and G the map from nodal displacements to F
// (model/element_stiffness.hpp). For the laws whose C can be indefinite (kProjectTangent in the
// material table; all isotropic), K_e comes projected to positive semi-definite straight from
// the law's analytic eigensystem in F's singular frame; for the others, C is formed from the
// law's differential on the unit basis of F.
#include "model/fem_body.hpp"

#include "material/material_params.hpp"
#include "material/isotropic_projection.hpp"
#include "material/material_table.hpp"
#include "linalg/sparse_system.hpp"
#include "model/element_stiffness.hpp"
#include "model/fem_kernel.hpp"

#include <algorithm>

namespace sh {
namespace {

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

// dP/dF's element stiffness for a law that projects (all isotropic: see the material table's
// kProjectTangent), per lane, projected to positive semi-definite: from the law's analytic
// eigensystem in F's singular frame, whose polar rotation (where it needs one) starts from
// near where the body keeps its elements' rotations (the last force pass's: see
// BlockRotations). Nodes 1..3's blocks; complete_node_zero adds node 0's. count (1 or 2)
// blocks b at once: their frames are found together (singular_frame_pair).
template <class Material>
void law_projected_stiffness(int count, const TetBlock* b, const Mat3L (&F)[2], const Lanes (&lambda)[2],
                             const Lanes (&mu)[2], const Mat3L* const (&near)[2], StiffnessLanes (&K)[2]) {
    SingularFrameLanes frame[2];
    if (count == 2) singular_frame_pair(F, near, frame);
    else frame[0] = singular_frames(F[0], near[0]);
    for (int n = 0; n < count; ++n)
        modal_element_stiffness(projected_principal_stiffness(Material::principal_stiffness(frame[n].s, lambda[n], mu[n])),
                                frame[n], b[n].Bm.m, K[n]);
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
    StiffnessLanes K[2];
    visit_material(model, [&](auto law) {
        using Law = decltype(law);
        if constexpr (Law::kProjectTangent) {
            law_projected_stiffness<Law>(count, b, F, lambda, mu, frame_near, K);
        } else {
            for (int n = 0; n < count; ++n) {
                StressDerivativeLanes C;
                stress_derivatives<Law>(F[n], lambda[n], mu[n], C);
                element_stiffness(C, b[n].Bm.m, K[n]);
            }
        }
    });
    for (int n = 0; n < count; ++n) {
        complete_node_zero(K[n]);
        const double* blocks = reinterpret_cast<const double*>(&K[n].block[0][0][0][0]);  // a vector aliases a double
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
