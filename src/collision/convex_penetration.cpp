// ConvexHull::penetrate: how deep a point lies in a convex hull. Cheap rejects first (the
// local bounding box, the slabs of the sampled directions); then the facet planes when the
// hull has them (exact), else libccd's GJK/EPA and MPR, each of whose answers only competes
// with the sampled directions' bound, so that depth and normal stay consistent.
#include "collision/convex_hull.hpp"

#include "collision/unit_vector.hpp"
#include "core/vec3.hpp"

#include <cmath>
#include <cstddef>

#ifdef SOFTHAP_WITH_CCD
#include <ccd/ccd.h>
#endif

namespace sh {
namespace {

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

/// The least upper bound on a point's depth (m) found so far and its push direction.
struct DepthBound {
    const ConvexHull& hull;
    const double* xl;  ///< the query point (local frame)
    double& depth;
    double* normal;

    /// A candidate push direction: the point's slack below the supporting plane along it.
    /// -1: xl is on or outside that plane (not inside); 0: unusable; 1: a candidate.
    int consider_direction(const ccd_vec3_t& dir) {
        double nrm[3] = {dir.v[0], dir.v[1], dir.v[2]};
        if (!finite3(nrm) || !normalize3(nrm)) return 0;
        const int i = hull.support_index(nrm);
        const double slack = dot3(nrm, hull.points().data() + 3 * static_cast<size_t>(i)) - dot3(nrm, xl);
        if (!(slack > 0.0)) return -1;
        if (slack < depth) {
            depth = slack;
            for (int k = 0; k < 3; ++k) normal[k] = nrm[k];
        }
        return 1;
    }

    /// The nearest boundary point seen by the support calls: depth <= |p - x|, pushing x out
    /// along p - x (this is what bounds queries within ~1e-6 of a vertex, where EPA and MPR
    /// are least reliable).
    void consider_boundary_point(const CcdHull& ccd_hull) {
        if (ccd_hull.nearest < 0) return;
        const double* p = hull.points().data() + 3 * static_cast<size_t>(ccd_hull.nearest);
        double d[3] = {p[0] - xl[0], p[1] - xl[1], p[2] - xl[2]};
        const double dist = norm3(d);
        if (dist < depth && normalize3(d)) {
            depth = dist;
            for (int k = 0; k < 3; ++k) normal[k] = d[k];
        }
    }
};
#endif

}  // namespace

bool ConvexHull::penetrate(const double xl[3], double& depth, double nl[3]) const {
    for (int k = 0; k < 3; ++k)
        if (!(xl[k] > local_lo_[k] && xl[k] < local_hi_[k])) return false;
    if (exact_planes_) return penetrate_facets(xl, depth, nl);
    // The least slack over the sampled slabs (an upper bound on the depth) is the fallback
    // answer.
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
    if (!refine_with_ccd(xl, best, best_normal)) return false;
#endif
    depth = best;
    for (int k = 0; k < 3; ++k) nl[k] = best_normal[k];
    return true;
}

bool ConvexHull::penetrate_facets(const double xl[3], double& depth, double nl[3]) const {
    // A point inside a polytope is as deep as its nearest facet plane: exact, and the same
    // depth the contact potential's excess terms maximise.
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

#ifdef SOFTHAP_WITH_CCD
bool ConvexHull::refine_with_ccd(const double xl[3], double& best, double best_normal[3]) const {
    // libccd on the hull (obj1) against the point (obj2), in the normalised frame. Its dir is
    // the direction that moves obj2 out of obj1, i.e. the hull's outward normal at the nearest
    // surface point (checked: cube hull, point near the +x face -> +x).
    CcdPoint point;
    for (int k = 0; k < 3; ++k) point.x[k] = (xl[k] - ccd_center_[k]) / ccd_scale_;
    const int count = static_cast<int>(ccd_points_.size() / 3);
    const long budget = 128 + 2L * count;
    DepthBound bound{*this, xl, best, best_normal};
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
            if (bound.consider_direction(ccd_dir) < 0) return false;
        }
        bound.consider_boundary_point(hull);
        // EPA's depth is a lower bound (the distance to a face of a polytope inside the
        // hull): when our best upper bound meets it, the answer is exact.
        if (converged && rc == 0 && std::isfinite(ccd_depth) && best <= (ccd_depth + 1e-9) * ccd_scale_)
            return true;
        // else: cut off, stopped early, degenerate, or rc == -2 (an allocation failed in libccd)
    }
    // Second opinion, MPR (allocation-free): the hull face that the ray from the hull's
    // centroid through x reaches; for points near the surface its slack tends to the depth.
    // The same budget bounds its loops.
    const CcdHull hull{ccd_points_.data(), count, ccd_centroid_, &point, budget};
    ccd_real_t ccd_depth = -1.0;
    ccd_vec3_t ccd_dir = {{NAN, NAN, NAN}};
    ccd_vec3_t ccd_pos;
    const int rc = ccdMPRPenetration(&hull, &point, &ccd, &ccd_depth, &ccd_dir, &ccd_pos);
    if (rc == 0 && bound.consider_direction(ccd_dir) < 0) return false;
    bound.consider_boundary_point(hull);
    // The least upper bound over all candidates stands (the sampled directions at worst).
    return true;
}
#endif

}  // namespace sh
