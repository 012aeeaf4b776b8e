#include "collision/closest_point.hpp"

#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

double closest_on_triangle(const double* p, const double* a, const double* b, const double* c, double w[3]) {
    double ab[3], ac[3], ap[3];
    sub3(b, a, ab);
    sub3(c, a, ac);
    sub3(p, a, ap);
    const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    auto set = [&](double wa, double wb, double wc) {
        w[0] = wa;
        w[1] = wb;
        w[2] = wc;
    };
    double bp[3], cp[3];
    sub3(p, b, bp);
    sub3(p, c, cp);
    const double d3 = dot3(ab, bp), d4 = dot3(ac, bp), d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    const double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
    if (d1 <= 0.0 && d2 <= 0.0) set(1, 0, 0);                                  // vertex a
    else if (d3 >= 0.0 && d4 <= d3) set(0, 1, 0);                              // vertex b
    else if (d6 >= 0.0 && d5 <= d6) set(0, 0, 1);                              // vertex c
    else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {                            // edge ab
        const double t = d1 / (d1 - d3);
        set(1 - t, t, 0);
    } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {                          // edge ac
        const double t = d2 / (d2 - d6);
        set(1 - t, 0, t);
    } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {                // edge bc
        const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        set(0, 1 - t, t);
    } else {                                                                   // inside
        const double sum = va + vb + vc;
        if (!(sum > 0.0)) set(1, 0, 0);  // zero-area triangle
        else set(va / sum, vb / sum, vc / sum);
    }
    double q[3], d[3];
    for (int k = 0; k < 3; ++k) q[k] = w[0] * a[k] + w[1] * b[k] + w[2] * c[k];
    sub3(p, q, d);
    return std::sqrt(dot3(d, d));
}

double distance_to_segment(const double* p, const double* a, const double* b) {
    double ab[3], ap[3];
    sub3(b, a, ab);
    sub3(p, a, ap);
    const double length2 = dot3(ab, ab);
    const double t = length2 > 0.0 ? std::min(std::max(dot3(ap, ab) / length2, 0.0), 1.0) : 0.0;
    double d[3];
    for (int k = 0; k < 3; ++k) d[k] = ap[k] - t * ab[k];
    return std::sqrt(dot3(d, d));
}

namespace {

// Where p lies against the plane of triangle (a, b, c): its height above it along the outward
// unit normal n, and the barycentric weights w of the point of the triangle nearest to p's
// projection, at distance lateral from it. False if the triangle is degenerate. Sets edge2 to
// its longer edge from a, squared.
bool over_face(const double* p, const double* a, const double* b, const double* c, double& height, double n[3],
               double w[3], double& lateral, double& edge2) {
    double ab[3], ac[3], ap[3];
    sub3(b, a, ab);
    sub3(c, a, ac);
    cross3(ab, ac, n);
    const double area2 = std::sqrt(dot3(n, n));
    edge2 = std::max(dot3(ab, ab), dot3(ac, ac));
    if (!(area2 > 1e-14 * edge2)) return false;
    for (int k = 0; k < 3; ++k) n[k] /= area2;
    sub3(p, a, ap);
    height = dot3(n, ap);
    double q[3];
    for (int k = 0; k < 3; ++k) q[k] = p[k] - height * n[k];
    lateral = closest_on_triangle(q, a, b, c, w);
    return true;
}

}  // namespace

bool node_behind_face(const double* p, const double* a, const double* b, const double* c, double& depth, double n[3],
                      double w[3]) {
    double height, lateral, edge2;
    if (!over_face(p, a, b, c, height, n, w, lateral, edge2)) return false;
    depth = -height;
    return depth > 0.0 && lateral * lateral <= edge2;
}

bool node_before_face(const double* p, const double* a, const double* b, const double* c) {
    double height, n[3], w[3], lateral, edge2;
    return over_face(p, a, b, c, height, n, w, lateral, edge2) && height >= 0.0 && lateral * lateral <= 1e-18 * edge2;
}

}  // namespace sh
