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
#include "material/polar_decomposition.hpp"
#include "linalg/sparse_system.hpp"
#include "model/fem_kernel.hpp"

#include <Eigen/Dense>

#include <algorithm>

namespace sh {
namespace {

using Matrix9 = StressDerivative;

// dP/dF per lane of a batch of elements of one material model; a law that keeps a rotation
// finds it from near where the caller has one (the body's last pass's: see BlockRotations).
template <class Material>
void stress_derivatives(const Mat3L& F, Lanes lambda, Lanes mu, const Mat3L* near, Matrix9 (&C)[kLanes]) {
    typename Material::State state;
    if constexpr (Material::kRotates) {
        Mat3L R;  // the batch's own: the body's are the force passes' (BlockRotations)
        Material::stress_at(F, kept_rotation(F, 0, KeptRotations{near, &R}), lambda, mu, state);
    } else {
        Material::stress(F, lambda, mu, state);
    }
    for (int q = 0; q < 9; ++q) {
        Mat3L dF{};
        dF.m[q / 3][q % 3] = splat(1.0);
        const Mat3L dP = Material::differential(F, state, dF, lambda, mu);
        for (int l = 0; l < kLanes; ++l)
            for (int p = 0; p < 9; ++p) C[l](p, q) = dP.m[p / 3][p % 3][l];
    }
}

// dP/dF of a law that projects (all isotropic: see the material table's kProjectTangent) for
// each lane, projected to positive semi-definite: from the law's analytic eigensystem in F's
// singular frame, which the batch's polar rotations give.
template <class Material>
void projected_stress_derivatives(const Mat3L& F, Lanes lambda, Lanes mu, int count, Matrix9 (&C)[kLanes]) {
    const Mat3L R = polar_rotation(F);
    for (int l = 0; l < count; ++l) {
        Eigen::Matrix3d f, r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) f(i, j) = F.m[i][j][l], r(i, j) = R.m[i][j][l];
        const SingularFrame frame = singular_frame(f, r);
        C[l] = projected_stress_derivative(Material::principal_stiffness(frame.s, lambda[l], mu[l]), frame);
    }
}

}  // namespace

void FemBody::add_tangent(const double* xs, double stiffness_scale, double damping_scale, SparseSystem& system) const {
    const double scale = stiffness_scale + damping_scale * damping_stiffness_;  // D = beta K
    if (scale == 0.0) return;
    const size_t tet_count = volume_.size();

    auto process = [&](int model, const int32_t* members, int count) {
        Mat3L F = identity_lanes();
        Lanes lambda = splat(1.0), mu = splat(1.0);
        Mat3L near = identity_lanes();
        const bool warm = rotations_.gather(model, members, count, lane_of_.data(), near);
        for (int l = 0; l < count; ++l) {
            const size_t t = static_cast<size_t>(members[l]);
            const int32_t* tet = &tets_[4 * t];
            const double* bm = &inverse_rest_[9 * t];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    double f = 0.0;
                    for (int a = 0; a < 3; ++a) f += (xs[3 * tet[a + 1] + i] - xs[3 * tet[0] + i]) * bm[3 * a + j];
                    F.m[i][j][l] = f;
                }
            lambda[l] = lame_lambda(materials_[t]);
            mu[l] = lame_mu(materials_[t]);
        }
        Matrix9 C[kLanes];
        visit_material(model, [&](auto law) {
            using Law = decltype(law);
            if constexpr (Law::kProjectTangent) {
                projected_stress_derivatives<Law>(F, lambda, mu, count, C);
            } else {
                stress_derivatives<Law>(F, lambda, mu, warm ? &near : nullptr, C);
                for (int l = 0; l < count; ++l) C[l] = 0.5 * (C[l] + C[l].transpose());
            }
        });
        for (int l = 0; l < count; ++l) {
            const size_t t = static_cast<size_t>(members[l]);
            const Matrix9& c = C[l];
            const double* bm = &inverse_rest_[9 * t];
            double g[4][3];
            for (int j = 0; j < 3; ++j) {
                g[0][j] = 0.0;
                for (int a = 1; a < 4; ++a) {
                    g[a][j] = bm[3 * (a - 1) + j];
                    g[0][j] -= g[a][j];
                }
            }
            // CG(q, (b, l)) = sum_m C(q, (l, m)) g_b[m]; K((a, k), (b, l)) = V0 sum_j g_a[j] CG((k, j), (b, l)).
            double cg[9][12];
            for (int q = 0; q < 9; ++q)
                for (int b = 0; b < 4; ++b)
                    for (int lc = 0; lc < 3; ++lc)
                        cg[q][3 * b + lc] = c(q, 3 * lc) * g[b][0] + c(q, 3 * lc + 1) * g[b][1] + c(q, 3 * lc + 2) * g[b][2];
            double ke[144];
            for (int a = 0; a < 4; ++a)
                for (int k = 0; k < 3; ++k)
                    for (int col = 0; col < 12; ++col)
                        ke[12 * (3 * a + k) + col] = volume_[t] * (g[a][0] * cg[3 * k][col] + g[a][1] * cg[3 * k + 1][col] +
                                                                   g[a][2] * cg[3 * k + 2][col]);
            system.add_element(t, ke, scale);
        }
    };

    int32_t batch[SH_MATERIAL_COUNT][kLanes];
    int filled[SH_MATERIAL_COUNT] = {};
    for (size_t t = 0; t < tet_count; ++t) {
        const int model = materials_[t].model;
        batch[model][filled[model]++] = static_cast<int32_t>(t);
        if (filled[model] == kLanes) {
            process(model, batch[model], kLanes);
            filled[model] = 0;
        }
    }
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model)
        if (filled[model] > 0) process(model, batch[model], filled[model]);
}

}  // namespace sh
