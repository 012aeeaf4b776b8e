// Shape: validation, bounds, support mapping and the narrow-phase point queries of the rigid
// colliders. Analytic for sphere, capsule, box and plane. A convex hull of up to
// kMaxExactHullPoints points answers point queries exactly from its facet planes; a larger one
// uses libccd's GJK/EPA (sim side only: EPA allocates inside libccd), bounded by a budget of
// support calls, with MPR and sampled directions as fallbacks; points within ~1e-6 of the
// hull's size from its surface may be reported outside (libccd's absolute tolerances).
#include "collision/shape.hpp"

#include "core/error.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#ifdef SOFTHAP_WITH_CCD
#include <ccd/ccd.h>
#endif

namespace sh {
namespace {

/// Scales v to unit length (safe for tiny and huge magnitudes). Returns false and leaves v
/// untouched when v is zero or not finite.
bool normalize3(double v[3]) {
    const double m = std::max({std::fabs(v[0]), std::fabs(v[1]), std::fabs(v[2])});
    if (!(m > 0.0) || !std::isfinite(m)) return false;
    const double s[3] = {v[0] / m, v[1] / m, v[2] / m};
    const double len = norm3(s);
    for (int k = 0; k < 3; ++k) v[k] = s[k] / len;
    return true;
}

/// Columns of the pose's rotation matrix: R[i][j] = (R e_j)_i.
void rotation_matrix(const Pose& pose, double R[3][3]) {
    for (int j = 0; j < 3; ++j) {
        double e[3] = {0.0, 0.0, 0.0};
        e[j] = 1.0;
        double c[3];
        pose.rotate(e, c);
        for (int i = 0; i < 3; ++i) R[i][j] = c[i];
    }
}

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

#ifdef SOFTHAP_WITH_CCD
/// libccd object: a single point (normalised frame).
struct CcdPoint {
    double x[3];
};

/// libccd object: a point set (normalised frame), with a per-query budget of support calls.
/// libccd's EPA loop has no iteration limit (and can cycle); once the budget is spent the
/// hull's support returns the query point itself, so the Minkowski support is the origin,
/// which ends EPA (and MPR) at the current (unconverged) face. Every support point for a
/// non-zero direction lies on the hull's boundary, so the nearest one to the query point seen
/// so far bounds the depth. The struct lives on the query's stack.
struct CcdHull {
    const double* points;
    int count;
    const double* centroid;
    const CcdPoint* query;
    mutable long calls_left;
    mutable int nearest = -1;  ///< the support point nearest to the query point so far
    mutable double nearest_dist2 = INFINITY;
};

void ccd_hull_support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
    const CcdHull* hull = static_cast<const CcdHull*>(obj);
    if (hull->calls_left <= 0) {
        for (int k = 0; k < 3; ++k) out->v[k] = hull->query->x[k];
        return;
    }
    --hull->calls_left;
    int best = 0;
    double best_dot = -INFINITY;
    for (int i = 0; i < hull->count; ++i) {
        const double* p = hull->points + 3 * static_cast<size_t>(i);
        const double s = p[0] * dir->v[0] + p[1] * dir->v[1] + p[2] * dir->v[2];
        if (s > best_dot) {
            best_dot = s;
            best = i;
        }
    }
    const double* p = hull->points + 3 * static_cast<size_t>(best);
    for (int k = 0; k < 3; ++k) out->v[k] = p[k];
    const double len2 = dir->v[0] * dir->v[0] + dir->v[1] * dir->v[1] + dir->v[2] * dir->v[2];
    if (len2 > 0.0 && std::isfinite(len2)) {  // a true maximiser: on the boundary
        const double d[3] = {p[0] - hull->query->x[0], p[1] - hull->query->x[1],
                             p[2] - hull->query->x[2]};
        const double dist2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (dist2 < hull->nearest_dist2) {
            hull->nearest_dist2 = dist2;
            hull->nearest = best;
        }
    }
}

void ccd_point_support(const void* obj, const ccd_vec3_t*, ccd_vec3_t* out) {
    const CcdPoint* point = static_cast<const CcdPoint*>(obj);
    for (int k = 0; k < 3; ++k) out->v[k] = point->x[k];
}

void ccd_hull_center(const void* obj, ccd_vec3_t* out) {
    const CcdHull* hull = static_cast<const CcdHull*>(obj);
    for (int k = 0; k < 3; ++k) out->v[k] = hull->centroid[k];
}

void ccd_point_center(const void* obj, ccd_vec3_t* out) {
    const CcdPoint* point = static_cast<const CcdPoint*>(obj);
    for (int k = 0; k < 3; ++k) out->v[k] = point->x[k];
}
#endif

}  // namespace

