// Where a point of the world lies in a body's rest shape (its material frame).
#pragma once

#include "core/memory.hpp"

#include <cstdint>

namespace sh {

class Body;

/// Where a world point lies in a body's rest shape.
struct RestPoint {
    double position[3];     ///< the rest-shape position
    int32_t tet = -1;       ///< the tet it was mapped through; -1 for a body without tets
    double inside = 0.0;    ///< p's least barycentric weight in that tet: >= 0 inside the body,
                            ///< about minus its distance outside over the tet's size
};

/// The rest-shape positions of the count world points p (3 each) in body, into out[count]:
/// each through the affine map of the tet that contains it in the current configuration (or,
/// outside the body, of the tet it is least outside of: an extrapolation); for a body without
/// tets, its offset from the nearest node. Looks only at tets near the points: near all of
/// them together where they lie close (a blade's samples), else near each apart (the far
/// corners of a cut's triangles), whichever costs less.
void rest_points(const Body& body, const double* p, int count, RestPoint* out);

/// A stretch of a segment inside a tet, or outside it by less than some slack.
struct SegmentSpan {
    double from = 0.0, to = 0.0;  ///< its ends, as fractions of the segment (0 at a, 1 at b)
    int32_t tet = -1;             ///< the tet
};

/// The stretches of the segment a-b (world, current configuration) over which it lies inside
/// a tet of body, or outside by at most slack in barycentric weight (about that fraction of
/// the tet's size), one per such tet, among the tets near the segment (the box around it
/// grown by half its length; all the body's tets if none is near). Each tet's weights are
/// linear along the segment, so a tet costs two weight evaluations, however finely the
/// caller samples the segment. Nothing for a body without tets.
vec<SegmentSpan> segment_in_tets(const Body& body, const double a[3], const double b[3], double slack);

/// rest_points' positions alone, into out (3 each).
void to_rest_all(const Body& body, const double* p, int count, double* out);

}  // namespace sh
