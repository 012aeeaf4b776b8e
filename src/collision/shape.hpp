// Shape: a rigid convex collider (sphere, capsule, box, convex hull of points, plane) and its
// narrow-phase queries against points and surface simplices.
#pragma once

#include "collision/pose.hpp"
#include "core/memory.hpp"

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

/// A rigid shape in its local frame. Sphere and capsule are centred at the origin, the capsule
/// along local z; the box is centred with half_extents; a convex hull's points are given in the
/// local frame; a plane is the half-space below the plane z = 0 of its local frame (its
/// outward normal is local +z).
class Shape {
public:
    /// Validates and copies def's shape (SH_ERR_INVALID_ARGUMENT naming the field for
    /// zero-size, non-finite or flat shapes; SH_ERR_UNSUPPORTED for a convex hull without
    /// libccd). For a plane, `normal` is the world normal: the local frame's z.
    explicit Shape(const sh_shape& def);

    sh_shape_kind kind() const { return kind_; }

    /// Half the thinnest width of the shape (m): a point moving less than this per query
    /// cannot cross it unseen. INFINITY for a plane. For a convex hull it is an estimate (the
    /// thinnest width over a fixed set of sampled directions, so never below the exact value).
    double inner_radius() const { return inner_radius_; }

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
    /// Sphere: the best of the triangle's interior stationary point (on the ray from the
    /// centre's foot against the interpolant's slope), its edges' and its corners, to round-off.
    /// True if the maximum is > 0. The other kinds give false: a plane's depth is linear, so
    /// its nodes carry all of it; capsules, boxes and convex hulls have no excess yet (see
    /// simplex_excess.cpp).
    bool deepest_excess(const Pose& pose, const double* const points[3], const double node_energy[3], int count,
                        const DepthPotential& psi, SimplexExcess& out) const;

    /// Sphere and capsule radius (m); 0 for the other kinds.
    double radius() const { return radius_; }

    /// From now on, point queries on a convex hull skip libccd's GJK/EPA, which allocates:
    /// MPR and the sampled directions give the depth (an upper bound, exact along the hull
    /// face MPR finds). For the haptic step's own copy of a tool.
    void use_allocation_free_queries() { allocation_free_ = true; }

private:
    static constexpr int kMaxDirections = 17;  ///< convex: sampled directions (see shape.cpp)
    static constexpr int kMaxExactHullPoints = 64;  ///< convex: facets by brute force up to this

    void init_convex(const sh_shape& def);
    /// Convex: planes_ from the points, for hulls of up to kMaxExactHullPoints points (larger
    /// ones keep libccd's point queries).
    void init_convex_planes();
    /// Convex: index of the point farthest along local direction d.
    int convex_support_index(const double d[3]) const;
    /// Convex: penetration of local point xl (depth, local outward normal nl).
    bool penetrate_convex(const double xl[3], double& depth, double nl[3]) const;

    sh_shape_kind kind_;
    double radius_ = 0.0;
    double half_length_ = 0.0;
    double half_extents_[3] = {};
    vec<double> points_;  ///< convex: 3 per point, local frame
    vec<double> planes_;  ///< convex: facet planes in the local frame, 4 numbers each (outward
                          ///< unit normal n, offset o: the hull is n . x <= o)
    bool exact_planes_ = false;  ///< planes_ are the hull's facets (point queries use them)
    double inner_radius_ = 0.0;
    bool allocation_free_ = false;  ///< convex: no GJK/EPA (see use_allocation_free_queries)
    // convex only:
    double local_lo_[3] = {}, local_hi_[3] = {};  ///< bounding box in the local frame
    double dirs_[kMaxDirections][3] = {};         ///< sampled unit directions, local frame
    double dir_max_[kMaxDirections] = {};         ///< max over the points of dirs_[i] . p
    double dir_min_[kMaxDirections] = {};         ///< min over the points of dirs_[i] . p
    int dir_count_ = 0;
    double ccd_center_[3] = {};  ///< libccd works on (p - ccd_center_) / ccd_scale_ so that its
    double ccd_scale_ = 1.0;     ///< absolute tolerances are relative to the hull's size
    double ccd_centroid_[3] = {};  ///< mean of the points, normalised frame (MPR's centre)
    vec<double> ccd_points_;     ///< the points in that normalised frame
};

/// Pose of a plane through point with outward normal n (normalised here): local z = n.
Pose plane_pose(const double point[3], const double normal[3]);

}  // namespace sh
