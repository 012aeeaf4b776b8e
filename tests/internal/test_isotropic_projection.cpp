// The laws' analytic eigensystems of dP/dF, projected to positive semi-definite in F's singular
// frame (material/isotropic_projection.hpp), against an independent reference: dP/dF formed
// from each law's differential dP(F)[dF] on the nine unit directions (for the corotational
// law, whose differential holds R fixed, from the exact differential derived by hand below and
// itself checked against central differences of P), fully eigendecomposed (Eigen's
// SelfAdjointEigenSolver) with its negative eigenvalues set to zero. For the laws that project
// (StVK, neo-Hookean, corotational) at stretched, compressed, inverted and degenerate
// deformations. The projected dP/dF is read off the element stiffness the tangent forms from
// the modes (model/element_stiffness.hpp) with unit shape-function gradients, and that element
// stiffness is compared with G^T C G formed densely from the reference, for random element
// shapes.
#include "material/corotational_material.hpp"
#include "material/isotropic_projection.hpp"
#include "material/neohookean_material.hpp"
#include "material/stvk_material.hpp"
#include "model/element_stiffness.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <algorithm>
#include <initializer_list>
#include <random>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

using StressDerivative = Eigen::Matrix<double, 9, 9>;
using Deformations = std::vector<Eigen::Matrix3d>;

Eigen::Matrix3d rotation(std::mt19937_64& rng) {
    std::normal_distribution<double> normal;
    Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
    return q.normalized().toRotationMatrix();
}

/// dP/dF of Law at f (lanes all f; Lame parameters lambda, mu), symmetrised.
template <class Law>
StressDerivative derivative(const Eigen::Matrix3d& f, double lambda, double mu) {
    sh::Mat3L F;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) F.m[i][j] = sh::splat(f(i, j));
    typename Law::State state;
    Law::stress(F, sh::splat(lambda), sh::splat(mu), state);
    StressDerivative c;
    for (int q = 0; q < 9; ++q) {
        sh::Mat3L dF{};
        dF.m[q / 3][q % 3] = sh::splat(1.0);
        const sh::Mat3L dP = Law::differential(F, state, dF, sh::splat(lambda), sh::splat(mu));
        for (int p = 0; p < 9; ++p) c(p, q) = dP.m[p / 3][p % 3][0];
    }
    return 0.5 * (c + c.transpose());
}

/// F's polar rotation from Eigen's SVD (det +1: the smallest singular value takes the sign).
Eigen::Matrix3d polar(const Eigen::Matrix3d& f) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d u = svd.matrixU();
    if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) = -u.col(2);
    return u * svd.matrixV().transpose();
}

/// The corotational P = R (2 mu (S - I) + lambda tr(S - I) I) = 2 mu (F - R) + lambda (tr S - 3) R.
Eigen::Matrix3d corotational_stress(const Eigen::Matrix3d& f, double lambda, double mu) {
    const Eigen::Matrix3d r = polar(f);
    return 2.0 * mu * (f - r) + lambda * ((r.transpose() * f).trace() - 3.0) * r;
}

/// Its exact dP/dF: dP = 2 mu dF + lambda tr(R^T dF) R + (lambda (tr S - 3) - 2 mu) dR (d tr S =
/// tr(R^T dF), as R^T dR is skew and S symmetric), with dR = R [w]x where, from R^T F = S
/// symmetric, (tr S I - S) w = axial(R^T dF - dF^T R). Symmetrised, as derivative() is.
StressDerivative corotational_derivative(const Eigen::Matrix3d& f, double lambda, double mu) {
    const Eigen::Matrix3d r = polar(f), s = r.transpose() * f;
    const Eigen::Matrix3d a = s.trace() * Eigen::Matrix3d::Identity() - s;
    StressDerivative c;
    for (int q = 0; q < 9; ++q) {
        Eigen::Matrix3d df = Eigen::Matrix3d::Zero();
        df(q / 3, q % 3) = 1.0;
        const Eigen::Matrix3d m = r.transpose() * df, skew = m - m.transpose();
        const Eigen::Vector3d w = a.partialPivLu().solve(Eigen::Vector3d(skew(2, 1), skew(0, 2), skew(1, 0)));
        Eigen::Matrix3d wx;
        wx << 0.0, -w(2), w(1), w(2), 0.0, -w(0), -w(1), w(0), 0.0;
        const Eigen::Matrix3d dp = 2.0 * mu * df + lambda * m.trace() * r + (lambda * (s.trace() - 3.0) - 2.0 * mu) * r * wx;
        for (int p = 0; p < 9; ++p) c(p, q) = dp(p / 3, p % 3);
    }
    return 0.5 * (c + c.transpose());
}

