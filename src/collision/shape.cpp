// Shape: each query goes to the kind's row of the shape table; what is common to every kind
// (the depth and normal checks of a point query, the excess's frames) is done here.
#include "collision/shape.hpp"

#include "collision/shape_kind.hpp"
#include "collision/unit_vector.hpp"
#include "core/enum_value.hpp"
#include "core/error.hpp"

#include <cmath>

namespace sh {

Shape::Shape(const sh_shape& def) : row_(&shape_kind(enum_value(def.kind))), kind_(row_->kind) {
    row_->init(def, geometry_);
}

bool Shape::is_half_space() const { return row_->half_space; }

void Shape::bounds(const Pose& pose, double margin, double lo[3], double hi[3]) const {
    row_->bounds(geometry_, pose, margin, lo, hi);
}

void Shape::support(const Pose& pose, const double dir[3], double out[3]) const {
    row_->support(geometry_, pose, dir, out);
}

bool Shape::penetrate_point(const Pose& pose, const double x[3], Penetration& out) const {
    double depth = 0.0;
    double normal[3] = {0.0, 0.0, 1.0};
    if (!row_->penetrate(geometry_, pose, x, depth, normal)) return false;
    if (!normalize3(normal) || !std::isfinite(depth)) return false;  // only for non-finite poses
    out.depth = depth;
    for (int k = 0; k < 3; ++k) {
        out.normal[k] = normal[k];
        out.point[k] = x[k];
    }
    return true;
}

void Shape::ball_centre(const Pose& pose, int i, double out[3]) const {
    double local[3];
    row_->ball_centre(geometry_, i, local);
    pose.to_world(local, out);
}

BallRow Shape::ball_row(const Pose& pose) const {
    BallRow row;
    row.count = ball_count();
    if (row.count == 0) return row;
    ball_centre(pose, 0, row.first);
    if (row.count == 1) return row;
    ball_centre(pose, row.count - 1, row.step);
    for (int k = 0; k < 3; ++k) row.step[k] = (row.step[k] - row.first[k]) / (row.count - 1);
    return row;
}

void Shape::balls_near(const Pose& pose, const double x[3], double reach, int& first, int& last) const {
    first = 0;
    last = -1;
    if (!row_->balls_near) return;
    double local[3];
    pose.to_local(x, local);
    row_->balls_near(geometry_, local, reach, first, last);
}

double checked_radius(const sh_shape& def) {
    SH_REQUIRE(std::isfinite(def.radius) && def.radius > 0.0, SH_ERR_INVALID_ARGUMENT,
               "shape.radius = %g m, must be finite and > 0", def.radius);
    return def.radius;
}

}  // namespace sh
