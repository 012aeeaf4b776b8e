// Where a point of the world lies in a body's rest shape (its material frame).
#pragma once

namespace sh {

class Body;

/// The rest-shape position of world point p in body: through the affine map of the tet that
/// contains p in the current configuration (or, outside the body, of the tet p is least
/// outside of: an extrapolation); for a body without tets, p's offset from the nearest node.
void to_rest(const Body& body, const double p[3], double out[3]);

}  // namespace sh
