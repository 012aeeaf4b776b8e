// Where a point of the world lies in a body's rest shape (its material frame).
#pragma once

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

/// The rest-shape position of world point p in body: through the affine map of the tet that
/// contains p in the current configuration (or, outside the body, of the tet p is least
/// outside of: an extrapolation); for a body without tets, p's offset from the nearest node.
RestPoint rest_point(const Body& body, const double p[3]);

/// rest_point of each of the count points p (3 each) into out[count], in one pass over the
/// tets (each tet's map is formed once for all the points).
void rest_points(const Body& body, const double* p, int count, RestPoint* out);

/// rest_point's position alone.
void to_rest(const Body& body, const double p[3], double out[3]);

/// to_rest of each of the count points p (3 each) into out (3 each), in one pass.
void to_rest_all(const Body& body, const double* p, int count, double* out);

}  // namespace sh
