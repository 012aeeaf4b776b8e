// Rotation part R of F = R S (S symmetric), per lane, with det R = +1 even for inverted F.
#pragma once

#include "material/lanes.hpp"

namespace sh {

/// Rotation of the polar decomposition of each lane's F. Well-conditioned lanes use the
/// Frobenius-scaled Newton iteration R <- (g R + R^-T / g) / 2; lanes with det F small or
/// negative use an SVD with the smallest singular value's sign flipped, so R is a rotation.
Mat3L polar_rotation(const Mat3L& F);

/// One Newton update of each lane's rotation R towards the polar factor of F: with M = R^T F,
/// S = sym(M) and w the axial vector of M - M^T, the update Q solves the linearised condition
/// skew(Q^T M) = 0, which for symmetric S reads (tr(S) I - S) omega = w; Q is omega's Cayley
/// rotation (exactly orthogonal), R becomes R Q. Returns |omega|^2 (rad^2) per lane, or NaN
/// where tr(S) I - S is not positive definite: there R is not near the polar factor (the one
/// maximum of tr(R^T F) over the rotations; the other stationary points are saddles and
/// minima), and the update would lead elsewhere.
Lanes rotation_update(const Mat3L& F, Mat3L& R);

/// Default settled2 of polar_rotation_near: R within about 1e-12 of the polar factor.
constexpr double kRotationSettled2 = 1e-12;

/// The same rotation found from a rotation `near` it (e.g. the element's at the last step):
/// Newton's method on the rotations R = near Q, Q a Cayley rotation, drives the skew part of
/// R^T F to zero. It converges quadratically, so a warm start close to the answer takes one or
/// two iterations where the iteration from F takes five to eight. It stops once no lane's last
/// update turned R by more than sqrt(settled2) rad: R is then about settled2 from the polar
/// factor. Lanes it cannot serve (det F small or negative, a start that does not converge
/// within a few iterations, a non-finite value) take polar_rotation's.
Mat3L polar_rotation_near(const Mat3L& F, const Mat3L& near, double settled2 = kRotationSettled2);

}  // namespace sh
