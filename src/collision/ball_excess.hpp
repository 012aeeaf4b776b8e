// The excess of a ball's contact potential over a surface edge or triangle: the sphere's
// excess solver (sphere_shape.cpp), exact to round-off.
#pragma once

#include "collision/shape_kind.hpp"

namespace sh {

/// Maximises psi(depth(x)) - sum_i w_i s.energy[i] over the simplex s, depth(x) = radius -
/// |x - centre|: the best of the triangle's interior stationary point (on the ray from the
/// centre's foot against the interpolant's slope), its edges' and its corners.
LocalExcess ball_excess(const LocalSimplex& s, const DepthPotential& psi, const double centre[3], double radius);

}  // namespace sh
