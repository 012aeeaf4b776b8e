// The rotation of the polar decomposition F = R S, cold (polar_rotation) and from a nearby
// rotation (polar_rotation_near), against an SVD of each F (F = U Sigma V^T, R = U V^T with the
// smallest singular value's sign flipped when det F < 0) from Eigen: an independent method.
#include "material/polar_decomposition.hpp"

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

using sh::kLanes;
using sh::Mat3L;

/// A rotation of angle |axis_angle| about its direction (Rodrigues).
Eigen::Matrix3d rotation(const Eigen::Vector3d& axis_angle) {
    const double angle = axis_angle.norm();
    if (angle == 0.0) return Eigen::Matrix3d::Identity();
    return Eigen::AngleAxisd(angle, axis_angle / angle).toRotationMatrix();
}

Eigen::Vector3d random_direction(std::mt19937_64& rng) {
    std::normal_distribution<double> normal;
    Eigen::Vector3d d(normal(rng), normal(rng), normal(rng));
    return d.normalized();
}

/// R Q^T diag(stretch) Q: a random rotation times a random symmetric positive stretch with
/// principal stretches in [low, high].
Eigen::Matrix3d random_deformation(std::mt19937_64& rng, double low, double high) {
    std::uniform_real_distribution<double> angle(0.0, M_PI), stretch(low, high);
    const Eigen::Matrix3d r = rotation(angle(rng) * random_direction(rng));
    const Eigen::Matrix3d q = rotation(angle(rng) * random_direction(rng));
    const Eigen::Vector3d s(stretch(rng), stretch(rng), stretch(rng));
    return r * q.transpose() * s.asDiagonal() * q;
}

/// The SVD's rotation of F.
Eigen::Matrix3d svd_rotation(const Eigen::Matrix3d& f) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d u = svd.matrixU();
    if ((u * svd.matrixV().transpose()).determinant() < 0) u.col(2) = -u.col(2);
    return u * svd.matrixV().transpose();
}

void put(Mat3L& m, int lane, const Eigen::Matrix3d& a) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m.m[i][j][lane] = a(i, j);
}

Eigen::Matrix3d get(const Mat3L& m, int lane) {
    Eigen::Matrix3d a;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) a(i, j) = m.m[i][j][lane];
    return a;
}

/// Largest entry difference between each lane of r and its expected rotation.
double worst_error(const Mat3L& r, const Eigen::Matrix3d expected[kLanes]) {
    double worst = 0.0;
    for (int l = 0; l < kLanes; ++l) worst = std::max(worst, (get(r, l) - expected[l]).cwiseAbs().maxCoeff());
    return worst;
}

/// kLanes random deformations F (principal stretches in [low, high]; lane `inverted`, if in
/// range, reflected to det F < 0), their SVD rotations, and a start for each: the rotation
/// turned by `off` radians about a random axis.
struct Block {
    Mat3L f, near;
    Eigen::Matrix3d expected[kLanes];

    Block(std::mt19937_64& rng, double low, double high, double off, int inverted = -1) {
        for (int l = 0; l < kLanes; ++l) {
            Eigen::Matrix3d a = random_deformation(rng, low, high);
            if (l == inverted) a.col(0) = -a.col(0);
            expected[l] = svd_rotation(a);
            put(f, l, a);
            put(near, l, expected[l] * rotation(off * random_direction(rng)));
        }
    }
};

/// Blocks whose warm start is the answer turned by `off` radians; every lane of both
/// functions must match the SVD within tolerance.
void check_starts(double off, double low, double high, double tolerance) {
    std::mt19937_64 rng(42);
    for (int n = 0; n < 200; ++n) {
        const Block block(rng, low, high, off);
        assert_true(worst_error(sh::polar_rotation(block.f), block.expected) < tolerance);
        assert_true(worst_error(sh::polar_rotation_near(block.f, block.near), block.expected) < tolerance);
        // A looser settling bound leaves R within a small multiple of it.
        assert_true(worst_error(sh::polar_rotation_near(block.f, block.near, 1e-8), block.expected) < 1e-7);
    }
}

/// A step's worth of motion (1e-4 rad), as between haptic ticks, and the largest strains of
/// soft tissue: one or two Newton updates.
void near_starts_match_the_svd(void**) { check_starts(1e-4, 0.5, 1.8, 1e-11); }

/// Starts a frame or more away (0.3 rad) converge too.
void far_starts_match_the_svd(void**) { check_starts(0.3, 0.5, 1.8, 1e-11); }

/// Starts half a turn away, where tr(S) I - S is indefinite and Newton would settle on a
/// wrong stationary rotation: the cold path answers.
void opposite_starts_fall_back(void**) { check_starts(M_PI * 0.97, 0.7, 1.3, 1e-11); }

/// Strong anisotropic stretch (1:20) with a near start.
void strong_stretch(void**) { check_starts(1e-2, 0.1, 2.0, 1e-10); }

/// An inverted lane (det F < 0) among well-shaped ones: the SVD's rotation with the smallest
/// singular value flipped, for the whole block as for that lane.
void inverted_lane(void**) {
    std::mt19937_64 rng(7);
    const Block block(rng, 0.8, 1.2, 0.0, 3);
    assert_true(worst_error(sh::polar_rotation_near(block.f, block.near), block.expected) < 1e-11);
}

/// An exact start stays exact: the update it computes is zero to round-off.
void exact_start_is_kept(void**) {
    std::mt19937_64 rng(3);
    const Block block(rng, 0.9, 1.1, 0.0);
    const Mat3L r = sh::polar_rotation_near(block.f, block.near);
    assert_true(worst_error(r, block.expected) < 1e-14);
    for (int l = 0; l < kLanes; ++l) {  // and orthogonal
        const Eigen::Matrix3d q = get(r, l);
        assert_true((q.transpose() * q - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-14);
    }
}

/// Newton's updates converge quadratically: from a start 0.05 rad off, each update leaves an
/// error at most a small multiple of the previous one's square, and the update returns the
/// angle it turned (the previous error, to first order).
void updates_converge_quadratically(void**) {
    std::mt19937_64 rng(11);
    const Block block(rng, 0.6, 1.6, 0.05);
    Mat3L r = block.near;
    double error = worst_error(r, block.expected);
    assert_true(error > 0.02);
    for (int update = 0; update < 3; ++update) {
        const sh::Lanes turned2 = sh::rotation_update(block.f, r);
        const double next = worst_error(r, block.expected);
        assert_true(next <= 4.0 * error * error + 1e-15);
        for (int l = 0; l < kLanes; ++l) assert_true(std::sqrt(turned2[l]) <= 2.0 * error + 1e-15);
        error = next;
    }
    assert_true(error < 1e-14);
}

}  // namespace

int main() {
    const CMUnitTest tests[] = {
        cmocka_unit_test(near_starts_match_the_svd), cmocka_unit_test(far_starts_match_the_svd),
        cmocka_unit_test(opposite_starts_fall_back), cmocka_unit_test(strong_stretch),
        cmocka_unit_test(inverted_lane),             cmocka_unit_test(exact_start_is_kept),
        cmocka_unit_test(updates_converge_quadratically),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
