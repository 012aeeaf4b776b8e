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
    /// psi'(d) and psi''(d) together, for a law that finds both at the price of one.
    virtual void force_and_stiffness(double depth, double& force, double& stiffness) const {
        force = this->force(depth);
        stiffness = this->stiffness(depth);
    }
};

struct ShapeKind;

/// A shape's balls (Shape::ball_count) in the world at one pose: evenly spaced from the first
/// centre by step.
struct BallRow {
    double first[3] = {0.0, 0.0, 0.0};  ///< ball 0's centre (m, world)
    double step[3] = {0.0, 0.0, 0.0};   ///< from one ball's centre to the next (m)
    int count = 0;
    /// The centre of ball i.
    void centre(int i, double out[3]) const {
        for (int k = 0; k < 3; ++k) out[k] = first[k] + i * step[k];
    }
};

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

    /// The number of balls whose union the contact potential's excess terms take between a
    /// body's nodes (shape_contact.hpp), evenly spaced along a segment, in order, at most half
    /// a radius apart (ball_core.hpp): 1 for a sphere; for a capsule, balls of its radius
    /// along its axis; for a box or a convex hull, those of its largest inscribed capsule
    /// along its longest axis; 0 for a plane, whose nodes carry all of its contact.
    int ball_count() const { return geometry_.balls.count; }

    /// The balls' radius (m).
    double ball_radius() const { return geometry_.balls.radius; }

    /// True if the one ball is the shape itself (a sphere): a point's depth in the shape is
    /// its depth in the ball.
    bool ball_is_shape() const { return geometry_.balls.is_shape; }

    /// True if the shape's excess is a smooth maximum over several balls (BallMix): two
    /// passes per evaluation, the balls' totals first.
    bool mixes_balls() const { return geometry_.balls.count > 1; }

    /// The world centre of ball i (0 <= i < ball_count()) at pose.
    void ball_centre(const Pose& pose, int i, double out[3]) const;

    /// All the balls' centres at pose.
    BallRow ball_row(const Pose& pose) const;

    /// The balls whose centres may lie within reach (m) of world point x at pose: from first
    /// to last (none if first > last, and for kinds without balls).
    void balls_near(const Pose& pose, const double x[3], double reach, int& first, int& last) const;

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
