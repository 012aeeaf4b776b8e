// The point of a triangle closest to a given point.
#pragma once

namespace sh {

/// The point of triangle (a, b, c) closest to p, as barycentric weights w; returns the
/// distance. A zero-area triangle gives its first vertex.
double closest_on_triangle(const double* p, const double* a, const double* b, const double* c, double w[3]);

}  // namespace sh
