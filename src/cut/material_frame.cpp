#include "cut/material_frame.hpp"

#include "core/vec3.hpp"
#include "model/body.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace sh {
namespace {

/// Barycentric weights of p in tet (a, b, c, d) at positions x; false for a flat tet.
bool weights_in(const double* x, const int32_t* tet, const double p[3], double w[4]) {
    Eigen::Matrix3d m;
    Eigen::Vector3d r;
    for (int i = 0; i < 3; ++i) {
        for (int a = 0; a < 3; ++a) m(i, a) = at(x, tet[a + 1])[i] - at(x, tet[0])[i];
        r(i) = p[i] - at(x, tet[0])[i];
    }
    const double det = m.determinant();
    if (!(std::fabs(det) > 0.0)) return false;
    const Eigen::Vector3d u = m.inverse() * r;
    w[0] = 1.0 - u.sum(), w[1] = u(0), w[2] = u(1), w[3] = u(2);
    return true;
}

void nearest_node_offset(const Body& body, const double p[3], double out[3]) {
    double best = INFINITY;
    int32_t nearest = 0;
    for (int32_t i = 0; i < body.node_count(); ++i) {
        double d[3];
        sub3(p, at(body.x.data(), i), d);
        if (dot3(d, d) < best) best = dot3(d, d), nearest = i;
    }
    for (int k = 0; k < 3; ++k) out[k] = at(body.rest.data(), nearest)[k] + p[k] - at(body.x.data(), nearest)[k];
}

}  // namespace

RestPoint rest_point(const Body& body, const double p[3]) {
    RestPoint found;
    if (body.nodes_per_element() != 4 || body.element_count() == 0) {
        nearest_node_offset(body, p, found.position);
        return found;
    }
    double best_w[4] = {0, 0, 0, 0};
    found.inside = -INFINITY;
    for (int32_t t = 0; t < body.element_count(); ++t) {
        const int32_t* tet = body.element_nodes() + 4 * static_cast<size_t>(t);
        double w[4];
        if (!weights_in(body.x.data(), tet, p, w)) continue;
        const double inside = std::fmin(std::fmin(w[0], w[1]), std::fmin(w[2], w[3]));  // >= 0 inside
        if (inside <= found.inside) continue;
        found.inside = inside, found.tet = t;
        for (int a = 0; a < 4; ++a) best_w[a] = w[a];
        if (inside >= 0.0) break;
    }
    if (found.tet < 0) {
        nearest_node_offset(body, p, found.position);
        return found;
    }
    const int32_t* tet = body.element_nodes() + 4 * static_cast<size_t>(found.tet);
    for (int k = 0; k < 3; ++k) {
        found.position[k] = 0.0;
        for (int a = 0; a < 4; ++a) found.position[k] += best_w[a] * at(body.rest.data(), tet[a])[k];
    }
    return found;
}

void to_rest(const Body& body, const double p[3], double out[3]) {
    const RestPoint found = rest_point(body, p);
    for (int k = 0; k < 3; ++k) out[k] = found.position[k];
}

}  // namespace sh
