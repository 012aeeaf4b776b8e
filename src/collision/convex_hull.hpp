// ConvexHull: the convex hull of a point set, the data and point queries of the convex shape
// kind (convex_shape.cpp). A hull of up to kMaxExactHullPoints points answers point queries
// exactly from its facet planes; a larger one uses libccd's GJK/EPA (sim side only: EPA
// allocates inside libccd), bounded by a budget of support calls, with MPR and sampled
// directions as fallbacks; points within ~1e-6 of the hull's size from its surface may be
// reported outside (libccd's absolute tolerances).
#pragma once

#include "core/memory.hpp"

#include <cstdint>

namespace sh {

/// The convex hull of points in a shape's local frame. Empty until built.
class ConvexHull {
public:
    /// Validates and copies count points (3 coordinates each): SH_ERR_INVALID_ARGUMENT naming
    /// the field for NULL, fewer than 4, non-finite, too spread or (nearly) coplanar points.
    void build(const double* points, int32_t count);

    /// Half the thinnest width over the sampled directions (m): an estimate, never below the
    /// exact value (which is attained at a face normal or an edge-edge direction the samples
    /// may miss).
    double inner_radius() const { return inner_radius_; }

    /// The points, 3 per point.
    const vec<double>& points() const { return points_; }

    /// Index of the point farthest along direction d.
    int support_index(const double d[3]) const;

    /// True if point xl lies inside: then its depth (m) and the outward unit normal nl at the
    /// nearest surface point.
    bool penetrate(const double xl[3], double& depth, double nl[3]) const;

    /// From now on, point queries skip libccd's GJK/EPA, which allocates: MPR and the sampled
    /// directions give the depth (an upper bound, exact along the hull face MPR finds).
    void use_allocation_free_queries() { allocation_free_ = true; }

private:
    static constexpr int kMaxDirections = 17;       ///< sampled directions (see sample_directions)
    static constexpr int kMaxExactHullPoints = 64;  ///< facets by brute force up to this

    /// Local bounding box and the normalised copy of the points that libccd works on.
    void normalise();
    /// The normal of a large tetrahedron of the points (normalised frame); throws if its volume
    /// says the points are (nearly) all in one plane.
    void pivot_normal(double base_normal[3]) const;
    /// The sampled directions, the points' extent along them and inner_radius_.
    void sample_directions(const double base_normal[3]);
    /// planes_ from the points, for hulls of up to kMaxExactHullPoints points (larger ones keep
    /// libccd's point queries).
    void init_planes();
    /// Depth by the facet planes (exact_planes_).
    bool penetrate_facets(const double xl[3], double& depth, double nl[3]) const;
    /// Lowers the depth bound best (m) and its normal with libccd's answers; false if libccd
    /// finds xl outside. Defined in builds with libccd only.
    bool refine_with_ccd(const double xl[3], double& best, double best_normal[3]) const;

    vec<double> points_;  ///< 3 per point
    vec<double> planes_;  ///< facet planes, 4 numbers each (outward unit normal n, offset o: the
                          ///< hull is n . x <= o)
    bool exact_planes_ = false;     ///< planes_ are the hull's facets (point queries use them)
    bool allocation_free_ = false;  ///< no GJK/EPA (see use_allocation_free_queries)
    double inner_radius_ = 0.0;
    double local_lo_[3] = {}, local_hi_[3] = {};  ///< bounding box
    double dirs_[kMaxDirections][3] = {};         ///< sampled unit directions
    double dir_max_[kMaxDirections] = {};         ///< max over the points of dirs_[i] . p
    double dir_min_[kMaxDirections] = {};         ///< min over the points of dirs_[i] . p
    int dir_count_ = 0;
    double ccd_center_[3] = {};    ///< libccd works on (p - ccd_center_) / ccd_scale_ so that its
    double ccd_scale_ = 1.0;       ///< absolute tolerances are relative to the hull's size
    double ccd_centroid_[3] = {};  ///< mean of the points, normalised frame (MPR's centre)
    vec<double> ccd_points_;       ///< the points in that normalised frame
};

}  // namespace sh