/// The reference dP/dF of Law at f: its differential's, or the corotational law's exact one.
template <class Law>
StressDerivative reference(const Eigen::Matrix3d& f, double lambda, double mu) {
    if constexpr (Law::kRotates) return corotational_derivative(f, lambda, mu);
    else return derivative<Law>(f, lambda, mu);
}

/// True if the law's eigensystem is the reference's at f: for the corotational law, every
/// pair of F's signed singular values sums to more than its kTurnFloor of the largest (R's
/// change is singular where two cancel, and the law bounds the turn stiffness there).
template <class Law>
bool reference_defined(const sh::SingularFrameLanes& frame, int l) {
    if constexpr (!Law::kRotates) return true;
    else {
        const double s[3] = {frame.s[0][l], frame.s[1][l], frame.s[2][l]};
        const double size = std::max({std::abs(s[0]), std::abs(s[1]), std::abs(s[2])});
        for (int a = 0; a < 3; ++a)
            if (!(s[(a + 1) % 3] + s[(a + 2) % 3] > Law::kTurnFloor * size)) return false;
        return true;
    }
}

/// The reference: c's eigendecomposition with the negative eigenvalues set to zero.
StressDerivative clamped(const StressDerivative& c) {
    const Eigen::SelfAdjointEigenSolver<StressDerivative> eigen(c);
    return eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
}

Eigen::Matrix3d lane(const sh::Mat3L& a, int l) {
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = a.m[i][j][l];
    return r;
}

