// The sphere kind: radius around the pose's position. A row of the shape table.
#include "collision/ball_excess.hpp"
#include "collision/shape_kind.hpp"
#include "collision/unit_vector.hpp"
#include "core/vec3.hpp"

namespace sh {
namespace {

void sphere_init(const sh_shape& def, ShapeGeometry& g) {
    g.radius = checked_radius(def);
    g.inner_radius = g.radius;
    const double centre[3] = {0.0, 0.0, 0.0}, axis[3] = {0.0, 0.0, 1.0};
    set_ball_core(g.balls, centre, axis, 0.0, g.radius);
    g.balls.is_shape = true;
}

void sphere_bounds(const ShapeGeometry& g, const Pose& pose, double margin, double lo[3], double hi[3]) {
    const double reach[3] = {g.radius, g.radius, g.radius};
    centred_bounds(pose, reach, margin, lo, hi);
}

void sphere_support(const ShapeGeometry& g, const Pose& pose, const double dir[3], double out[3]) {
    double u[3] = {dir[0], dir[1], dir[2]};
    if (!normalize3(u)) {
        const double ex[3] = {1.0, 0.0, 0.0};
        pose.rotate(ex, u);
    }
    for (int k = 0; k < 3; ++k) out[k] = pose.p[k] + g.radius * u[k];
}

bool sphere_penetrate(const ShapeGeometry& g, const Pose& pose, const double x[3], double& depth, double normal[3]) {
    depth = ball_depth(pose.p, g.radius, pose, x, normal);
    return depth > 0.0;
}

}  // namespace

extern const ShapeKind kSphereShape = {SH_SHAPE_SPHERE, "sphere", false,       sphere_init,      sphere_bounds,
                                       sphere_support,  sphere_penetrate, core_balls_near,  core_ball_centre};

}  // namespace sh
