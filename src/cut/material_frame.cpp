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

/// A point outside the body within this many sizes of the tet it is least outside of (by a
/// first, narrow search) is near enough for its extrapolation to matter (a blade in a slit).
constexpr double kNearElements = 4.0;

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

/// The body's node nearest to p in its current configuration.
int32_t nearest_node(const Body& body, const double p[3]) {
    double best = INFINITY;
    int32_t nearest = 0;
    for (int32_t i = 0; i < body.node_count(); ++i) {
        double d[3];
        sub3(p, at(body.x.data(), i), d);
        if (dot3(d, d) < best) best = dot3(d, d), nearest = i;
    }
    return nearest;
}

void nearest_node_offset(const Body& body, const double p[3], double out[3]) {
    const int32_t nearest = nearest_node(body, p);
    for (int k = 0; k < 3; ++k) out[k] = at(body.rest.data(), nearest)[k] + p[k] - at(body.x.data(), nearest)[k];
}

/// Takes tet t (mapped by map) for point p of out (with its weights in w) if p lies inside
/// it, or less outside of it than of the tet out has.
void consider_tet(const TetMap& map, int32_t t, const double p[3], RestPoint& out, double w[4]) {
    double tried[4];
    map.weights(p, tried);
    const double inside = std::fmin(std::fmin(tried[0], tried[1]), std::fmin(tried[2], tried[3]));  // >= 0 inside
    if (inside <= out.inside) return;
    out.inside = inside, out.tet = t;
    std::copy(tried, tried + 4, w);
}

/// For each point i of p in which: the tet that contains it, else the one it is least
/// outside of, among the tets whose box meets boxes[i] (6 doubles: lo, hi).
void search_tets_in_boxes(const Body& body, const double* p, const vec<int>& which, const vec<double>& boxes, RestPoint* out,
                          double* best_w) {
    vec<double> packed;
    for (const int i : which) packed.insert(packed.end(), &boxes[6 * static_cast<size_t>(i)], &boxes[6 * static_cast<size_t>(i)] + 6);
    TetMap map;
    for_each_tet_in_boxes(body.x.data(), body.node_count(), body.element_nodes(), body.element_count(), packed.data(),
                          static_cast<int>(which.size()), [&](int32_t t, int first, uint32_t hits) {
                              if (!map.form(body.x.data(), body.element_nodes() + 4 * static_cast<size_t>(t))) return;
                              for (size_t j = static_cast<size_t>(first); hits != 0; ++j, hits >>= 1)
                                  if (const int i = which[j]; (hits & 1u) && out[i].inside < 0.0)
                                      consider_tet(map, t, &p[3 * i], out[i], &best_w[4 * static_cast<size_t>(i)]);
                          });
}

/// Writes box as 6 doubles: lo, then hi.
void put_box(const Aabb& box, double* out) {
    std::copy(box.lo, box.lo + 3, out);
    std::copy(box.hi, box.hi + 3, out + 3);
}

/// The length of the diagonal of tet t's box.
double tet_size(const Body& body, int32_t t) {
    Aabb box;
    for (int a = 0; a < 4; ++a) box.add(at(body.x.data(), body.element_nodes()[4 * static_cast<size_t>(t) + a]));
    double d[3];
    sub3(box.hi, box.lo, d);
    return norm3(d);
}