/// Checks lane l's frame of f: orthonormal, and it diagonalises f into its signed singular
/// values, to round-off.
void check_frame(const sh::SingularFrameLanes& frame, int l, const Eigen::Matrix3d& f) {
    const Eigen::Matrix3d u = lane(frame.u, l), v = lane(frame.v, l);
    const Eigen::Matrix3d d = u.transpose() * f * v;
    const Eigen::Vector3d s(frame.s[0][l], frame.s[1][l], frame.s[2][l]);
    assert_true((d - Eigen::Matrix3d(s.asDiagonal())).cwiseAbs().maxCoeff() <= 1e-14 * f.norm());
    assert_true((u.transpose() * u - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-14);
    assert_true((v.transpose() * v - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-14);
}

/// G (9x12), the map from a tet's nodal displacements to F, for node gradients g_1..g_3 (rows of
/// g) and g_0 = -(g_1 + g_2 + g_3): dF_kj / dx_ak = g_a[j].
Eigen::Matrix<double, 9, 12> displacement_gradient(const Eigen::Matrix3d& g) {
    Eigen::Matrix<double, 9, 12> G = Eigen::Matrix<double, 9, 12>::Zero();
    for (int a = 0; a < 4; ++a) {
        const Eigen::Vector3d ga = a == 0 ? Eigen::Vector3d(-g.colwise().sum().transpose()) : Eigen::Vector3d(g.row(a - 1).transpose());
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 3; ++j) G(3 * k + j, 3 * a + k) = ga(j);
    }
    return G;
}

/// Lane l of K as a 12x12 matrix.
Eigen::Matrix<double, 12, 12> lane(const sh::StiffnessLanes& K, int l) {
    Eigen::Matrix<double, 12, 12> r;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
            for (int k = 0; k < 3; ++k)
                for (int m = 0; m < 3; ++m) r(3 * a + k, 3 * b + m) = K.block[a][b][k][m][l];
    return r;
}

/// The element stiffness from frame's projected modes, for random shape gradients per lane,
/// against G^T c G formed densely from the reference's projected dP/dF c (expected[l]) where
/// lane l has one (has_reference[l]); elsewhere finite and positive semi-definite.
template <class Law>
void check_element_stiffness(const sh::SingularFrameLanes& frame, const StressDerivative* expected,
                             const bool* has_reference, int count) {
    static unsigned batches = 0;  // each batch its own shapes, the same in every run
    std::mt19937_64 rng(++batches);
    std::uniform_real_distribution<double> entry(-2.0, 2.0);
    Eigen::Matrix3d g[sh::kLanes];
    sh::Lanes gl[3][3];
    for (int l = 0; l < sh::kLanes; ++l) {
        g[l] = Eigen::Matrix3d::NullaryExpr([&](Eigen::Index, Eigen::Index) { return entry(rng); });
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) gl[i][j][l] = g[l](i, j);
    }
    sh::StiffnessLanes K;
    sh::modal_element_stiffness(sh::projected_principal_stiffness(Law::principal_stiffness(frame.s, sh::splat(2.0), sh::splat(1.0))),
                                frame, gl, K);
    sh::complete_node_zero(K);
    for (int l = 0; l < count; ++l) {
        const Eigen::Matrix<double, 12, 12> mine = lane(K, l);
        if (!has_reference[l]) {
            assert_true(mine.allFinite());
            const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>> eigen(mine);
            assert_true(eigen.eigenvalues()(0) >= -1e-10 * std::max(mine.cwiseAbs().maxCoeff(), 1.0));
            continue;
        }
        const Eigen::Matrix<double, 9, 12> G = displacement_gradient(g[l]);
        const Eigen::Matrix<double, 12, 12> reference = G.transpose() * expected[l] * G;
        const double scale = std::max(reference.cwiseAbs().maxCoeff(), expected[l].cwiseAbs().maxCoeff());
        assert_true((mine - reference).cwiseAbs().maxCoeff() <= 1e-10 * scale);
    }
}

/// dP/dF with stiffness k's negative eigenvalues removed, per lane, as the tangent forms it
/// (projected_principal_stiffness, then modal_element_stiffness): with the shape-function
/// gradients g_a = e_(a-1) of nodes a = 1..3, K((a, k), (b, l)) = C((k, a-1), (l, b-1)), so
/// those blocks are dP/dF's entries.
sh::StressDerivativeLanes projected_derivative(const sh::PrincipalStiffnessLanes& k, const sh::SingularFrameLanes& frame) {
    sh::Lanes g[3][3] = {};
    for (int a = 0; a < 3; ++a) g[a][a] = sh::splat(1.0);
    sh::StiffnessLanes K;
    sh::modal_element_stiffness(sh::projected_principal_stiffness(k), frame, g, K);
    sh::StressDerivativeLanes c;
    for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a)
            for (int l = 0; l < 3; ++l)
                for (int b = 0; b < 3; ++b) c.c[3 * i + a][3 * l + b] = K.block[a + 1][b + 1][i][l];
    return c;
}

