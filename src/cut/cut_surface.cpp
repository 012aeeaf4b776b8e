#include "cut/cut_surface.hpp"

#include "collision/closest_point.hpp"
#include "core/error.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace sh {

CutSurface::CutSurface(const double* triangles, int32_t count) {
    SH_REQUIRE(count >= 1, SH_ERR_INVALID_ARGUMENT, "triangle_count = %d: a cut needs at least one triangle", count);
    corners_.assign(triangles, triangles + 9 * static_cast<size_t>(count));
    normals_.resize(3 * static_cast<size_t>(count));
    boxes_.resize(6 * static_cast<size_t>(count));
    for (int k = 0; k < 3; ++k) lower_[k] = INFINITY, upper_[k] = -INFINITY;
    for (int32_t i = 0; i < count; ++i) {
        const double* a = corner(i, 0);
        for (int c = 0; c < 3; ++c)
            SH_REQUIRE(finite3(corner(i, c)), SH_ERR_INVALID_ARGUMENT, "triangles[%d] corner %d is not finite", i, c);
        double ab[3], ac[3], n[3];
        sub3(corner(i, 1), a, ab);
        sub3(corner(i, 2), a, ac);
        cross3(ab, ac, n);
        const double twice_area = norm3(n), longest = std::max(dot3(ab, ab), dot3(ac, ac));
        SH_REQUIRE(twice_area > 1e-12 * longest && twice_area > 0.0, SH_ERR_INVALID_ARGUMENT,
                   "triangles[%d] has zero area (its corners are on one line)", i);
        double* box = &boxes_[6 * static_cast<size_t>(i)];
        for (int k = 0; k < 3; ++k) {
            normals_[3 * static_cast<size_t>(i) + k] = n[k] / twice_area;
            box[k] = std::min({a[k], corner(i, 1)[k], corner(i, 2)[k]});
            box[3 + k] = std::max({a[k], corner(i, 1)[k], corner(i, 2)[k]});
            lower_[k] = std::min(lower_[k], box[k]);
            upper_[k] = std::max(upper_[k], box[3 + k]);
        }
    }
    orient();
}

void CutSurface::orient() {
    // Weld corners that are equal, then walk the triangles across shared edges, flipping a
    // neighbour whose shared edge runs the same way (it would face the other side).
    struct Corner {
        std::array<double, 3> p;
        int32_t slot;
    };
    const size_t count = normals_.size() / 3;
    vec<Corner> sorted(3 * count);
    for (size_t s = 0; s < 3 * count; ++s) sorted[s] = {{corners_[3 * s], corners_[3 * s + 1], corners_[3 * s + 2]}, static_cast<int32_t>(s)};
    std::sort(sorted.begin(), sorted.end(), [](const Corner& a, const Corner& b) { return a.p < b.p; });
    vec<int32_t> vertex(3 * count);
    int32_t next = -1;
    for (size_t s = 0; s < sorted.size(); ++s) {
        if (s == 0 || sorted[s].p != sorted[s - 1].p) ++next;
        vertex[static_cast<size_t>(sorted[s].slot)] = next;
    }
    struct Edge {
        int32_t lo, hi, triangle, forward;
    };
    vec<Edge> edges;
    edges.reserve(3 * count);
    for (size_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) {
            const int32_t a = vertex[3 * i + k], b = vertex[3 * i + (k + 1) % 3];
            edges.push_back({std::min(a, b), std::max(a, b), static_cast<int32_t>(i), a < b ? 1 : 0});
        }
    std::sort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) { return a.lo != b.lo ? a.lo < b.lo : a.hi < b.hi; });
    vec<int32_t> flip(count, -1), queue;
    for (size_t seed = 0; seed < count; ++seed) {
        if (flip[seed] >= 0) continue;
        flip[seed] = 0;
        queue.assign(1, static_cast<int32_t>(seed));
        while (!queue.empty()) {
            const int32_t i = queue.back();
            queue.pop_back();
            for (int k = 0; k < 3; ++k) {
                const int32_t a = vertex[3 * static_cast<size_t>(i) + k], b = vertex[3 * static_cast<size_t>(i) + (k + 1) % 3];
                const Edge key{std::min(a, b), std::max(a, b), 0, 0};
                auto it = std::lower_bound(edges.begin(), edges.end(), key, [](const Edge& x, const Edge& y) {
                    return x.lo != y.lo ? x.lo < y.lo : x.hi < y.hi;
                });
                const int32_t forward = (a < b ? 1 : 0) ^ flip[static_cast<size_t>(i)];
                for (; it != edges.end() && it->lo == key.lo && it->hi == key.hi; ++it) {
                    if (it->triangle == i || flip[static_cast<size_t>(it->triangle)] >= 0) continue;
                    flip[static_cast<size_t>(it->triangle)] = it->forward == forward ? 1 : 0;
                    queue.push_back(it->triangle);
                }
            }
        }
    }
    for (size_t i = 0; i < count; ++i)
        if (flip[i] == 1) {
            for (int k = 0; k < 3; ++k) std::swap(corners_[9 * i + 3 + k], corners_[9 * i + 6 + k]);
            for (int k = 0; k < 3; ++k) normals_[3 * i + k] = -normals_[3 * i + k];
        }
}