/// For each point i of p listed in all (every point, 0 to count - 1): the tet that contains
/// it, else the one it is least outside of. First among the tets whose box meets the box spanned by the point and its nearest node:
/// every tet that contains the point, and at least the nearest node's. A point outside but
/// within a few elements of the body (in a slit, or just off a face) looks again within its
/// distance to that node, which reaches the tet nearest to it; a point farther out keeps the
/// first choice, whose extrapolation is as good as any. Two passes over the nodes and one or
/// two over the tets per 8 points, not a pass over every tet near all of them.
void search_near_tets(const Body& body, const double* p, const vec<int>& all, RestPoint* out, double* best_w) {
    const size_t count = all.size();
    vec<double> spans(6 * count), reaches(6 * count), distance(count);
    vec<int> near;
    for (const int i : all) {
        const double* node = at(body.x.data(), nearest_node(body, &p[3 * i]));
        double d[3];
        sub3(&p[3 * i], node, d);
        distance[static_cast<size_t>(i)] = norm3(d);
        Aabb span, reach;
        span.add(&p[3 * i]), span.add(node), reach.add(&p[3 * i]);
        reach.inflate((1.0 + 1e-9) * norm3(d));  // the node inside, despite round-off
        put_box(span, &spans[6 * static_cast<size_t>(i)]);
        put_box(reach, &reaches[6 * static_cast<size_t>(i)]);
    }
    search_tets_in_boxes(body, p, all, spans, out, best_w);
    for (const int i : all)
        if (out[i].tet >= 0 && out[i].inside < 0.0 && distance[static_cast<size_t>(i)] < kNearElements * tet_size(body, out[i].tet))
            near.push_back(i);
    if (!near.empty()) search_tets_in_boxes(body, p, near, reaches, out, best_w);
}

/// Calls visit(map, t) for each non-flat tet t listed in tets (null: all the body's) with its
/// map at the current positions, while visit returns true.
template <class Visit>
void for_each_mapped_tet(const Body& body, const vec<int32_t>* tets, Visit&& visit) {
    TetMap map;
    const int32_t count = tets ? static_cast<int32_t>(tets->size()) : body.element_count();
    for (int32_t k = 0; k < count; ++k) {
        const int32_t t = tets ? (*tets)[static_cast<size_t>(k)] : k;
        if (map.form(body.x.data(), body.element_nodes() + 4 * static_cast<size_t>(t)) && !visit(map, t)) return;
    }
}

/// For the points of p listed in which: the tet that contains it, else the one it is least
/// outside of, among tets (null: all the body's). A point found inside a tet is done, and the
/// search ends once every point is.
void search_tets(const Body& body, const double* p, const vec<int>& which, const vec<int32_t>* tets, RestPoint* out,
                 double* best_w) {
    size_t left = which.size();
    for_each_mapped_tet(body, tets, [&](const TetMap& map, int32_t t) {
        for (const int i : which) {
            if (out[i].inside >= 0.0) continue;
            consider_tet(map, t, &p[3 * i], out[i], &best_w[4 * static_cast<size_t>(i)]);
            left -= out[i].inside >= 0.0 ? 1 : 0;
        }
        return left > 0;
    });
}

/// The box around all the count points p grown by half its diagonal: it holds every tet that
/// contains a point, and those near the points that an outside one may be least outside of.
/// Small for points close together (the samples along a blade).
Aabb box_near_all(const double* p, int count) {
    Aabb box;
    for (int i = 0; i < count; ++i) box.add(&p[3 * i]);
    double diagonal[3];
    sub3(box.hi, box.lo, diagonal);
    box.inflate(0.5 * norm3(diagonal));
    return box;
}

/// The tets whose box meets box.
vec<int32_t> tets_in(const Body& body, const Aabb& box) {
    vec<int32_t> near;
    for_each_tet_in_box(body.x.data(), body.node_count(), body.element_nodes(), body.element_count(), box.lo, box.hi,
                        [&](int32_t t) { near.push_back(t); });
    return near;
}

/// About how many tets lie in box: its share of the nodes (every 8th node looked at, enough
/// to choose a search) times the body's tets.
double tets_estimated_in(const Body& body, const Aabb& box) {
    constexpr int32_t kStride = 8;
    int32_t inside = 0, looked = 0;
    for (int32_t i = 0; i < body.node_count(); i += kStride, ++looked) inside += box.distance2(at(body.x.data(), i)) == 0.0 ? 1 : 0;
    return static_cast<double>(inside) * body.element_count() / std::max(looked, 1);
}

