// Rotation part R of F = R S (S symmetric), per lane, with det R = +1 even for inverted F.
#pragma once

#include "material/lanes.hpp"

namespace sh {

/// Rotation of the polar decomposition of each lane's F. Well-conditioned lanes use the
/// Frobenius-scaled Newton iteration R <- (g R + R^-T / g) / 2; lanes with det F small or
/// negative use an SVD with the smallest singular value's sign flipped, so R is a rotation.
Mat3L polar_rotation(const Mat3L& F);

}  // namespace sh