bool CutSurface::box_touches(int32_t i, const double* lo, const double* hi, double margin) const {
    const double* box = &boxes_[6 * static_cast<size_t>(i)];
    for (int k = 0; k < 3; ++k)
        if (box[k] > hi[k] + margin || box[3 + k] < lo[k] - margin) return false;
    return true;
}

bool CutSurface::first_hit(const double* p, const double* q, double& t_hit, int32_t& triangle) const {
    // Moller-Trumbore against every triangle whose box meets the segment's. Barycentric
    // weights may be a hair below zero so that a segment through a shared edge of two
    // triangles cannot slip between them.
    constexpr double kEdgeSlack = 1e-10;
    double lo[3], hi[3], d[3];
    for (int k = 0; k < 3; ++k) lo[k] = std::min(p[k], q[k]), hi[k] = std::max(p[k], q[k]), d[k] = q[k] - p[k];
    bool found = false;
    for (int32_t i = 0; i < triangle_count(); ++i) {
        if (!box_touches(i, lo, hi, 0.0)) continue;
        const double *a = corner(i, 0), *b = corner(i, 1), *c = corner(i, 2);
        double e1[3], e2[3], s[3], pv[3], qv[3];
        sub3(b, a, e1);
        sub3(c, a, e2);
        cross3(d, e2, pv);
        const double det = dot3(e1, pv);
        if (std::fabs(det) <= 1e-14 * norm3(d) * norm3(e1) * norm3(e2)) continue;  // parallel
        sub3(p, a, s);
        const double u = dot3(s, pv) / det;
        if (u < -kEdgeSlack || u > 1.0 + kEdgeSlack) continue;
        cross3(s, e1, qv);
        const double v = dot3(d, qv) / det;
        if (v < -kEdgeSlack || u + v > 1.0 + kEdgeSlack) continue;
        const double t = dot3(e2, qv) / det;
        if (t < 0.0 || t > 1.0 || (found && t >= t_hit)) continue;
        t_hit = t;
        triangle = i;
        found = true;
    }
    return found;
}

double CutSurface::signed_distance(const double* p, int32_t& triangle) const {
    double best = INFINITY, side = 0.0;
    triangle = -1;
    for (int32_t i = 0; i < triangle_count(); ++i) {
        double w[3];
        const double distance = closest_on_triangle(p, corner(i, 0), corner(i, 1), corner(i, 2), w);
        if (distance >= best) continue;
        double offset[3];
        for (int k = 0; k < 3; ++k) offset[k] = p[k] - (w[0] * corner(i, 0)[k] + w[1] * corner(i, 1)[k] + w[2] * corner(i, 2)[k]);
        best = distance;
        side = dot3(offset, normal(i));
        triangle = i;
    }
    return side >= 0.0 ? best : -best;
}

}  // namespace sh
