// ShapeGeometry: the dimensions of a rigid shape in its local frame, as its kind's functions
// read them (shape_kind.hpp).
#pragma once

#include "collision/ball_core.hpp"
#include "collision/convex_hull.hpp"

namespace sh {

/// The fields of sh_shape a kind reads, validated, and what its kind derives from them. Each
/// kind fills and reads only its own fields.
struct ShapeGeometry {
    double radius = 0.0;          ///< sphere, capsule (m)
    BallCore balls;               ///< the balls its contact takes between nodes (Shape::ball_count)
    double half_length = 0.0;     ///< capsule: half its axis segment, along local z (m)
    double half_extents[3] = {};  ///< box: half widths along the local axes (m)
    ConvexHull hull;              ///< convex
    /// Half the thinnest width (m): a point moving less than this per query cannot cross the
    /// shape unseen. INFINITY for a plane; an estimate, never below the exact value, for a
    /// convex hull.
    double inner_radius = 0.0;
};

}  // namespace sh
