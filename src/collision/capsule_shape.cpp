// The capsule kind: radius around the segment from -half_length to +half_length on the local
// z axis. A row of the shape table.
#include "collision/shape_kind.hpp"
#include "collision/unit_vector.hpp"
#include "core/error.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

void capsule_init(const sh_shape& def, ShapeGeometry& g) {
    g.radius = checked_radius(def);
    SH_REQUIRE(std::isfinite(def.half_length) && def.half_length >= 0.0, SH_ERR_INVALID_ARGUMENT,
               "shape.half_length = %g m, must be finite and >= 0", def.half_length);
    g.half_length = def.half_length;
    g.inner_radius = g.radius;
    SH_REQUIRE(g.half_length <= kMaxCoreHalfLength * g.radius, SH_ERR_INVALID_ARGUMENT,
               "shape.half_length = %g m is more than %g times shape.radius = %g m", g.half_length,
               kMaxCoreHalfLength, g.radius);
    const double centre[3] = {0.0, 0.0, 0.0}, axis[3] = {0.0, 0.0, 1.0};
    set_ball_core(g.balls, centre, axis, g.half_length, g.radius);
}

void capsule_bounds(const ShapeGeometry& g, const Pose& pose, double margin, double lo[3], double hi[3]) {
    const double half_axis[3] = {0.0, 0.0, g.half_length};
    double a[3];
    pose.rotate(half_axis, a);
    double reach[3] = {g.radius, g.radius, g.radius};
    for (int k = 0; k < 3; ++k) reach[k] += std::fabs(a[k]);
    centred_bounds(pose, reach, margin, lo, hi);
}

void capsule_support(const ShapeGeometry& g, const Pose& pose, const double dir[3], double out[3]) {
    double d[3];
    pose.unrotate(dir, d);
    const double z = d[2] >= 0.0 ? g.half_length : -g.half_length;
    if (!normalize3(d)) {
        d[0] = 1.0;
        d[1] = d[2] = 0.0;
    }
    const double local[3] = {g.radius * d[0], g.radius * d[1], z + g.radius * d[2]};
    pose.to_world(local, out);
}

bool capsule_penetrate(const ShapeGeometry& g, const Pose& pose, const double x[3], double& depth, double normal[3]) {
    double xl[3];
    pose.to_local(x, xl);
    const double t = std::min(std::max(xl[2], -g.half_length), g.half_length);
    double d[3] = {xl[0], xl[1], xl[2] - t};
    const double dist = norm3(d);
    depth = g.radius - dist;
    if (!(depth > 0.0)) return false;
    if (!(dist > 1e-12 * g.radius && normalize3(d))) {
        d[0] = 1.0;  // on the axis: the local x axis, perpendicular to it
        d[1] = d[2] = 0.0;
    }
    pose.rotate(d, normal);
    return true;
}

}  // namespace

extern const ShapeKind kCapsuleShape = {SH_SHAPE_CAPSULE,   "capsule",          false,
                                        capsule_init,       capsule_bounds,     capsule_support,
                                        capsule_penetrate,  core_balls_near,    core_ball_centre};

}  // namespace sh