/// Rough costs of the two searches, in point-in-tet tests (measured on the raptor: a blade's
/// 33 samples, a cut's 6 corners): searching the tets near all the points together (each
/// tet's map formed once, about 20 tests, then tested against every point), or each point
/// apart (search_near_tets: a nearest node, about a third of a test per node and point, then
/// two passes over the nodes and tets per 8 points).
double together_cost(double near_tets, int count) { return near_tets * (20.0 + count); }
double apart_cost(const Body& body, int count) {
    const double nodes = body.node_count(), tets = body.element_count(), groups = (count + 7) / 8;
    return count * nodes / 3.0 + 2.0 * groups * (8.0 * nodes / 3.0 + tets / 2.0);
}

/// Narrows span (fractions of a segment) to where each barycentric weight, wa at its start
/// and wb at its end and linear between, stays at least -slack; false if nothing is left.
bool clip_to_weights(const double wa[4], const double wb[4], double slack, SegmentSpan& span) {
    for (int c = 0; c < 4; ++c) {
        const double slope = wb[c] - wa[c], margin = wa[c] + slack;
        if (slope > 0.0) span.from = std::fmax(span.from, -margin / slope);
        else if (slope < 0.0) span.to = std::fmin(span.to, -margin / slope);
        else if (margin < 0.0) return false;
    }
    return span.from <= span.to;
}

}  // namespace

void rest_points(const Body& body, const double* p, int count, RestPoint* out) {
    if (body.nodes_per_element() != 4 || body.element_count() == 0) {
        for (int i = 0; i < count; ++i) out[i] = RestPoint{}, nearest_node_offset(body, &p[3 * i], out[i].position);
        return;
    }
    // The points together where they lie close (a blade's samples), else each apart (the far
    // corners of a cut's triangles); a point whose nearby tets are all flat looks through all.
    vec<double> best_w(4 * static_cast<size_t>(count), 0.0);
    vec<int> all(static_cast<size_t>(count)), unreached;
    for (int i = 0; i < count; ++i) out[i] = RestPoint{}, out[i].inside = -INFINITY, all[static_cast<size_t>(i)] = i;
    const Aabb together = box_near_all(p, count);
    if (together_cost(tets_estimated_in(body, together), count) <= apart_cost(body, count)) {
        const vec<int32_t> near = tets_in(body, together);
        search_tets(body, p, all, &near, out, best_w.data());
    } else {
        search_near_tets(body, p, all, out, best_w.data());
    }
    for (int i = 0; i < count; ++i)
        if (out[i].tet < 0) unreached.push_back(i);
    if (!unreached.empty()) search_tets(body, p, unreached, nullptr, out, best_w.data());
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

vec<SegmentSpan> segment_in_tets(const Body& body, const double a[3], const double b[3], double slack) {
    vec<SegmentSpan> spans;
    if (body.nodes_per_element() != 4 || body.element_count() == 0) return spans;
    double ends[6];
    std::copy(a, a + 3, ends), std::copy(b, b + 3, ends + 3);
    const vec<int32_t> near = tets_in(body, box_near_all(ends, 2));
    for_each_mapped_tet(body, near.empty() ? nullptr : &near, [&](const TetMap& map, int32_t t) {
        double wa[4], wb[4];
        map.weights(a, wa), map.weights(b, wb);
        SegmentSpan span{0.0, 1.0, t};
        if (clip_to_weights(wa, wb, slack, span)) spans.push_back(span);
        return true;
    });
    return spans;
}

void to_rest_all(const Body& body, const double* p, int count, double* out) {
    vec<RestPoint> found(static_cast<size_t>(count));
    rest_points(body, p, count, found.data());
    for (int i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) out[3 * i + k] = found[static_cast<size_t>(i)].position[k];
}

}  // namespace sh