/// Projects Law's derivative at up to kLanes deformations at once (one per lane, the last
/// repeated into the rest) and compares each lane with the reference; returns the reference's
/// negative eigenvalues (those the projection removed).
template <class Law>
int check_lanes(const Eigen::Matrix3d* fs, int count) {
    sh::Mat3L F;
    for (int l = 0; l < sh::kLanes; ++l)
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) F.m[i][j][l] = fs[std::min(l, count - 1)](i, j);
    const sh::SingularFrameLanes frame = sh::singular_frames(F);
    const sh::StressDerivativeLanes projected =
        projected_derivative(Law::principal_stiffness(frame.s, sh::splat(2.0), sh::splat(1.0)), frame);
    int removed = 0;
    StressDerivative expected[sh::kLanes];
    bool has_reference[sh::kLanes] = {};
    for (int l = 0; l < count; ++l) {
        check_frame(frame, l, fs[l]);
        StressDerivative mine;
        for (int p = 0; p < 9; ++p)
            for (int q = 0; q < 9; ++q) mine(p, q) = projected.c[p][q][l];
        if (!reference_defined<Law>(frame, l)) {  // finite and positive semi-definite only
            assert_true(mine.allFinite());
            const Eigen::SelfAdjointEigenSolver<StressDerivative> eigen(mine);
            assert_true(eigen.eigenvalues()(0) >= -1e-10 * std::max(mine.cwiseAbs().maxCoeff(), 1.0));
            continue;
        }
        const StressDerivative c = reference<Law>(fs[l], 2.0, 1.0);
        // The reference's projection, which is positive semi-definite.
        const double scale = c.cwiseAbs().maxCoeff();
        expected[l] = clamped(c), has_reference[l] = true;
        assert_true((mine - expected[l]).cwiseAbs().maxCoeff() <= 1e-10 * scale);
        const Eigen::SelfAdjointEigenSolver<StressDerivative> after(mine), before(c);
        assert_true(after.eigenvalues()(0) >= -1e-10 * scale);
        removed += static_cast<int>((before.eigenvalues().array() < -1e-10 * scale).count());
    }
    check_element_stiffness<Law>(frame, expected, has_reference, count);
    return removed;
}

/// check_lanes over all of fs, kLanes at a time.
template <class Law>
int check(const Deformations& fs) {
    int removed = 0;
    for (size_t first = 0; first < fs.size(); first += sh::kLanes)
        removed += check_lanes<Law>(&fs[first], static_cast<int>(std::min<size_t>(sh::kLanes, fs.size() - first)));
    return removed;
}

/// Appends r1 diag(s) r2 for each of stretches s, with one random pair of rotations r1, r2.
void add_rotated(Deformations& fs, std::mt19937_64& rng, std::initializer_list<Eigen::Vector3d> stretches) {
    const Eigen::Matrix3d r1 = rotation(rng), r2 = rotation(rng);
    for (const Eigen::Vector3d& s : stretches) fs.push_back(r1 * s.asDiagonal() * r2);
}

/// Random deformations r1 diag(s) r2 with principal stretches in [low, high], det F > 0.
Deformations random_deformations(double low, double high, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> stretch(low, high);
    Deformations fs;
    for (int n = 0; n < 300; ++n) {
        const Eigen::Vector3d s(stretch(rng), stretch(rng), stretch(rng));
        add_rotated(fs, rng, {s});
    }
    return fs;
}

/// Two batches' frames found together (singular_frame_pair) diagonalise each batch's F to
/// round-off, as one batch's do, with the same singular values: one batch of mild strains and
/// one of strong compression and inversion, whose eigen-solves take different sweeps.
void paired_frames(void**) {
    Deformations fs = random_deformations(0.95, 1.05, 11);
    std::mt19937_64 rng(12);
    for (int n = 0; n < 8; ++n) add_rotated(fs, rng, {Eigen::Vector3d(0.9, 0.3, n % 2 ? -0.2 : 0.1)});
    sh::Mat3L F[2];
    for (int b = 0; b < 2; ++b)
        for (int l = 0; l < sh::kLanes; ++l)
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) F[b].m[i][j][l] = fs[b == 0 ? l : fs.size() - 1 - l](i, j);
    const sh::Mat3L* const near[2] = {nullptr, nullptr};
    sh::SingularFrameLanes pair[2];
    sh::singular_frame_pair(F, near, pair);
    for (int b = 0; b < 2; ++b) {
        const sh::SingularFrameLanes alone = sh::singular_frames(F[b]);
        for (int l = 0; l < sh::kLanes; ++l) {
            check_frame(pair[b], l, lane(F[b], l));
            for (int k = 0; k < 3; ++k)
                assert_true(std::abs(pair[b].s[k][l] - alone.s[k][l]) <= 1e-14 * lane(F[b], l).norm());
        }
    }
}