Shape::Shape(const sh_shape& def) : kind_(def.kind) {
    switch (def.kind) {
        case SH_SHAPE_SPHERE:
            SH_REQUIRE(std::isfinite(def.radius) && def.radius > 0.0, SH_ERR_INVALID_ARGUMENT,
                       "shape.radius = %g m, must be finite and > 0", def.radius);
            radius_ = def.radius;
            inner_radius_ = radius_;
            break;
        case SH_SHAPE_CAPSULE:
            SH_REQUIRE(std::isfinite(def.radius) && def.radius > 0.0, SH_ERR_INVALID_ARGUMENT,
                       "shape.radius = %g m, must be finite and > 0", def.radius);
            SH_REQUIRE(std::isfinite(def.half_length) && def.half_length >= 0.0,
                       SH_ERR_INVALID_ARGUMENT, "shape.half_length = %g m, must be finite and >= 0",
                       def.half_length);
            radius_ = def.radius;
            half_length_ = def.half_length;
            inner_radius_ = radius_;
            break;
        case SH_SHAPE_BOX:
            for (int k = 0; k < 3; ++k) {
                SH_REQUIRE(std::isfinite(def.half_extents[k]) && def.half_extents[k] > 0.0,
                           SH_ERR_INVALID_ARGUMENT,
                           "shape.half_extents[%d] = %g m, must be finite and > 0", k,
                           def.half_extents[k]);
                half_extents_[k] = def.half_extents[k];
            }
            inner_radius_ = std::min({half_extents_[0], half_extents_[1], half_extents_[2]});
            break;
        case SH_SHAPE_CONVEX:
            init_convex(def);
            break;
        case SH_SHAPE_PLANE: {
            double n[3] = {def.normal[0], def.normal[1], def.normal[2]};
            SH_REQUIRE(finite3(n) && normalize3(n), SH_ERR_INVALID_ARGUMENT,
                       "shape.normal = (%g, %g, %g), must be finite and non-zero", def.normal[0],
                       def.normal[1], def.normal[2]);
            inner_radius_ = INFINITY;
            break;
        }
        default:
            SH_REQUIRE(false, SH_ERR_INVALID_ARGUMENT,
                       "shape.kind = %d is not a shape kind (SH_SHAPE_SPHERE..SH_SHAPE_PLANE)",
                       static_cast<int>(def.kind));
    }
}

