// Shape: a rigid convex collider (sphere, capsule, box, convex hull of points, plane) and its
// narrow-phase queries against points and triangles.
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

    /// True if the shape at pose reaches through the triangle (a, b, c) from its outer side:
    /// the shape's deepest point below the triangle's plane (outward normal (b - a) x (c - a))
    /// projects inside the triangle and lies depth > 0 below it, with the shape's centre
    /// (pose.p) on the outer side. Then out.normal is minus the triangle's unit outward normal
    /// (the push that moves the triangle out of the shape), out.point the deepest point's
    /// projection on the triangle and bary its barycentric weights (each >= 0, sum 1).
    /// Zero-area triangles and planes give false.
    bool penetrate_triangle(const Pose& pose, const double a[3], const double b[3], const double c[3],
                            Penetration& out, double bary[3]) const;

    /// True if the shape at pose reaches through the edge (a, b) where two surface triangles
    /// with unit outward normals n1 and n2 meet in a convex dihedral, in the edge's own region:
    /// over the directions m between n1 and n2 (perpendicular to the edge) the overlap
    /// m.a - min over the shape of m.s is least strictly between them (at n1 or n2 it is a
    /// face's, see penetrate_triangle), and positive there, the shape's deepest point along -m
    /// projects onto the segment and its centre is on the outer side. Then out.depth is that
    /// overlap, out.normal = -m (the push that moves the edge out of the shape), out.point the
    /// projected point and t its parameter from a (0) to b (1). Exact for spheres (m points
    /// from the edge to the centre); a one-dimensional search over m for the other shapes.
    /// Planes, zero-length edges and parallel normals give false.
    bool penetrate_edge(const Pose& pose, const double a[3], const double b[3], const double n1[3],
                        const double n2[3], Penetration& out, double& t) const;

    /// From now on, point queries on a convex hull skip libccd's GJK/EPA, which allocates:
    /// MPR and the sampled directions give the depth (an upper bound, exact along the hull
    /// face MPR finds). For the haptic step's own copy of a tool.
    void use_allocation_free_queries() { allocation_free_ = true; }

private:
    static constexpr int kMaxDirections = 17;  ///< convex: sampled directions (see shape.cpp)

    void init_convex(const sh_shape& def);
    /// Convex: index of the point farthest along local direction d.
    int convex_support_index(const double d[3]) const;
    /// Convex: penetration of local point xl (depth, local outward normal nl).
    bool penetrate_convex(const double xl[3], double& depth, double nl[3]) const;

    sh_shape_kind kind_;
    double radius_ = 0.0;
    double half_length_ = 0.0;
    double half_extents_[3] = {};
    vec<double> points_;  ///< convex: 3 per point, local frame
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
