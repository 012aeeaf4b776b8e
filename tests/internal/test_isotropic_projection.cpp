// The laws' analytic eigensystems of dP/dF, projected to positive semi-definite in F's singular
// frame (material/isotropic_projection.hpp), against an independent reference: dP/dF formed
// numerically from each law's differential dP(F)[dF] on the nine unit directions, fully
// eigendecomposed (Eigen's SelfAdjointEigenSolver) with its negative eigenvalues set to zero.
// For the laws that project (StVK, neo-Hookean) at stretched, compressed, inverted and
// degenerate deformations.
#include "material/isotropic_projection.hpp"
#include "material/neohookean_material.hpp"
#include "material/polar_decomposition.hpp"
#include "material/stvk_material.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <random>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

using sh::StressDerivative;

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

/// f's singular frame the way the tangent assembly finds it: from f's polar rotation.
sh::SingularFrame frame_of(const Eigen::Matrix3d& f) {
    sh::Mat3L F;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) F.m[i][j] = sh::splat(f(i, j));
    const sh::Mat3L R = sh::polar_rotation(F);
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = R.m[i][j][0];
    return sh::singular_frame(f, r);
}

/// The reference: c's eigendecomposition with the negative eigenvalues set to zero.
StressDerivative clamped(const StressDerivative& c) {
    const Eigen::SelfAdjointEigenSolver<StressDerivative> eigen(c);
    return eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
}

/// Projects Law's derivative at r1 diag(s) r2 and compares with the reference; returns the
/// reference's negative eigenvalues (those the projection removed).
template <class Law>
int check(const Eigen::Matrix3d& r1, const Eigen::Vector3d& s, const Eigen::Matrix3d& r2) {
    const Eigen::Matrix3d f = r1 * s.asDiagonal() * r2;
    const StressDerivative c = derivative<Law>(f, 2.0, 1.0);
    const sh::SingularFrame frame = frame_of(f);
    // The frame is orthonormal and diagonalises f, to round-off ...
    const Eigen::Matrix3d d = frame.u.transpose() * f * frame.v;
    assert_true((d - Eigen::Matrix3d(d.diagonal().asDiagonal())).cwiseAbs().maxCoeff() <= 1e-14 * f.norm());
    assert_true((d.diagonal() - frame.s).cwiseAbs().maxCoeff() <= 1e-14 * f.norm());
    assert_true((frame.u.transpose() * frame.u - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-14);
    assert_true((frame.v.transpose() * frame.v - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-14);
    const StressDerivative projected =
        sh::projected_stress_derivative(Law::principal_stiffness(frame.s, 2.0, 1.0), frame);
    const StressDerivative expected = clamped(c);
    const double scale = c.cwiseAbs().maxCoeff();
    assert_true((projected - expected).cwiseAbs().maxCoeff() <= 1e-10 * scale);
    // ... and gives the reference's projection, which is positive semi-definite.
    const Eigen::SelfAdjointEigenSolver<StressDerivative> after(projected);
    assert_true(after.eigenvalues()(0) >= -1e-10 * scale);
    const Eigen::SelfAdjointEigenSolver<StressDerivative> before(c);
    return static_cast<int>((before.eigenvalues().array() < -1e-10 * scale).count());
}

/// Random deformations with principal stretches in [low, high], det F > 0.
template <class Law>
int random_cases(double low, double high, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> stretch(low, high);
    int removed = 0;
    for (int n = 0; n < 300; ++n)
        removed += check<Law>(rotation(rng), Eigen::Vector3d(stretch(rng), stretch(rng), stretch(rng)), rotation(rng));
    return removed;
}

/// Strong compression makes both laws indefinite: eigenvalues must be removed, and the result
/// is the full eigendecomposition's.
void compressed_elements(void**) {
    assert_true(random_cases<sh::StvkMaterial>(0.2, 0.9, 1) > 0);
    assert_true(random_cases<sh::NeoHookeanMaterial>(0.1, 0.6, 2) > 0);
}

/// Stretched and mixed deformations, definite or not.
void mixed_elements(void**) {
    random_cases<sh::StvkMaterial>(0.3, 2.0, 3);
    random_cases<sh::NeoHookeanMaterial>(0.3, 2.0, 4);
}

/// Inverted elements (one negative principal stretch, as the SVD of det F < 0 returns).
void inverted_elements(void**) {
    std::mt19937_64 rng(5);
    int removed = 0;
    for (int n = 0; n < 100; ++n) {
        const Eigen::Vector3d s(0.9, 0.7, -0.2 - 0.001 * n);
        removed += check<sh::StvkMaterial>(rotation(rng), s, rotation(rng));
        removed += check<sh::NeoHookeanMaterial>(rotation(rng), s, rotation(rng));
    }
    assert_true(removed > 0);
}

/// Repeated singular values (the frame is not unique there) and the rest shape.
void degenerate_stretches(void**) {
    std::mt19937_64 rng(6);
    for (int n = 0; n < 100; ++n) {
        const Eigen::Matrix3d r1 = rotation(rng), r2 = rotation(rng);
        check<sh::StvkMaterial>(r1, Eigen::Vector3d(0.5, 0.5, 1.2), r2);
        check<sh::NeoHookeanMaterial>(r1, Eigen::Vector3d(0.4, 0.4, 0.4), r2);
        check<sh::StvkMaterial>(r1, Eigen::Vector3d(1.0, 1.0, 1.0), r1.transpose());
    }
}

}  // namespace

int main() {
    const CMUnitTest tests[] = {
        cmocka_unit_test(compressed_elements),
        cmocka_unit_test(mixed_elements),
        cmocka_unit_test(inverted_elements),
        cmocka_unit_test(degenerate_stretches),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