void Shape::init_convex(const sh_shape& def) {
#ifndef SOFTHAP_WITH_CCD
    require(false, SH_ERR_UNSUPPORTED, "convex shapes need libccd (built with SOFTHAP_WITH_CCD=OFF)");
#endif
    SH_REQUIRE(def.points != nullptr, SH_ERR_INVALID_ARGUMENT,
               "shape.points is NULL: a convex shape needs point_count x 3 coordinates");
    SH_REQUIRE(def.point_count >= 4, SH_ERR_INVALID_ARGUMENT, "shape.point_count = %d, must be >= 4",
               static_cast<int>(def.point_count));
    const int n = def.point_count;
    for (int i = 0; i < n; ++i) {
        const double* p = def.points + 3 * static_cast<size_t>(i);
        SH_REQUIRE(finite3(p), SH_ERR_INVALID_ARGUMENT, "shape.points[%d] = (%g, %g, %g) is not finite",
                   i, p[0], p[1], p[2]);
    }
    points_.assign(def.points, def.points + 3 * static_cast<size_t>(n));
    const double* pts = points_.data();

    // Local bounding box and its diagonal (the shape's scale).
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

    // Normalised copy for libccd (its tolerances are absolute) and for the flatness test.
    const bool has_size = diagonal > 0.0;
    ccd_scale_ = has_size ? diagonal : 1.0;
    for (int k = 0; k < 3; ++k) ccd_center_[k] = 0.5 * (local_lo_[k] + local_hi_[k]);
    ccd_points_.resize(points_.size());
    for (size_t j = 0; j < points_.size(); ++j)
        ccd_points_[j] = (points_[j] - ccd_center_[j % 3]) / ccd_scale_;
    const double* u = ccd_points_.data();

    // Flatness: a large tetrahedron by farthest-point pivots, O(n). Its volume is within a
    // constant factor of the largest one among the points. i0, i1: the extremes along the
    // bounding box's longest axis; i2: farthest from their line; i3: farthest from the plane.
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
    double base_normal[3];
    cross3(e1, e2, base_normal);
    double six_volume = 0.0;
    for (int i = 0; i < n; ++i) {
        const double d[3] = {u[3 * i] - u0[0], u[3 * i + 1] - u0[1], u[3 * i + 2] - u0[2]};
        six_volume = std::max(six_volume, std::fabs(dot3(base_normal, d)));
    }
    // In the normalised frame the diagonal is 1: volume > 1e-9 diagonal^3.
    SH_REQUIRE(has_size && six_volume / 6.0 > 1e-9, SH_ERR_INVALID_ARGUMENT,
               "shape.points are (nearly) all in one plane: a convex shape needs volume");

    // Sampled directions: 3 axes, 6 face diagonals, 4 body diagonals of the local frame, the
    // point set's 3 principal axes and the pivot tetrahedron's base normal (which is close to
    // a thin hull's thin direction).
    static const double fixed[13][3] = {
        {1, 0, 0}, {0, 1, 0}, {0, 0, 1},  {1, 1, 0},  {1, -1, 0}, {1, 0, 1},  {1, 0, -1},
        {0, 1, 1}, {0, 1, -1}, {1, 1, 1}, {1, 1, -1}, {1, -1, 1}, {1, -1, -1}};
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
    // An estimate: the exact thinnest width is attained at a face normal or an edge-edge
    // direction, which the samples may miss, so this may exceed the exact value.
    inner_radius_ = 0.5 * min_width;
    init_convex_planes();
}

int Shape::convex_support_index(const double d[3]) const {
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

void Shape::bounds(const Pose& pose, double margin, double lo[3], double hi[3]) const {
    // Sphere, capsule and box are symmetric about their centre: a reach per axis.
    double reach[3] = {radius_, radius_, radius_};
    switch (kind_) {
        case SH_SHAPE_SPHERE:
            break;
        case SH_SHAPE_CAPSULE: {
            const double half_axis[3] = {0.0, 0.0, half_length_};
            double a[3];
            pose.rotate(half_axis, a);
            for (int k = 0; k < 3; ++k) reach[k] += std::fabs(a[k]);
            break;
        }
        case SH_SHAPE_BOX: {
            double R[3][3];
            rotation_matrix(pose, R);
            for (int k = 0; k < 3; ++k)
                reach[k] = std::fabs(R[k][0]) * half_extents_[0] + std::fabs(R[k][1]) * half_extents_[1] +
                           std::fabs(R[k][2]) * half_extents_[2];
            break;
        }
        case SH_SHAPE_CONVEX: {
            double R[3][3];
            rotation_matrix(pose, R);
            for (int k = 0; k < 3; ++k) {
                lo[k] = INFINITY;
                hi[k] = -INFINITY;
            }
            const double* pts = points_.data();
            const size_t n = points_.size() / 3;
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
            }
            break;
        }
        case SH_SHAPE_PLANE:
        default: {
            const double ez[3] = {0.0, 0.0, 1.0};
            double nrm[3];
            pose.rotate(ez, nrm);
            for (int k = 0; k < 3; ++k) {
                lo[k] = -INFINITY;
                hi[k] = INFINITY;
            }
            for (int k = 0; k < 3; ++k) {
                const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
                if (std::fabs(nrm[k1]) > 1e-12 || std::fabs(nrm[k2]) > 1e-12 ||
                    std::fabs(std::fabs(nrm[k]) - 1.0) > 1e-12)
                    continue;
                if (nrm[k] > 0.0)
                    hi[k] = pose.p[k] + margin;
                else
                    lo[k] = pose.p[k] - margin;
            }
            return;  // the infinite sides stay infinite
        }
    }
    for (int k = 0; k < 3; ++k) {
        if (kind_ != SH_SHAPE_CONVEX) {
            lo[k] = pose.p[k] - reach[k];
            hi[k] = pose.p[k] + reach[k];
        }
        lo[k] -= margin;
        hi[k] += margin;
    }
}

