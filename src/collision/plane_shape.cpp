// The plane kind (obstacles only): the half-space below the plane z = 0 of its local frame,
// whose pose plane_pose() builds from a point and the world normal. A row of the shape table.
#include "collision/shape_kind.hpp"
#include "collision/unit_vector.hpp"
#include "core/error.hpp"
#include "core/vec3.hpp"

#include <cmath>

namespace sh {
namespace {

void plane_init(const sh_shape& def, ShapeGeometry& g) {
    double n[3] = {def.normal[0], def.normal[1], def.normal[2]};
    SH_REQUIRE(finite3(n) && normalize3(n), SH_ERR_INVALID_ARGUMENT,
               "shape.normal = (%g, %g, %g), must be finite and non-zero", def.normal[0], def.normal[1],
               def.normal[2]);
    g.inner_radius = INFINITY;
}

void plane_bounds(const ShapeGeometry&, const Pose& pose, double margin, double lo[3], double hi[3]) {
    // Infinite on every side, except along an axis the normal lies on: up to the plane there.
    const double ez[3] = {0.0, 0.0, 1.0};
    double nrm[3];
    pose.rotate(ez, nrm);
    for (int k = 0; k < 3; ++k) {
        lo[k] = -INFINITY;
        hi[k] = INFINITY;
    }
    for (int k = 0; k < 3; ++k) {
        const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        if (std::fabs(nrm[k1]) > 1e-12 || std::fabs(nrm[k2]) > 1e-12 || std::fabs(std::fabs(nrm[k]) - 1.0) > 1e-12)
            continue;
        if (nrm[k] > 0.0)
            hi[k] = pose.p[k] + margin;
        else
            lo[k] = pose.p[k] - margin;
    }
}

void plane_support(const ShapeGeometry&, const Pose& pose, const double[3], double out[3]) {
    for (int k = 0; k < 3; ++k) out[k] = pose.p[k];
}

bool plane_penetrate(const ShapeGeometry&, const Pose& pose, const double x[3], double& depth, double normal[3]) {
    const double ez[3] = {0.0, 0.0, 1.0};
    pose.rotate(ez, normal);
    normalize3(normal);
    const double d[3] = {x[0] - pose.p[0], x[1] - pose.p[1], x[2] - pose.p[2]};
    depth = -dot3(normal, d);
    return depth > 0.0;
}

}  // namespace

// No balls: a plane's depth is linear, so its nodes carry all of it.
extern const ShapeKind kPlaneShape = {SH_SHAPE_PLANE, "plane", true,         plane_init, plane_bounds,
                                      plane_support,  plane_penetrate, nullptr, nullptr};

Pose plane_pose(const double point[3], const double normal[3]) {
    double n[3] = {normal[0], normal[1], normal[2]};
    SH_REQUIRE(finite3(n) && normalize3(n), SH_ERR_INVALID_ARGUMENT,
               "shape.normal = (%g, %g, %g), must be finite and non-zero", normal[0], normal[1],
               normal[2]);
    SH_REQUIRE(finite3(point), SH_ERR_INVALID_ARGUMENT, "position = (%g, %g, %g) m, must be finite",
               point[0], point[1], point[2]);
    Pose pose;
    for (int k = 0; k < 3; ++k) pose.p[k] = point[k];
    // Shortest rotation taking +z to n: q ~ (1 + z.n, z x n) = (1 + n_z, -n_y, n_x, 0). Near
    // n = -z, 1 + n_z cancels; (n_x^2 + n_y^2) / (1 - n_z) is the same value without
    // cancellation. At exactly -z the rotation axis is undetermined: pi about x.
    const double w = n[2] >= 0.0 ? 1.0 + n[2] : (n[0] * n[0] + n[1] * n[1]) / (1.0 - n[2]);
    double q[4] = {w, -n[1], n[0], 0.0};
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    if (len > 1e-150) {
        for (int k = 0; k < 4; ++k) pose.q[k] = q[k] / len;
    } else {
        pose.q[0] = 0.0;
        pose.q[1] = 1.0;
        pose.q[2] = 0.0;
        pose.q[3] = 0.0;
    }
    return pose;
}

}  // namespace sh
