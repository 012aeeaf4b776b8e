// ConvexHull construction: validation, the normalised frame libccd works in, the flatness test
// and the sampled directions of the cheap point-query rejects.
#include "collision/convex_hull.hpp"

#include "collision/unit_vector.hpp"
#include "core/error.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace sh {
namespace {

/// Eigenvectors (columns of V) of the symmetric 3x3 matrix A (destroyed), cyclic Jacobi.
void symmetric_eigenvectors(double A[3][3], double V[3][3]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) V[i][j] = i == j ? 1.0 : 0.0;
    static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int sweep = 0; sweep < 32; ++sweep) {
        const double off = A[0][1] * A[0][1] + A[0][2] * A[0][2] + A[1][2] * A[1][2];
        const double diag = A[0][0] * A[0][0] + A[1][1] * A[1][1] + A[2][2] * A[2][2];
        if (!(off > 1e-30 * diag)) break;
        for (const auto& pq : pairs) {
            const int p = pq[0], q = pq[1];
            if (A[p][q] == 0.0) continue;
            const double theta = (A[q][q] - A[p][p]) / (2.0 * A[p][q]);
            const double t = std::fabs(theta) > 1e150
                                 ? 0.5 / theta
                                 : (theta >= 0.0 ? 1.0 : -1.0) /
                                       (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
            const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
            for (int k = 0; k < 3; ++k) {  // A <- A J, V <- V J
                const double akp = A[k][p], akq = A[k][q];
                A[k][p] = c * akp - s * akq;
                A[k][q] = s * akp + c * akq;
                const double vkp = V[k][p], vkq = V[k][q];
                V[k][p] = c * vkp - s * vkq;
                V[k][q] = s * vkp + c * vkq;
            }
            for (int k = 0; k < 3; ++k) {  // A <- J^T A
                const double apk = A[p][k], aqk = A[q][k];
                A[p][k] = c * apk - s * aqk;
                A[q][k] = s * apk + c * aqk;
            }
        }
    }
}

}  // namespace

void ConvexHull::build(const double* points, int32_t count) {
    SH_REQUIRE(points != nullptr, SH_ERR_INVALID_ARGUMENT,
               "shape.points is NULL: a convex shape needs point_count x 3 coordinates");
    SH_REQUIRE(count >= 4, SH_ERR_INVALID_ARGUMENT, "shape.point_count = %d, must be >= 4",
               static_cast<int>(count));
    const int n = count;
    for (int i = 0; i < n; ++i) {
        const double* p = points + 3 * static_cast<size_t>(i);
        SH_REQUIRE(finite3(p), SH_ERR_INVALID_ARGUMENT, "shape.points[%d] = (%g, %g, %g) is not finite",
                   i, p[0], p[1], p[2]);
    }
    points_.assign(points, points + 3 * static_cast<size_t>(n));
    normalise();
    double base_normal[3];
    pivot_normal(base_normal);
    sample_directions(base_normal);
    init_planes();
}

void ConvexHull::normalise() {
    const double* pts = points_.data();
    const int n = static_cast<int>(points_.size() / 3);
    for (int k = 0; k < 3; ++k) local_lo_[k] = local_hi_[k] = pts[k];
    for (int i = 1; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            local_lo_[k] = std::min(local_lo_[k], pts[3 * i + k]);
            local_hi_[k] = std::max(local_hi_[k], pts[3 * i + k]);
        }
    const double extent[3] = {local_hi_[0] - local_lo_[0], local_hi_[1] - local_lo_[1],
                              local_hi_[2] - local_lo_[2]};
    const double diagonal = norm3(extent);
    SH_REQUIRE(std::isfinite(diagonal), SH_ERR_INVALID_ARGUMENT,
               "shape.points span a bounding box of diagonal %g m: too large", diagonal);
    // libccd's tolerances are absolute: it gets the points scaled to a unit diagonal (and so
    // does the flatness test).
    ccd_scale_ = diagonal > 0.0 ? diagonal : 1.0;
    for (int k = 0; k < 3; ++k) ccd_center_[k] = 0.5 * (local_lo_[k] + local_hi_[k]);
    ccd_points_.resize(points_.size());
    for (size_t j = 0; j < points_.size(); ++j)
        ccd_points_[j] = (points_[j] - ccd_center_[j % 3]) / ccd_scale_;
}

