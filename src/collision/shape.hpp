// Shape: a rigid convex collider (sphere, capsule, box, convex hull of points, plane) and its
// narrow-phase queries against points and surface simplices, each answered by its kind's
// functions (shape_kind.hpp).
#pragma once

#include "collision/pose.hpp"
#include "collision/shape_geometry.hpp"

#include <softhap/softhap.h>

namespace sh {

/// Where a point or triangle penetrates a shape.
struct Penetration {
    double depth = 0.0;     ///< how far inside (m), > 0 when reported
    double normal[3] = {};  ///< unit direction that pushes the body out of the shape (world)
    double point[3] = {};   ///< the touched point on the body (world)
};

/// A contact potential psi of the depth d (m): psi(d) (J), psi'(d) (N), psi''(d) (N/m), all
/// zero for d <= 0; psi' >= 0 and psi convex.
class DepthPotential {
public:
    virtual ~DepthPotential() = default;
    virtual double energy(double depth) const = 0;
    virtual double force(double depth) const = 0;
    virtual double stiffness(double depth) const = 0;
};

/// Where a shape's contact potential exceeds most, over a surface edge or triangle, the linear
/// interpolant of its nodes' own potentials (Shape::deepest_excess).
struct SimplexExcess {
    double value = 0.0;      ///< max over the simplex of psi(depth(x)) - sum_i w_i psi_i (J)
    double depth = 0.0;      ///< the shape's depth at the maximiser (m)
    double weights[3] = {};  ///< the maximiser's barycentric weights (count of them used)
    double point[3] = {};    ///< the maximiser (world)
    double normal[3] = {};   ///< unit push out of the shape at the maximiser (world)
    double push[3] = {};     ///< minus the gradient of psi(depth) at the maximiser for the
                             ///< simplex moved rigidly (N, world): psi' times the normal
};

struct ShapeKind;

/// A rigid shape in its local frame. Sphere and capsule are centred at the origin, the capsule
/// along local z; the box is centred with half_extents; a convex hull's points are given in the
/// local frame; a plane is the half-space below the plane z = 0 of its local frame (its
/// outward normal is local +z). Each query goes to its kind's row of the shape table
/// (shape_kind.hpp).
class Shape {
public:
    /// Validates and copies def's shape (SH_ERR_INVALID_ARGUMENT naming the field for an
    /// unknown kind, zero-size, non-finite or flat shapes; SH_ERR_UNSUPPORTED for a convex hull
    /// without libccd). For a plane, `normal` is the world normal: the local frame's z.
    explicit Shape(const sh_shape& def);

    sh_shape_kind kind() const { return kind_; }

    /// True for an unbounded half-space (a plane; see ShapeKind::half_space).
    bool is_half_space() const;

    /// True if the kind has an excess solver (deepest_excess can be > 0).
    bool has_excess() const;

    /// Half the thinnest width of the shape (m): a point moving less than this per query
    /// cannot cross it unseen. INFINITY for a plane. For a convex hull it is an estimate (the
    /// thinnest width over a fixed set of sampled directions, so never below the exact value).
    double inner_radius() const { return geometry_.inner_radius; }

    /// World-frame bounds of the shape at pose, grown by margin (m); a plane's are infinite
    /// on the sides it is unbounded.
    void bounds(const Pose& pose, double margin, double lo[3], double hi[3]) const;

    /// The shape's farthest point in world direction dir (not necessarily unit), at pose.
    void support(const Pose& pose, const double dir[3], double out[3]) const;

    /// True if world point x lies inside the shape at pose (depth > 0); then out holds the
    /// depth, the outward normal at the nearest surface point and out.point = x.
    bool penetrate_point(const Pose& pose, const double x[3], Penetration& out) const;

    /// Maximises psi(depth(x)) - sum_i w_i node_energy[i] over the simplex of `count` (2 or 3)
    /// world points, x = sum_i w_i points[i], depth(x) the shape's penetration depth at x.
    /// True if the maximum is > 0. Each kind has its own solver; the sphere's is exact (see
    /// ball_excess.hpp); a kind without one gives false, its nodes carrying its contact.
    bool deepest_excess(const Pose& pose, const double* const points[3], const double node_energy[3], int count,
                        const DepthPotential& psi, SimplexExcess& out) const;

    /// From now on, point queries on a convex hull skip libccd's GJK/EPA, which allocates:
    /// MPR and the sampled directions give the depth (an upper bound, exact along the hull
    /// face MPR finds). For the haptic step's own copy of a tool.
    void use_allocation_free_queries() { geometry_.hull.use_allocation_free_queries(); }

private:
    const ShapeKind* row_;  ///< the kind's row of the shape table
    sh_shape_kind kind_;
    ShapeGeometry geometry_;
};

/// Pose of a plane through point with outward normal n (normalised here): local z = n.
Pose plane_pose(const double point[3], const double normal[3]);

}  // namespace sh
