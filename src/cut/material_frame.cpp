#include "cut/material_frame.hpp"

#include "collision/aabb_tree.hpp"
#include "core/memory.hpp"
#include "core/vec3.hpp"
#include "mesh/tets_in_box.hpp"
#include "model/body.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

/// The map from world points to barycentric weights in tet (a, b, c, d) at positions x: the
/// inverse edge matrix and the first corner; false for a flat tet.
struct TetMap {
    Eigen::Matrix3d inverse;
    Eigen::Vector3d origin;
    bool form(const double* x, const int32_t* tet) {
        Eigen::Matrix3d m;
        for (int i = 0; i < 3; ++i) {
            for (int a = 0; a < 3; ++a) m(i, a) = at(x, tet[a + 1])[i] - at(x, tet[0])[i];
            origin(i) = at(x, tet[0])[i];
        }
        const double det = m.determinant();
        if (!(std::fabs(det) > 0.0)) return false;
        inverse = m.inverse();
        return true;
    }
    void weights(const double p[3], double w[4]) const {
        const Eigen::Vector3d u = inverse * (Eigen::Vector3d(p[0], p[1], p[2]) - origin);
        w[0] = 1.0 - u.sum(), w[1] = u(0), w[2] = u(1), w[3] = u(2);
    }
};

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

/// The tets whose box meets the box around the count points p grown by half its diagonal:
/// every tet that contains a point, and those near the points that an outside point may be
/// least outside of.
vec<int32_t> tets_near(const Body& body, const double* p, int count) {
    Aabb box;
    for (int i = 0; i < count; ++i) box.add(&p[3 * i]);
    double diagonal[3];
    sub3(box.hi, box.lo, diagonal);
    box.inflate(0.5 * norm3(diagonal));
    vec<int32_t> near;
    for_each_tet_in_box(body.x.data(), body.node_count(), body.element_nodes(), body.element_count(), box.lo, box.hi,
                        [&](int32_t t) { near.push_back(t); });
    return near;
}

/// For each point i of p with out[i].inside < 0 (not yet inside a tet): the first of the tets
/// listed in only (null: all the body's) that contains it, else the one it is least outside
/// of if less than out[i].inside, with its barycentric weights in best_w (4 per point).
void search_tets(const Body& body, const double* p, int count, const vec<int32_t>* only, RestPoint* out, double* best_w) {
    int left = 0;
    for (int i = 0; i < count; ++i) left += out[i].inside < 0.0 ? 1 : 0;
    const int32_t tets = only ? static_cast<int32_t>(only->size()) : body.element_count();
    TetMap map;
    for (int32_t k = 0; k < tets && left > 0; ++k) {
        const int32_t t = only ? (*only)[static_cast<size_t>(k)] : k;
        if (!map.form(body.x.data(), body.element_nodes() + 4 * static_cast<size_t>(t))) continue;
        for (int i = 0; i < count; ++i) {
            if (out[i].inside >= 0.0) continue;
            double w[4];
            map.weights(&p[3 * i], w);
            const double inside = std::fmin(std::fmin(w[0], w[1]), std::fmin(w[2], w[3]));  // >= 0 inside
            if (inside <= out[i].inside) continue;
            out[i].inside = inside, out[i].tet = t;
            std::copy(w, w + 4, &best_w[4 * static_cast<size_t>(i)]);
            left -= inside >= 0.0 ? 1 : 0;
        }
    }
}

}  // namespace

void rest_points(const Body& body, const double* p, int count, RestPoint* out) {
    if (body.nodes_per_element() != 4 || body.element_count() == 0) {
        for (int i = 0; i < count; ++i) out[i] = RestPoint{}, nearest_node_offset(body, &p[3 * i], out[i].position);
        return;
    }
    // The tets near the points first; a point that none of them reaches (outside, and far
    // from the others) looks through them all.
    vec<double> best_w(4 * static_cast<size_t>(count), 0.0);
    for (int i = 0; i < count; ++i) out[i] = RestPoint{}, out[i].inside = -INFINITY;
    const vec<int32_t> near = tets_near(body, p, count);
    search_tets(body, p, count, &near, out, best_w.data());
    bool unreached = false;
    for (int i = 0; i < count; ++i) unreached = unreached || out[i].tet < 0;
    if (unreached) search_tets(body, p, count, nullptr, out, best_w.data());
    for (int i = 0; i < count; ++i) {
        if (out[i].tet < 0) {
            nearest_node_offset(body, &p[3 * i], out[i].position);
            continue;
        }
        const int32_t* tet = body.element_nodes() + 4 * static_cast<size_t>(out[i].tet);
        for (int k = 0; k < 3; ++k) {
            out[i].position[k] = 0.0;
            for (int a = 0; a < 4; ++a) out[i].position[k] += best_w[4 * static_cast<size_t>(i) + a] * at(body.rest.data(), tet[a])[k];
        }
    }
}

void to_rest_all(const Body& body, const double* p, int count, double* out) {
    vec<RestPoint> found(static_cast<size_t>(count));
    rest_points(body, p, count, found.data());
    for (int i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) out[3 * i + k] = found[static_cast<size_t>(i)].position[k];
}

}  // namespace sh