void Shape::support(const Pose& pose, const double dir[3], double out[3]) const {
    switch (kind_) {
        case SH_SHAPE_SPHERE: {
            double u[3] = {dir[0], dir[1], dir[2]};
            if (!normalize3(u)) {
                const double ex[3] = {1.0, 0.0, 0.0};
                pose.rotate(ex, u);
            }
            for (int k = 0; k < 3; ++k) out[k] = pose.p[k] + radius_ * u[k];
            return;
        }
        case SH_SHAPE_CAPSULE: {
            double d[3];
            pose.unrotate(dir, d);
            const double z = d[2] >= 0.0 ? half_length_ : -half_length_;
            if (!normalize3(d)) {
                d[0] = 1.0;
                d[1] = d[2] = 0.0;
            }
            const double local[3] = {radius_ * d[0], radius_ * d[1], z + radius_ * d[2]};
            pose.to_world(local, out);
            return;
        }
        case SH_SHAPE_BOX: {
            double d[3];
            pose.unrotate(dir, d);
            double local[3];
            for (int k = 0; k < 3; ++k) local[k] = d[k] >= 0.0 ? half_extents_[k] : -half_extents_[k];
            pose.to_world(local, out);
            return;
        }
        case SH_SHAPE_CONVEX: {
            double d[3];
            pose.unrotate(dir, d);
            const int i = convex_support_index(d);
            pose.to_world(points_.data() + 3 * static_cast<size_t>(i), out);
            return;
        }
        case SH_SHAPE_PLANE:
        default:
            for (int k = 0; k < 3; ++k) out[k] = pose.p[k];
            return;
    }
}