/// Strong compression makes both laws indefinite: eigenvalues must be removed, and the result
/// is the full eigendecomposition's.
void compressed_elements(void**) {
    assert_true(check<sh::StvkMaterial>(random_deformations(0.2, 0.9, 1)) > 0);
    assert_true(check<sh::NeoHookeanMaterial>(random_deformations(0.1, 0.6, 2)) > 0);
    assert_true(check<sh::CorotationalMaterial>(random_deformations(0.2, 0.9, 9)) > 0);
}

/// Stretched and mixed deformations, definite or not.
void mixed_elements(void**) {
    check<sh::StvkMaterial>(random_deformations(0.3, 2.0, 3));
    check<sh::NeoHookeanMaterial>(random_deformations(0.3, 2.0, 4));
    check<sh::CorotationalMaterial>(random_deformations(0.3, 2.0, 10));
}

/// Inverted elements (one negative principal stretch).
void inverted_elements(void**) {
    std::mt19937_64 rng(5);
    Deformations fs;
    for (int n = 0; n < 100; ++n) add_rotated(fs, rng, {Eigen::Vector3d(0.9, 0.7, -0.2 - 0.001 * n)});
    assert_true(check<sh::StvkMaterial>(fs) > 0);
    assert_true(check<sh::NeoHookeanMaterial>(fs) > 0);
    assert_true(check<sh::CorotationalMaterial>(fs) > 0);
}

/// Flattened elements, det F > 0 but singular values far apart (down to 1e-6 of the largest):
/// their frames are as accurate as those of mild strains, in the same batches as mild ones.
void flattened_elements(void**) {
    std::mt19937_64 rng(13);
    Deformations fs;
    for (int n = 0; n < 40; ++n)
        add_rotated(fs, rng, {Eigen::Vector3d(1.0, 0.3, 1e-2), Eigen::Vector3d(1.1, 0.9, 1.0), Eigen::Vector3d(2.0, 1e-3, 1e-6),
                              Eigen::Vector3d(1.0, 1.0, 0.05)});
    check<sh::StvkMaterial>(fs);
    check<sh::NeoHookeanMaterial>(fs);
}

/// Repeated singular values (the frame is not unique there) and pure rotations (the rest
/// shape, turned), in the same batches as distinct ones (each lane converges on its own).
void degenerate_stretches(void**) {
    std::mt19937_64 rng(6);
    Deformations fs;
    for (int n = 0; n < 100; ++n)
        add_rotated(fs, rng, {Eigen::Vector3d(0.5, 0.5, 1.2), Eigen::Vector3d(0.4, 0.4, 0.4), Eigen::Vector3d(1.0, 1.0, 1.0),
                              Eigen::Vector3d(0.3, 0.8, 1.6)});
    check<sh::StvkMaterial>(fs);
    check<sh::NeoHookeanMaterial>(fs);
    check<sh::CorotationalMaterial>(fs);
}

/// Singular deformations: F = 0 and F of rank one and two (flattened and collapsed elements).
void singular_deformations(void**) {
    std::mt19937_64 rng(7);
    Deformations fs;
    for (int n = 0; n < 40; ++n) add_rotated(fs, rng, {Eigen::Vector3d(0.8, 0.6, 0.0), Eigen::Vector3d(1.1, 0.0, 0.0)});
    fs.push_back(Eigen::Matrix3d::Zero());
    check<sh::StvkMaterial>(fs);
    check<sh::NeoHookeanMaterial>(fs);
    check<sh::CorotationalMaterial>(fs);
}

