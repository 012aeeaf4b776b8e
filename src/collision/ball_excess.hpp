// The excess of a ball's contact potential over a surface edge or triangle: the sphere's
// excess solver (sphere_shape.cpp), exact to round-off.
#pragma once

#include "collision/shape_kind.hpp"

namespace sh {

/// Maximises psi(depth(x)) - sum_i w_i s.energy[i] over the simplex s, depth(x) = radius -
/// |x - centre|: the best of the triangle's interior stationary point (on the ray from the
/// centre's foot against the interpolant's slope), its edges' and its corners.
LocalExcess ball_excess(const LocalSimplex& s, const DepthPotential& psi, const double centre[3], double radius);

/// Point x's depth (m; <= 0 outside) in the ball (centre, radius), and in normal the unit
/// direction that pushes it out: away from the centre, or pose's local x axis at the centre.
double ball_depth(const double centre[3], double radius, const Pose& pose, const double x[3], double normal[3]);

}  // namespace sh
