// Unit vectors for the shape kinds' normals and directions.
#pragma once

#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

/// Scales v to unit length (safe for tiny and huge magnitudes). Returns false and leaves v
/// untouched when v is zero or not finite.
inline bool normalize3(double v[3]) {
    const double m = std::max({std::fabs(v[0]), std::fabs(v[1]), std::fabs(v[2])});
    if (!(m > 0.0) || !std::isfinite(m)) return false;
    const double s[3] = {v[0] / m, v[1] / m, v[2] / m};
    const double len = norm3(s);
    for (int k = 0; k < 3; ++k) v[k] = s[k] / len;
    return true;
}

}  // namespace sh