bool Shape::penetrate_convex(const double xl[3], double& depth, double nl[3]) const {
    // Cheap rejects: the local bounding box, then the slabs of the sampled directions. The
    // least slack over the slabs (an upper bound on the depth) is also the fallback answer.
    for (int k = 0; k < 3; ++k)
        if (!(xl[k] > local_lo_[k] && xl[k] < local_hi_[k])) return false;
    if (exact_planes_) {
        // A point inside a polytope is as deep as its nearest facet plane: exact, and the same
        // depth the contact potential's excess terms maximise (simplex_excess.cpp).
        depth = INFINITY;
        for (size_t f = 0; f < planes_.size(); f += 4) {
            const double slack = planes_[f + 3] - dot3(&planes_[f], xl);
            if (!(slack > 0.0)) return false;
            if (slack < depth) {
                depth = slack;
                for (int k = 0; k < 3; ++k) nl[k] = planes_[f + k];
            }
        }
        return true;
    }
    double best = INFINITY;
    double best_normal[3] = {1.0, 0.0, 0.0};
    for (int j = 0; j < dir_count_; ++j) {
        const double s = dot3(dirs_[j], xl);
        const double up = dir_max_[j] - s, down = s - dir_min_[j];
        if (!(up > 0.0 && down > 0.0)) return false;
        if (up < best) {
            best = up;
            for (int k = 0; k < 3; ++k) best_normal[k] = dirs_[j][k];
        }
        if (down < best) {
            best = down;
            for (int k = 0; k < 3; ++k) best_normal[k] = -dirs_[j][k];
        }
    }
#ifdef SOFTHAP_WITH_CCD
    // libccd on the hull (obj1) against the point (obj2), in the normalised frame. Its dir is
    // the direction that moves obj2 out of obj1, i.e. the hull's outward normal at the nearest
    // surface point (checked: cube hull, point near the +x face -> +x). Each direction it
    // gives is only a candidate: our own slack along it (an upper bound on the depth, exact
    // along the nearest face's normal) competes with the sampled ones, so depth and normal
    // stay consistent and never worse than the sampled estimate.
    CcdPoint point;
    for (int k = 0; k < 3; ++k) point.x[k] = (xl[k] - ccd_center_[k]) / ccd_scale_;
    const int count = static_cast<int>(ccd_points_.size() / 3);
    const long budget = 128 + 2L * count;
    // -1: x is on or outside a supporting plane (not inside); 0: unusable; 1: a candidate.
    auto consider_direction = [&](const ccd_vec3_t& dir) -> int {
        double nrm[3] = {dir.v[0], dir.v[1], dir.v[2]};
        if (!finite3(nrm) || !normalize3(nrm)) return 0;
        const int i = convex_support_index(nrm);
        const double slack = dot3(nrm, points_.data() + 3 * static_cast<size_t>(i)) - dot3(nrm, xl);
        if (!(slack > 0.0)) return -1;
        if (slack < best) {
            best = slack;
            for (int k = 0; k < 3; ++k) best_normal[k] = nrm[k];
        }
        return 1;
    };
    // The nearest boundary point seen by the support calls: depth <= |p - x|, pushing x out
    // along p - x (this is what bounds queries within ~1e-6 of a vertex, where EPA and MPR
    // are least reliable).
    auto consider_boundary_point = [&](const CcdHull& hull) {
        if (hull.nearest < 0) return;
        const double* p = points_.data() + 3 * static_cast<size_t>(hull.nearest);
        double d[3] = {p[0] - xl[0], p[1] - xl[1], p[2] - xl[2]};
        const double dist = norm3(d);
        if (dist < best && normalize3(d)) {
            best = dist;
            for (int k = 0; k < 3; ++k) best_normal[k] = d[k];
        }
    };
    // Touching contact: libccd tests squared distances against DBL_EPSILON (distance 1.5e-8
    // in the normalised frame) and then gives no usable direction: x is on the surface.
    const double touching = 2e-8;
    ccd_t ccd;
    CCD_INIT(&ccd);
    ccd.support1 = ccd_hull_support;
    ccd.support2 = ccd_point_support;
    ccd.center1 = ccd_hull_center;
    ccd.center2 = ccd_point_center;
    ccd.max_iterations = 1000;  // bounds GJK and MPR's last phase (default: unlimited)
    // EPA stops when a new support point gains less than epa_tolerance / (current distance)
    // over the nearest face (normalised frame); MPR when it gains less than mpr_tolerance.
    ccd.epa_tolerance = 1e-10;
    ccd.mpr_tolerance = 1e-12;
    if (!allocation_free_) {
        // GJK/EPA: exact (the nearest face) when it converges. Its loop has no iteration limit
        // and can cycle, mostly for points within ~1e-6 of a vertex; the budget ends a cycle.
        const CcdHull hull{ccd_points_.data(), count, ccd_centroid_, &point, budget};
        ccd_real_t ccd_depth = -1.0;
        ccd_vec3_t ccd_dir = {{NAN, NAN, NAN}};
        ccd_vec3_t ccd_pos;
        const int rc = ccdGJKPenetration(&hull, &point, &ccd, &ccd_depth, &ccd_dir, &ccd_pos);
        const bool converged = hull.calls_left > 0;
        if (converged && rc == -1) return false;  // no intersection
        if (rc == 0) {
            if (converged && ccd_depth >= 0.0 && ccd_depth <= touching) return false;
            if (consider_direction(ccd_dir) < 0) return false;
        }
        consider_boundary_point(hull);
        // EPA's depth is a lower bound (the distance to a face of a polytope inside the
        // hull): when our best upper bound meets it, the answer is exact.
        if (converged && rc == 0 && std::isfinite(ccd_depth) &&
            best <= (ccd_depth + 1e-9) * ccd_scale_) {
            depth = best;
            for (int k = 0; k < 3; ++k) nl[k] = best_normal[k];
            return true;
        }
        // else: cut off, stopped early, degenerate, or rc == -2 (an allocation failed in libccd)
    }
    {
        // Second opinion, MPR (allocation-free): the hull face that the ray from the hull's
        // centroid through x reaches; for points near the surface its slack tends to the
        // depth. The same budget bounds its loops.
        const CcdHull hull{ccd_points_.data(), count, ccd_centroid_, &point, budget};
        ccd_real_t ccd_depth = -1.0;
        ccd_vec3_t ccd_dir = {{NAN, NAN, NAN}};
        ccd_vec3_t ccd_pos;
        const int rc = ccdMPRPenetration(&hull, &point, &ccd, &ccd_depth, &ccd_dir, &ccd_pos);
        if (rc == 0 && consider_direction(ccd_dir) < 0) return false;
        consider_boundary_point(hull);
    }
    // The least upper bound over all candidates stands (the sampled directions at worst).
#endif
    depth = best;
    for (int k = 0; k < 3; ++k) nl[k] = best_normal[k];
    return true;
}