/// F scaled far beyond any physical strain (1e-60 to 1e60): the frames stay orthonormal and
/// exact, and the projected derivative finite and positive semi-definite. (The numerically
/// differentiated reference loses its digits at such scales, so it is not compared.)
template <class Law>
void check_scaled(double scale, const Eigen::Matrix3d& f0) {
    const Eigen::Matrix3d f = scale * f0;
    sh::Mat3L F;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) F.m[i][j] = sh::splat(f(i, j));
    const sh::SingularFrameLanes frame = sh::singular_frames(F);
    check_frame(frame, 0, f);
    const sh::StressDerivativeLanes projected =
        projected_derivative(Law::principal_stiffness(frame.s, sh::splat(2.0), sh::splat(1.0)), frame);
    StressDerivative mine;
    for (int p = 0; p < 9; ++p)
        for (int q = 0; q < 9; ++q) mine(p, q) = projected.c[p][q][0];
    assert_true(mine.allFinite());
    const Eigen::SelfAdjointEigenSolver<StressDerivative> eigen(mine);
    assert_true(eigen.eigenvalues()(0) >= -1e-10 * mine.cwiseAbs().maxCoeff());
}

void extreme_scales(void**) {
    std::mt19937_64 rng(8);
    const Eigen::Matrix3d f0 = rotation(rng) * Eigen::Vector3d(0.7, 1.2, 0.9).asDiagonal() * rotation(rng);
    for (const double scale : {1e-60, 1e-45, 1e-20, 1e20, 1e45, 1e60}) {
        check_scaled<sh::StvkMaterial>(scale, f0);
        check_scaled<sh::NeoHookeanMaterial>(scale, f0);
        check_scaled<sh::CorotationalMaterial>(scale, f0);
    }
}

/// The projected derivative is linear in the stiffness (the projection commutes with a
/// positive scale): at 1e-160 to 1e160 times a unit stiffness it is that multiple of the unit
/// result. The stretch blocks are indefinite, one only through its determinant (its corner
/// and leading pair are positive, a determinant cubes the entries), one with two eigenvalues
/// 1e-7 apart (a Jacobi turn squares their gap).
void stiffness_at_extreme_scales_scales_the_projection(void**) {
    std::mt19937_64 rng(13);
    const Eigen::Matrix3d f = rotation(rng) * Eigen::Vector3d(0.9, 1.1, 1.0).asDiagonal() * rotation(rng);
    sh::Mat3L F;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) F.m[i][j] = sh::splat(f(i, j));
    const sh::SingularFrameLanes frame = sh::singular_frames(F);
    const double blocks[2][3][3] = {{{2.0, 1.0, 1.0}, {1.0, 2.0, 1.0}, {1.0, 1.0, -0.5}},
                                    {{1.0, 1e-7, 0.3}, {1e-7, 1.0 + 1e-7, 0.2}, {0.3, 0.2, -1.0}}};
    for (const auto& block : blocks) {
        const auto projected = [&](double scale) {
            sh::PrincipalStiffnessLanes k;
            for (int a = 0; a < 3; ++a) {
                for (int b = 0; b < 3; ++b) k.stretch[a][b] = sh::splat(scale * block[a][b]);
                k.shear[a] = sh::splat(scale * (1.0 + a)), k.turn[a] = sh::splat(scale * (0.5 + a));
            }
            const sh::StressDerivativeLanes out = projected_derivative(k, frame);
            StressDerivative c;
            for (int p = 0; p < 9; ++p)
                for (int q = 0; q < 9; ++q) c(p, q) = out.c[p][q][0] / scale;
            return c;
        };
        const StressDerivative unit = projected(1.0);
        const Eigen::SelfAdjointEigenSolver<StressDerivative> eigen(unit);
        assert_true(eigen.eigenvalues()(0) >= -1e-12);  // projected: the negative stretch mode is gone
        for (const double scale : {1e-160, 1e-146, 1e120, 1e160})
            assert_true((projected(scale) - unit).cwiseAbs().maxCoeff() <= 1e-12 * unit.cwiseAbs().maxCoeff());
    }
}

