// CutSurface: the triangulated surface a cut follows, checked, welded and consistently
// oriented, with the queries the cut asks of it.
#pragma once

#include "core/memory.hpp"

#include <cstdint>

namespace sh {

/// A cut surface: triangles in the world frame, oriented consistently across shared edges so
/// that "the side a normal points to" means the same on both sides of every edge.
class CutSurface {
public:
    /// Copies triangles[0..9 count); throws SH_ERR_INVALID_ARGUMENT naming the first triangle
    /// with a non-finite corner or zero area, or count < 1.
    CutSurface(const double* triangles, int32_t count);

    /// Where the segment from p to q first meets the surface: true with t in [0, 1] (the point
    /// p + t (q - p)) and the triangle met; a segment within the plane of a triangle does not
    /// meet it.
    bool first_hit(const double* p, const double* q, double& t, int32_t& triangle) const;

    /// The signed distance of p from the surface along the unit normal of its nearest triangle
    /// (positive on the side the normals point to); triangle receives the one nearest.
    double signed_distance(const double* p, int32_t& triangle) const;

    /// Unit normal of triangle i.
    const double* normal(int32_t i) const { return &normals_[3 * static_cast<size_t>(i)]; }

    /// Corner k of triangle i.
    const double* corner(int32_t i, int k) const { return &corners_[9 * static_cast<size_t>(i) + 3 * k]; }

    int32_t triangle_count() const { return static_cast<int32_t>(normals_.size() / 3); }

    /// Lower and upper corners of the box around every triangle (m).
    const double* lower() const { return lower_; }
    const double* upper() const { return upper_; }

    /// True if the box [lo, hi] grown by margin touches triangle i's box.
    bool box_touches(int32_t i, const double* lo, const double* hi, double margin) const;

private:
    /// Flips triangles so that neighbours across welded edges agree in orientation.
    void orient();

    vec<double> corners_;   ///< 9 per triangle
    vec<double> normals_;   ///< 3 per triangle, unit
    vec<double> boxes_;     ///< 6 per triangle: lower then upper corner
    double lower_[3], upper_[3];
};

}  // namespace sh
