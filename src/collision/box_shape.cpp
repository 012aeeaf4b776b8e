// The box kind: half_extents along the local axes, centred on the pose. A row of the shape
// table.
#include "collision/shape_kind.hpp"
#include "core/error.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

bool box_penetrate(const ShapeGeometry& g, const Pose& pose, const double x[3], double& depth, double normal[3]);

void box_init(const sh_shape& def, ShapeGeometry& g) {
    for (int k = 0; k < 3; ++k) {
        SH_REQUIRE(std::isfinite(def.half_extents[k]) && def.half_extents[k] > 0.0, SH_ERR_INVALID_ARGUMENT,
                   "shape.half_extents[%d] = %g m, must be finite and > 0", k, def.half_extents[k]);
        g.half_extents[k] = def.half_extents[k];
    }
    g.inner_radius = std::min({g.half_extents[0], g.half_extents[1], g.half_extents[2]});
    double corners[8][3];
    for (int c = 0; c < 8; ++c)
        for (int k = 0; k < 3; ++k) corners[c][k] = (c >> k & 1) ? g.half_extents[k] : -g.half_extents[k];
    inscribe_ball_core(g.balls, corners[0], 8, box_penetrate, g);
}

void box_bounds(const ShapeGeometry& g, const Pose& pose, double margin, double lo[3], double hi[3]) {
    double R[3][3];
    pose.rotation_matrix(R);
    double reach[3];
    for (int k = 0; k < 3; ++k)
        reach[k] = std::fabs(R[k][0]) * g.half_extents[0] + std::fabs(R[k][1]) * g.half_extents[1] +
                   std::fabs(R[k][2]) * g.half_extents[2];
    centred_bounds(pose, reach, margin, lo, hi);
}

void box_support(const ShapeGeometry& g, const Pose& pose, const double dir[3], double out[3]) {
    double d[3];
    pose.unrotate(dir, d);
    double local[3];
    for (int k = 0; k < 3; ++k) local[k] = d[k] >= 0.0 ? g.half_extents[k] : -g.half_extents[k];
    pose.to_world(local, out);
}

bool box_penetrate(const ShapeGeometry& g, const Pose& pose, const double x[3], double& depth, double normal[3]) {
    double xl[3];
    pose.to_local(x, xl);
    int axis = 0;
    depth = INFINITY;
    for (int k = 0; k < 3; ++k) {
        const double slack = g.half_extents[k] - std::fabs(xl[k]);
        if (!(slack > 0.0)) return false;
        // Ties (e.g. the centre) go to the lower axis index among the smallest slacks; at the
        // centre the slack is the half extent: the thinnest axis, + side.
        if (slack < depth) {
            depth = slack;
            axis = k;
        }
    }
    double nl[3] = {0.0, 0.0, 0.0};
    nl[axis] = xl[axis] < 0.0 ? -1.0 : 1.0;
    pose.rotate(nl, normal);
    return true;
}

}  // namespace

// Between nodes, a box's contact takes the balls of its largest inscribed capsule: an exact
// excess over its facets' arrangement would jump or kink where its maximiser changes, which
// Newton does not survive. The capsule misses its edges and corners (a cube's is its inscribed
// ball): those sink between nodes until the capsule meets the face.
extern const ShapeKind kBoxShape = {SH_SHAPE_BOX,  "box",           false,          box_init,        box_bounds,
                                    box_support,   box_penetrate,   core_balls_near, core_ball_centre};

}  // namespace sh
