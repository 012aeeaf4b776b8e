// The point of a triangle (or segment) closest to a given point, and where a point lies against a triangle.
#pragma once

namespace sh {

/// The point of triangle (a, b, c) closest to p, as barycentric weights w; returns the
/// distance. A zero-area triangle gives its first vertex.
double closest_on_triangle(const double* p, const double* a, const double* b, const double* c, double w[3]);

/// The distance from p to the segment from a to b (to a if they coincide).
double distance_to_segment(const double* p, const double* a, const double* b);

/// A point p behind triangle (a, b, c) (outward by the right-hand rule): its depth below the
/// plane along the outward unit normal n, and the barycentric weights w of the triangle's
/// point nearest to p's projection. False if p is in front, the triangle is degenerate, or p
/// lies beyond the triangle's rim by more than its longer edge from a.
bool node_behind_face(const double* p, const double* a, const double* b, const double* c, double& depth, double n[3],
                      double w[3]);

/// A point p in front of triangle (a, b, c), over the triangle itself (its projection inside
/// it, to round-off): the face it would enter.
bool node_before_face(const double* p, const double* a, const double* b, const double* c);

}  // namespace sh