bool Shape::penetrate_point(const Pose& pose, const double x[3], Penetration& out) const {
    double depth = 0.0;
    double normal[3] = {0.0, 0.0, 1.0};
    switch (kind_) {
        case SH_SHAPE_SPHERE: {
            double d[3] = {x[0] - pose.p[0], x[1] - pose.p[1], x[2] - pose.p[2]};
            const double dist = norm3(d);
            depth = radius_ - dist;
            if (!(depth > 0.0)) return false;
            if (dist > 1e-12 * radius_ && normalize3(d)) {
                for (int k = 0; k < 3; ++k) normal[k] = d[k];
            } else {  // at the centre: any direction; the local x axis
                const double ex[3] = {1.0, 0.0, 0.0};
                pose.rotate(ex, normal);
            }
            break;
        }
        case SH_SHAPE_CAPSULE: {
            double xl[3];
            pose.to_local(x, xl);
            const double t = std::min(std::max(xl[2], -half_length_), half_length_);
            double d[3] = {xl[0], xl[1], xl[2] - t};
            const double dist = norm3(d);
            depth = radius_ - dist;
            if (!(depth > 0.0)) return false;
            if (!(dist > 1e-12 * radius_ && normalize3(d))) {
                d[0] = 1.0;  // on the axis: the local x axis, perpendicular to it
                d[1] = d[2] = 0.0;
            }
            pose.rotate(d, normal);
            break;
        }
        case SH_SHAPE_BOX: {
            double xl[3];
            pose.to_local(x, xl);
            int axis = 0;
            depth = INFINITY;
            for (int k = 0; k < 3; ++k) {
                const double slack = half_extents_[k] - std::fabs(xl[k]);
                if (!(slack > 0.0)) return false;
                // Ties (e.g. the centre) go to the lower axis index among the smallest slacks;
                // at the centre the slack is the half extent: the thinnest axis, + side.
                if (slack < depth) {
                    depth = slack;
                    axis = k;
                }
            }
            double nl[3] = {0.0, 0.0, 0.0};
            nl[axis] = xl[axis] < 0.0 ? -1.0 : 1.0;
            pose.rotate(nl, normal);
            break;
        }
        case SH_SHAPE_CONVEX: {
            double xl[3], nl[3];
            pose.to_local(x, xl);
            if (!penetrate_convex(xl, depth, nl)) return false;
            pose.rotate(nl, normal);
            break;
        }
        case SH_SHAPE_PLANE:
        default: {
            const double ez[3] = {0.0, 0.0, 1.0};
            pose.rotate(ez, normal);
            normalize3(normal);
            const double d[3] = {x[0] - pose.p[0], x[1] - pose.p[1], x[2] - pose.p[2]};
            depth = -dot3(normal, d);
            if (!(depth > 0.0)) return false;
            break;
        }
    }
    if (!normalize3(normal) || !std::isfinite(depth)) return false;  // only for non-finite poses
    out.depth = depth;
    for (int k = 0; k < 3; ++k) {
        out.normal[k] = normal[k];
        out.point[k] = x[k];
    }
    return true;
}

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
