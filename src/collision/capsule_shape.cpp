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

// The longest capsule in radii: its balls (4 per radius) are summed on every evaluation.
constexpr double kMaxHalfLength = 1024.0;

void capsule_init(const sh_shape& def, ShapeGeometry& g) {
    g.radius = checked_radius(def);
    SH_REQUIRE(std::isfinite(def.half_length) && def.half_length >= 0.0, SH_ERR_INVALID_ARGUMENT,
               "shape.half_length = %g m, must be finite and >= 0", def.half_length);
    g.half_length = def.half_length;
    g.inner_radius = g.radius;
    // Balls at most half a radius apart from end to end: their union is the capsule but for
    // scallops of at most 3 % of the radius between them, which no ball's excess sees (each
    // one's maximiser is at the foot of its own centre).
    SH_REQUIRE(g.half_length <= kMaxHalfLength * g.radius, SH_ERR_INVALID_ARGUMENT,
               "shape.half_length = %g m is more than %g times shape.radius = %g m", g.half_length, kMaxHalfLength,
               g.radius);
    g.ball_count = 1 + static_cast<int>(std::ceil(4.0 * g.half_length / g.radius));
}

// Ball i's position along the axis (m).
double ball_axis(const ShapeGeometry& g, int i) {
    const int intervals = g.ball_count - 1;
    return intervals > 0 ? g.half_length * (2.0 * i - intervals) / intervals : 0.0;
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

void capsule_balls_near(const ShapeGeometry& g, const double x[3], double reach, int& first, int& last) {
    first = 0;
    last = -1;
    const double across2 = x[0] * x[0] + x[1] * x[1];
    if (!(across2 <= reach * reach)) return;
    const double along = std::sqrt(reach * reach - across2);
    const int intervals = g.ball_count - 1;
    if (intervals == 0) {
        last = std::fabs(x[2]) <= along ? 0 : -1;
        return;
    }
    const double spacing = 2.0 * g.half_length / intervals;
    const double lo = std::ceil((x[2] - along + g.half_length) / spacing);
    const double hi = std::floor((x[2] + along + g.half_length) / spacing);
    first = static_cast<int>(std::min(std::max(lo, 0.0), intervals + 1.0));
    last = static_cast<int>(std::min(std::max(hi, -1.0), static_cast<double>(intervals)));
}

void capsule_ball_centre(const ShapeGeometry& g, int i, double centre[3]) {
    centre[0] = centre[1] = 0.0;
    centre[2] = ball_axis(g, i);
}

}  // namespace

extern const ShapeKind kCapsuleShape = {SH_SHAPE_CAPSULE,   "capsule",          false,
                                        capsule_init,       capsule_bounds,     capsule_support,
                                        capsule_penetrate,  capsule_balls_near, capsule_ball_centre};

}  // namespace sh