/// An element collapsed onto a stretched line (F of rank one, or nearly: s = (5, d, d)), or
/// inverted across a pair whose stretches nearly cancel beside a long third axis: the exact
/// turn stiffness grows as 1 / (s_b + s_c) without bound there; the corotational law's
/// projected derivative stays finite, positive semi-definite and below a few thousand times
/// its moduli.
void corotational_turn_stays_bounded(void**) {
    std::mt19937_64 rng(12);
    Deformations fs;
    for (const double d : {1e-3, 1e-9, 1e-15, 0.0})
        add_rotated(fs, rng, {Eigen::Vector3d(5.0, d, d), Eigen::Vector3d(4.0, 1.0, -1.0 + d)});
    for (const Eigen::Matrix3d& f : fs) {
        sh::Mat3L F;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) F.m[i][j] = sh::splat(f(i, j));
        const sh::SingularFrameLanes frame = sh::singular_frames(F);
        const sh::StressDerivativeLanes projected =
            projected_derivative(sh::CorotationalMaterial::principal_stiffness(frame.s, sh::splat(4.0), sh::splat(1.0)), frame);
        StressDerivative mine;
        for (int p = 0; p < 9; ++p)
            for (int q = 0; q < 9; ++q) mine(p, q) = projected.c[p][q][0];
        assert_true(mine.allFinite());
        assert_true(mine.cwiseAbs().maxCoeff() <= 1e4 * (4.0 + 1.0));
        const Eigen::SelfAdjointEigenSolver<StressDerivative> eigen(mine);
        assert_true(eigen.eigenvalues()(0) >= -1e-10 * mine.cwiseAbs().maxCoeff());
    }
}

/// The corotational reference above against central differences of its stress, at stretched,
/// compressed and inverted deformations.
void corotational_reference_is_the_derivative(void**) {
    std::mt19937_64 rng(11);
    for (const Eigen::Vector3d& s : {Eigen::Vector3d(1.3, 0.8, 1.1), Eigen::Vector3d(0.5, 0.4, 0.9),
                                     Eigen::Vector3d(0.9, 0.7, -0.3)}) {
        const Eigen::Matrix3d f = rotation(rng) * s.asDiagonal() * rotation(rng);
        const StressDerivative c = corotational_derivative(f, 2.0, 1.0);
        StressDerivative numeric;
        const double h = 1e-6;
        for (int q = 0; q < 9; ++q) {
            Eigen::Matrix3d df = Eigen::Matrix3d::Zero();
            df(q / 3, q % 3) = h;
            const Eigen::Matrix3d dp = (corotational_stress(f + df, 2.0, 1.0) - corotational_stress(f - df, 2.0, 1.0)) / (2.0 * h);
            for (int p = 0; p < 9; ++p) numeric(p, q) = dp(p / 3, p % 3);
        }
        assert_true((c - numeric).cwiseAbs().maxCoeff() <= 1e-7 * c.cwiseAbs().maxCoeff());
    }
}

}  // namespace

int main() {
    const CMUnitTest tests[] = {
        cmocka_unit_test(paired_frames),
        cmocka_unit_test(compressed_elements),
        cmocka_unit_test(mixed_elements),
        cmocka_unit_test(inverted_elements),
        cmocka_unit_test(degenerate_stretches),
        cmocka_unit_test(flattened_elements),
        cmocka_unit_test(singular_deformations),
        cmocka_unit_test(extreme_scales),
        cmocka_unit_test(stiffness_at_extreme_scales_scales_the_projection),
        cmocka_unit_test(corotational_reference_is_the_derivative),
        cmocka_unit_test(corotational_turn_stays_bounded),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