void ConvexHull::pivot_normal(double base_normal[3]) const {
    // A large tetrahedron by farthest-point pivots, O(n). Its volume is within a constant
    // factor of the largest one among the points. i0, i1: the extremes along the bounding
    // box's longest axis; i2: farthest from their line; i3: farthest from the plane.
    const double* u = ccd_points_.data();
    const int n = static_cast<int>(ccd_points_.size() / 3);
    const double extent[3] = {local_hi_[0] - local_lo_[0], local_hi_[1] - local_lo_[1],
                              local_hi_[2] - local_lo_[2]};
    const bool has_size = norm3(extent) > 0.0;
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (extent[k] > extent[axis]) axis = k;
    int i0 = 0, i1 = 0;
    for (int i = 1; i < n; ++i) {
        if (u[3 * i + axis] < u[3 * i0 + axis]) i0 = i;
        if (u[3 * i + axis] > u[3 * i1 + axis]) i1 = i;
    }
    const double* u0 = u + 3 * static_cast<size_t>(i0);
    const double e1[3] = {u[3 * i1] - u0[0], u[3 * i1 + 1] - u0[1], u[3 * i1 + 2] - u0[2]};
    int i2 = i0;
    double best = -1.0;
    for (int i = 0; i < n; ++i) {
        const double d[3] = {u[3 * i] - u0[0], u[3 * i + 1] - u0[1], u[3 * i + 2] - u0[2]};
        double c[3];
        cross3(e1, d, c);
        const double c2 = dot3(c, c);
        if (c2 > best) {
            best = c2;
            i2 = i;
        }
    }
    const double e2[3] = {u[3 * i2] - u0[0], u[3 * i2 + 1] - u0[1], u[3 * i2 + 2] - u0[2]};
    cross3(e1, e2, base_normal);
    double six_volume = 0.0;
    for (int i = 0; i < n; ++i) {
        const double d[3] = {u[3 * i] - u0[0], u[3 * i + 1] - u0[1], u[3 * i + 2] - u0[2]};
        six_volume = std::max(six_volume, std::fabs(dot3(base_normal, d)));
    }
    // In the normalised frame the diagonal is 1: volume > 1e-9 diagonal^3.
    SH_REQUIRE(has_size && six_volume / 6.0 > 1e-9, SH_ERR_INVALID_ARGUMENT,
               "shape.points are (nearly) all in one plane: a convex shape needs volume");
}

void ConvexHull::sample_directions(const double base_normal[3]) {
    // 3 axes, 6 face diagonals, 4 body diagonals of the local frame, the point set's 3
    // principal axes and the pivot tetrahedron's base normal (which is close to a thin hull's
    // thin direction).
    static const double fixed[13][3] = {
        {1, 0, 0}, {0, 1, 0}, {0, 0, 1},  {1, 1, 0},  {1, -1, 0}, {1, 0, 1},  {1, 0, -1},
        {0, 1, 1}, {0, 1, -1}, {1, 1, 1}, {1, 1, -1}, {1, -1, 1}, {1, -1, -1}};
    const double* u = ccd_points_.data();
    const double* pts = points_.data();
    const int n = static_cast<int>(points_.size() / 3);
    dir_count_ = 0;
    auto add_direction = [this](const double d[3]) {
        double v[3] = {d[0], d[1], d[2]};
        if (dir_count_ < kMaxDirections && normalize3(v)) {
            for (int k = 0; k < 3; ++k) dirs_[dir_count_][k] = v[k];
            ++dir_count_;
        }
    };
    for (const auto& d : fixed) add_direction(d);
    double mean[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) mean[k] += u[3 * i + k];
    for (int k = 0; k < 3; ++k) {
        mean[k] /= n;
        ccd_centroid_[k] = mean[k];  // a convex combination with all weights > 0: interior
    }
    double cov[3][3] = {};
    for (int i = 0; i < n; ++i) {
        const double d[3] = {u[3 * i] - mean[0], u[3 * i + 1] - mean[1], u[3 * i + 2] - mean[2]};
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) cov[r][c] += d[r] * d[c];
    }
    double V[3][3];
    symmetric_eigenvectors(cov, V);
    for (int c = 0; c < 3; ++c) {
        const double axis_c[3] = {V[0][c], V[1][c], V[2][c]};
        add_direction(axis_c);
    }
    add_direction(base_normal);

    double min_width = INFINITY;
    for (int j = 0; j < dir_count_; ++j) {
        double hi = -INFINITY, lo = INFINITY;
        for (int i = 0; i < n; ++i) {
            const double s = dot3(dirs_[j], pts + 3 * static_cast<size_t>(i));
            hi = std::max(hi, s);
            lo = std::min(lo, s);
        }
        dir_max_[j] = hi;
        dir_min_[j] = lo;
        min_width = std::min(min_width, hi - lo);
    }
    inner_radius_ = 0.5 * min_width;
}

int ConvexHull::support_index(const double d[3]) const {
    const double* pts = points_.data();
    const int n = static_cast<int>(points_.size() / 3);
    int best = 0;
    double best_dot = -INFINITY;
    for (int i = 0; i < n; ++i) {
        const double s = dot3(d, pts + 3 * static_cast<size_t>(i));
        if (s > best_dot) {
            best_dot = s;
            best = i;
        }
    }
    return best;
}

}  // namespace sh
