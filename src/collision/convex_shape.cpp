// The convex kind: the convex hull of points given in the local frame (ConvexHull), which
// needs libccd. A row of the shape table.
#include "collision/shape_kind.hpp"
#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace sh {
namespace {

bool convex_penetrate(const ShapeGeometry& g, const Pose& pose, const double x[3], double& depth, double normal[3]);

void convex_init(const sh_shape& def, ShapeGeometry& g) {
#ifndef SOFTHAP_WITH_CCD
    require(false, SH_ERR_UNSUPPORTED, "convex shapes need libccd (built with SOFTHAP_WITH_CCD=OFF)");
#endif
    g.hull.build(def.points, def.point_count);
    g.inner_radius = g.hull.inner_radius();
    inscribe_ball_core(g.balls, g.hull.points().data(), static_cast<int>(g.hull.points().size() / 3), convex_penetrate, g);
}

void convex_bounds(const ShapeGeometry& g, const Pose& pose, double margin, double lo[3], double hi[3]) {
    double R[3][3];
    pose.rotation_matrix(R);
    for (int k = 0; k < 3; ++k) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    const double* pts = g.hull.points().data();
    const size_t n = g.hull.points().size() / 3;
    for (size_t i = 0; i < n; ++i) {
        const double* p = pts + 3 * i;
        for (int k = 0; k < 3; ++k) {
            const double w = R[k][0] * p[0] + R[k][1] * p[1] + R[k][2] * p[2];
            lo[k] = std::min(lo[k], w);
            hi[k] = std::max(hi[k], w);
        }
    }
    for (int k = 0; k < 3; ++k) {
        lo[k] += pose.p[k];
        hi[k] += pose.p[k];
        lo[k] -= margin;
        hi[k] += margin;
    }
}

void convex_support(const ShapeGeometry& g, const Pose& pose, const double dir[3], double out[3]) {
    double d[3];
    pose.unrotate(dir, d);
    const int i = g.hull.support_index(d);
    pose.to_world(g.hull.points().data() + 3 * static_cast<size_t>(i), out);
}

bool convex_penetrate(const ShapeGeometry& g, const Pose& pose, const double x[3], double& depth, double normal[3]) {
    double xl[3], nl[3];
    pose.to_local(x, xl);
    if (!g.hull.penetrate(xl, depth, nl)) return false;
    pose.rotate(nl, normal);
    return true;
}

}  // namespace

// Between nodes, as for the box, the balls of its largest inscribed capsule.
extern const ShapeKind kConvexShape = {SH_SHAPE_CONVEX,  "convex",         false,           convex_init,     convex_bounds,
                                       convex_support,   convex_penetrate, core_balls_near, core_ball_centre};

}  // namespace sh
