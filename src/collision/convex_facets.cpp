// The facet planes of a convex hull: exact, allocation-free point queries.
#include "collision/convex_hull.hpp"

#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// True if planes (4 numbers each) already holds (n, offset) to tolerance tol (m).
bool has_plane(const vec<double>& planes, const double n[3], double offset, double tol) {
    for (size_t i = 0; i < planes.size(); i += 4)
        if (std::fabs(planes[i] - n[0]) + std::fabs(planes[i + 1] - n[1]) + std::fabs(planes[i + 2] - n[2]) < 1e-9 &&
            std::fabs(planes[i + 3] - offset) < tol)
            return true;
    return false;
}

}  // namespace

void ConvexHull::init_planes() {
    planes_.clear();
    exact_planes_ = false;
    const double* pts = points_.data();
    const int n = static_cast<int>(points_.size() / 3);
    if (n > kMaxExactHullPoints) return;
    // Every plane through three points with all points on one side is a facet's (brute force,
    // O(n^4), at creation only).
    const double tol = 1e-9 * ccd_scale_;
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j)
            for (int k = j + 1; k < n; ++k) {
                double e1[3], e2[3], normal[3];
                sub3(pts + 3 * j, pts + 3 * i, e1);
                sub3(pts + 3 * k, pts + 3 * i, e2);
                cross3(e1, e2, normal);
                const double len = norm3(normal);
                if (!(len > 1e-12 * ccd_scale_ * ccd_scale_)) continue;
                for (int c = 0; c < 3; ++c) normal[c] /= len;
                const double offset = dot3(normal, pts + 3 * i);
                double above = -INFINITY, below = INFINITY;
                for (int m = 0; m < n; ++m) {
                    const double s = dot3(normal, pts + 3 * m) - offset;
                    above = std::max(above, s);
                    below = std::min(below, s);
                }
                const double sign = above <= tol ? 1.0 : below >= -tol ? -1.0 : 0.0;
                if (sign == 0.0) continue;
                for (int c = 0; c < 3; ++c) normal[c] *= sign;
                if (has_plane(planes_, normal, sign * offset, tol)) continue;
                for (int c = 0; c < 3; ++c) planes_.push_back(normal[c]);
                planes_.push_back(sign * offset);
            }
    exact_planes_ = true;
}

}  // namespace sh
