#include "contact/body_contacts.hpp"

#include "collision/closest_point.hpp"
#include "contact/hunt_crossley.hpp"
#include "core/clock.hpp"
#include "core/vec3.hpp"
#include "solver/sparse_system.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
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

// A node p behind triangle (a, b, c) of another body: depth below its plane along the outward
// unit normal n, and the barycentric weights of the nearest point of the triangle to p's
// projection. False if p is in front, the triangle is degenerate, or p has slid off it.
bool node_behind_face(const double* p, const double* a, const double* b, const double* c, double& depth, double n[3],
                      double w[3]) {
    double height, lateral, edge2;
    if (!over_face(p, a, b, c, height, n, w, lateral, edge2)) return false;
    depth = -height;
    return depth > 0.0 && lateral * lateral <= edge2;
}

// A node p in front of triangle (a, b, c) of another body, over the triangle itself (its
// projection inside it, to round-off): the face it would enter.
bool node_before_face(const double* p, const double* a, const double* b, const double* c) {
    double height, n[3], w[3], lateral, edge2;
    return over_face(p, a, b, c, height, n, w, lateral, edge2) && height >= 0.0 && lateral * lateral <= 1e-18 * edge2;
}

inline const double* at(const double* x, int32_t node) { return x + 3 * static_cast<size_t>(node); }

// The tangent of one contact point, stiffness_scale K + damping_scale D, as 3x3 blocks between
// two of the nodes it acts on (its own, or for a body pair one of the other body's): for
// depth gradients g_a, g_b and shares w_a, w_b, K_ab = k g_a g_b^T, D_ab = c g_a g_b^T +
// w_a w_b D_t, D_t friction's -dF/dvt on the tangent plane: across (I - n n^T - t t^T) + along
// t t^T (friction_tangent), exact for the velocity-only friction of contact() but for the part
// dropped to stay positive semi-definite.
class PointTangent {
public:
    PointTangent(const ContactPoint& p, const sh_contact_params& params, double stiffness_scale, double damping_scale,
                 double chord = -1.0)
        : p_(p),
          // A subtracted term (an edge's excess) is left out: the tangent stays positive
          // semi-definite, and the line search takes care of the rest.
          normal_scale_(std::max(0.0, stiffness_scale * p.stiffness + damping_scale * p.damping)),
          damping_scale_(damping_scale) {
        if (p.friction_normal > 0.0) {
            const double vn = dot3(p.relative_velocity, p.normal);
            for (int k = 0; k < 3; ++k) t_[k] = p.relative_velocity[k] - vn * p.normal[k];
            const double speed = std::sqrt(dot3(t_, t_));
            ft_ = friction_tangent(params, p.friction_normal, speed, chord);
            for (int k = 0; k < 3; ++k) t_[k] = speed > 0.0 ? t_[k] / speed : 0.0;
        }
    }

    void block(const double* ga, double wa, const double* gb, double wb, double out[9]) const {
        const double shares = damping_scale_ * wa * wb;
        for (int r = 0; r < 3; ++r)
            for (int s = 0; s < 3; ++s) {
                const double tangent_plane = (r == s ? 1.0 : 0.0) - p_.normal[r] * p_.normal[s];
                out[3 * r + s] = normal_scale_ * ga[r] * gb[s] +
                                 shares * (ft_.across * (tangent_plane - t_[r] * t_[s]) + ft_.along * t_[r] * t_[s]);
            }
    }

private:
    const ContactPoint& p_;
    double normal_scale_, damping_scale_;
    double t_[3] = {0.0, 0.0, 0.0};
    FrictionTangent ft_;
};


}  // namespace

BodyContacts::BodyContacts(const Body& body) : body_(body) {
    const size_t n = static_cast<size_t>(body.node_count());
    vec<uint8_t> on_surface(n, 0);
    node_area_.assign(n, 0.0);
    const vec<int32_t>& tris = body.surface_triangles;
    if (!tris.empty()) {
        for (size_t t = 0; t < tris.size(); t += 3) {
            double ab[3], ac[3], c[3];
            sub3(at(body.x.data(), tris[t + 1]), at(body.x.data(), tris[t]), ab);
            sub3(at(body.x.data(), tris[t + 2]), at(body.x.data(), tris[t]), ac);
            cross3(ab, ac, c);
            const double third = std::sqrt(dot3(c, c)) / 6.0;
            for (int k = 0; k < 3; ++k) {
                on_surface[static_cast<size_t>(tris[t + k])] = 1;
                node_area_[static_cast<size_t>(tris[t + k])] += third;
            }
        }
        boxes_.resize(tris.size() / 3);
    } else {
        for (size_t i = 0; i < n; ++i) on_surface[i] = body.mass[i] > 0.0;
    }
    for (size_t i = 0; i < n; ++i)
        if (on_surface[i]) surface_nodes_.push_back(static_cast<int32_t>(i));
    if (tris.empty()) boxes_.resize(surface_nodes_.size());
    // Each surface edge's two triangles.
    edge_neighbor_.assign(tris.size(), -1);
    pair_triangles_across_edges(tris.data(), tris.size() / 3, edge_neighbor_.data());
    edge_length_.resize(tris.size());
    for (size_t i = 0; i < tris.size(); ++i) {
        double e[3];
        sub3(at(body.rest.data(), tris[i]), at(body.rest.data(), tris[i - i % 3 + (i % 3 + 1) % 3]), e);
        edge_length_[i] = norm3(e);
    }
    stamp_.assign(n, 0);
}

void BodyContacts::clear() {
    candidates_.clear();
    groups_.clear();
}

void BodyContacts::refit(double margin) {
    margin_ = margin;
    const double* x = body_.x.data();
    const vec<int32_t>& tris = body_.surface_triangles;
    for (size_t b = 0; b < boxes_.size(); ++b) {
        Aabb box;
        if (!tris.empty())
            for (int k = 0; k < 3; ++k) box.add(at(x, tris[3 * b + k]));
        else
            box.add(at(x, surface_nodes_[b]));
        box.inflate(margin);
        boxes_[b] = box;
    }
    if (tree_.primitive_count() != static_cast<int32_t>(boxes_.size()) || boxes_.empty())
        tree_.build(boxes_.data(), static_cast<int32_t>(boxes_.size()));
    else
        tree_.refit(boxes_.data());
}

bool BodyContacts::detect(Collider& collider, double reach) {
    Collider* target = &collider;
    Group group{static_cast<int32_t>(candidates_.size()), 0};
    double lo[3], hi[3];
    collider.shape.bounds(collider.pose, reach, lo, hi);
    Aabb query;
    for (int k = 0; k < 3; ++k) {
        query.lo[k] = lo[k];
        query.hi[k] = hi[k];
    }
    const bool plane = collider.shape.kind() == SH_SHAPE_PLANE;
    double normal[3] = {0.0, 0.0, 1.0};
    const double local_z[3] = {0.0, 0.0, 1.0};
    if (plane) collider.pose.rotate(local_z, normal);
    const double* x = body_.x.data();
    const vec<int32_t>& tris = body_.surface_triangles;
    ++pass_;
    auto take_node = [&](int32_t node) {
        if (stamp_[static_cast<size_t>(node)] == pass_) return;
        stamp_[static_cast<size_t>(node)] = pass_;
        if (plane) {  // the plane's bounds are unbounded sideways: keep only nodes near it
            double d[3];
            sub3(at(x, node), collider.pose.p, d);
            if (dot3(d, normal) > reach) return;
        }
        candidates_.push_back({ContactCandidate::kNodeShape, node, {-1, -1, -1}, target, nullptr, &collider.params});
    };
    tree_.query(query, [&](int32_t prim) {
        if (tris.empty()) take_node(surface_nodes_[static_cast<size_t>(prim)]);
        else
            for (int k = 0; k < 3; ++k) take_node(tris[3 * static_cast<size_t>(prim) + k]);
    });
    if (!plane && !tris.empty())
        tree_.query(query, [&](int32_t prim) {
            const int32_t* t = &tris[3 * static_cast<size_t>(prim)];
            const double* length = &edge_length_[3 * static_cast<size_t>(prim)];
            const double face_weight = excess_weight(collider, std::max({length[0], length[1], length[2]}));
            if (face_weight > 0.0) {
                candidates_.push_back({ContactCandidate::kFaceShape, -1, {t[0], t[1], t[2]}, target, nullptr, &collider.params});
                candidates_.back().excess_weight = face_weight;
            }
            // Its edges, each once: from the triangle of higher index, or from this one where no
            // single triangle lies across (a border of the surface).
            for (int k = 0; k < 3; ++k) {
                const int32_t across = edge_neighbor_[3 * static_cast<size_t>(prim) + static_cast<size_t>(k)];
                const double edge_weight = excess_weight(collider, length[k]);
                if ((across >= 0 && across <= prim) || !(edge_weight > 0.0)) continue;
                candidates_.push_back({ContactCandidate::kEdgeShape, -1, {t[k], t[(k + 1) % 3], -1}, target, nullptr,
                                       &collider.params});
                candidates_.back().excess_weight = edge_weight;
            }
        });
    group.end = static_cast<int32_t>(candidates_.size());
    if (group.end == group.begin) return false;
    const bool dropped = keep_deepest(group, collider.params.capacity);
    groups_.push_back(group);
    return dropped;
}

void BodyContacts::ensure_tet_tree() {
    const int32_t* tets = body_.element_nodes();
    const size_t count = static_cast<size_t>(body_.element_count());
    tet_boxes_.resize(count);
    for (size_t t = 0; t < count; ++t) {
        Aabb box;
        for (int k = 0; k < 4; ++k) box.add(at(body_.x.data(), tets[4 * t + k]));
        tet_boxes_[t] = box;
    }
    if (tet_tree_.primitive_count() != static_cast<int32_t>(count)) tet_tree_.build(tet_boxes_.data(), static_cast<int32_t>(count));
    else tet_tree_.refit(tet_boxes_.data());
}

bool BodyContacts::detect_pair(BodyContacts& a, BodyContacts& b, const sh_contact_params& params) {
    b.ensure_tet_tree();
    const double* xa = a.body_.x.data();
    const double* xb = b.body_.x.data();
    const int32_t* tets = b.body_.element_nodes();
    const vec<int32_t>& tris = b.body_.surface_triangles;
    Group group_a{static_cast<int32_t>(a.candidates_.size()), 0};
    Group group_b{static_cast<int32_t>(b.candidates_.size()), 0};
    for (const int32_t node : a.surface_nodes_) {
        const double* p = at(xa, node);
        Aabb point;
        point.add(p);
        bool inside = false;
        b.tet_tree_.query(point, [&](int32_t t) {
            if (inside) return;
            const int32_t* tet = tets + 4 * static_cast<size_t>(t);
            // Barycentric coordinates of p by signed volumes.
            const double* v0 = at(xb, tet[0]);
            double e[3][3], r[3];
            for (int k = 0; k < 3; ++k) sub3(at(xb, tet[k + 1]), v0, e[k]);
            sub3(p, v0, r);
            double c12[3], c20[3], c01[3];
            cross3(e[1], e[2], c12);
            cross3(e[2], e[0], c20);
            cross3(e[0], e[1], c01);
            const double det = dot3(e[0], c12);
            if (!(std::fabs(det) > 0.0)) return;
            const double l1 = dot3(r, c12) / det, l2 = dot3(r, c20) / det, l3 = dot3(r, c01) / det;
            inside = l1 >= 0.0 && l2 >= 0.0 && l3 >= 0.0 && l1 + l2 + l3 <= 1.0;
        });
        // Outside b, the node is a candidate while the bodies may close the gap in the step
        // (without it, a node resting at the surface would fall a whole step into b each time
        // it is found outside, and chatter).
        const double reach = inside ? INFINITY : a.margin_ + b.margin_;
        if (!(reach > 0.0)) continue;
        double distance = 0.0;
        const int32_t tri = b.tree_.nearest(p, reach, [&](int32_t t) {
            double w[3];
            const int32_t* f = &tris[3 * static_cast<size_t>(t)];
            return closest_on_triangle(p, at(xb, f[0]), at(xb, f[1]), at(xb, f[2]), w);
        }, distance);
        if (tri < 0) continue;
        const int32_t* f = &tris[3 * static_cast<size_t>(tri)];
        if (!inside && !node_before_face(p, at(xb, f[0]), at(xb, f[1]), at(xb, f[2]))) continue;
        a.candidates_.push_back({ContactCandidate::kNodeFace, node, {f[0], f[1], f[2]}, nullptr, &b.body_, &params});
        b.candidates_.push_back({ContactCandidate::kFaceNode, node, {f[0], f[1], f[2]}, nullptr, &a.body_, &params});
    }
    group_a.end = static_cast<int32_t>(a.candidates_.size());
    group_b.end = static_cast<int32_t>(b.candidates_.size());
    bool dropped = false;
    if (group_a.end > group_a.begin) {
        dropped |= a.keep_deepest(group_a, params.capacity);
        a.groups_.push_back(group_a);
    }
    if (group_b.end > group_b.begin) {
        dropped |= b.keep_deepest(group_b, params.capacity);
        b.groups_.push_back(group_b);
    }
    return dropped;
}

bool BodyContacts::keep_deepest(Group& group, int32_t capacity) {
    const int32_t count = group.end - group.begin;
    if (count <= capacity) return false;
    keys_.resize(static_cast<size_t>(count));
    for (int32_t i = 0; i < count; ++i) {
        ContactPoint point;
        const ContactCandidate& c = candidates_[static_cast<size_t>(group.begin + i)];
        keys_[static_cast<size_t>(i)] = touching(c, body_.x.data(), nullptr, point) ? point.depth : -1.0;
    }
    // Order the group by depth, deepest first, and keep the first `capacity`.
    vec<int32_t> order(static_cast<size_t>(count));
    for (int32_t i = 0; i < count; ++i) order[static_cast<size_t>(i)] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](int32_t p, int32_t q) { return keys_[static_cast<size_t>(p)] > keys_[static_cast<size_t>(q)]; });
    vec<ContactCandidate> kept;
    kept.reserve(static_cast<size_t>(capacity));
    for (int32_t i = 0; i < capacity; ++i) kept.push_back(candidates_[static_cast<size_t>(group.begin + order[static_cast<size_t>(i)])]);
    candidates_.resize(static_cast<size_t>(group.begin));
    candidates_.insert(candidates_.end(), kept.begin(), kept.end());
    group.end = static_cast<int32_t>(candidates_.size());
    return true;
}

BodyContacts* BodyContacts::finish_detection(double h) {
    iterates_.clear();
    step_ = 0.0;
    if (candidates_.empty()) return nullptr;
    if (!implicit_step()) return this;
    bool friction = false;
    for (const ContactCandidate& c : candidates_) friction |= c.params->static_friction > 0.0;
    // At the step's start state (colliders where the step starts, see World::detect_contacts):
    // each candidate's depth, for the depth rate of the step's law, and for friction its
    // normal force (the law at rest) and where it acts.
    for (ContactCandidate& c : candidates_) c.friction_normal = c.start_depth = 0.0;
    vec<FrictionIterate> iterates(friction ? candidates_.size() : 0, FrictionIterate{});
    evaluate_candidates(body_.x.data(), body_.v.data(), [&](const ContactCandidate& c, const ContactPoint* point) {
        if (!point) return;
        const size_t index = static_cast<size_t>(&c - candidates_.data());
        candidates_[index].start_depth = point->depth;
        if (!friction) return;
        // Only pushing terms take friction (an edge's subtracted term would make the
        // dissipation potential concave): where a region straddles an edge, both faces carry
        // friction on their share.
        candidates_[index].friction_normal = std::max(point->net_normal_force, 0.0);
        FrictionIterate& r = iterates[index];
        for (int k = 0; k < 3; ++k) {
            r.lag_normal[k] = point->normal[k];
            r.lag_point[k] = point->point[k];
            // The face's barycentric weights, for the kinds with one.
            r.lag_face[k] = c.kind == ContactCandidate::kFaceShape || c.kind == ContactCandidate::kEdgeShape
                                ? (k < point->count ? point->weights[k] : 0.0)
                            : c.kind == ContactCandidate::kFaceNode ? -point->weights[k]
                            : c.kind == ContactCandidate::kNodeFace ? -point->other_weights[k]
                                                                    : 0.0;
        }
    });
    iterates_.swap(iterates);
    step_ = h;
    return this;
}

bool BodyContacts::implicit_step() const { return body_.settings.integrator == SH_INTEGRATOR_IMPLICIT_EULER; }

StepLaw BodyContacts::step_law(const ContactCandidate& c) const {
    return hunt_crossley_step_law(*c.params, c.start_depth, step_);
}

bool BodyContacts::lagged_friction(const ContactCandidate& c, const double* v, ContactPoint& out) const {
    // An implicit body's friction is that of the step's start: the normal force, normal, point
    // and weights there (lagged, as in IPC), so that it depends on the velocities alone and is
    // the gradient of a dissipation potential (dissipation()). A candidate that touched at the
    // start keeps it through the step even at iterates where it has come off: else it would
    // vanish as a node leaves the surface, a jump Newton cannot converge across.
    if (!(c.friction_normal > 0.0) || iterates_.size() != candidates_.size() || !(c.params->static_friction > 0.0))
        return false;
    const FrictionIterate& r = iterates_[static_cast<size_t>(&c - candidates_.data())];
    double vrel[3] = {0.0, 0.0, 0.0};
    int count = 1;
    const int32_t* nodes = &c.node;
    double weights[3] = {1.0, 0.0, 0.0};
    switch (c.kind) {
        case ContactCandidate::kNodeShape:
        case ContactCandidate::kFaceShape:
        case ContactCandidate::kEdgeShape: {
            double vc[3];
            c.collider->point_velocity(r.lag_point, vc);
            if (c.kind == ContactCandidate::kFaceShape || c.kind == ContactCandidate::kEdgeShape) {
                count = c.kind == ContactCandidate::kFaceShape ? 3 : 2;
                nodes = c.face;
                for (int k = 0; k < 3; ++k) weights[k] = r.lag_face[k];
            }
            for (int k = 0; k < 3; ++k) vrel[k] = -vc[k];
            break;
        }
        case ContactCandidate::kNodeFace:
            for (int a = 0; a < 3; ++a)
                for (int k = 0; k < 3; ++k) vrel[k] -= r.lag_face[a] * at(c.other->v.data(), c.face[a])[k];
            for (int k = 0; k < 3; ++k) out.other_weights[k] = -r.lag_face[k];
            break;
        case ContactCandidate::kFaceNode:
            count = 3;
            nodes = c.face;
            for (int k = 0; k < 3; ++k) {
                weights[k] = -r.lag_face[k];
                vrel[k] = at(c.other->v.data(), c.node)[k];
            }
            break;
    }
    out.depth = 0.0;
    out.count = count;
    for (int k = 0; k < 3; ++k) {
        out.normal[k] = r.lag_normal[k];
        out.point[k] = r.lag_point[k];
    }
    for (int a = 0; a < count; ++a) {
        out.nodes[a] = nodes[a];
        out.weights[a] = weights[a];
        for (int k = 0; k < 3; ++k) {
            out.gradient[a][k] = weights[a] * out.normal[k];
            vrel[k] += weights[a] * at(v, nodes[a])[k];
        }
    }
    out.stiffness = out.damping = out.normal_force = 0.0;
    out.law_scale = 1.0;
    out.friction_normal = c.friction_normal;
    for (int k = 0; k < 3; ++k) out.relative_velocity[k] = vrel[k];
    const double vn = dot3(vrel, out.normal);
    double vt[3], ft[3];
    for (int k = 0; k < 3; ++k) vt[k] = vrel[k] - vn * out.normal[k];
    out.friction = coulomb_friction(*c.params, out.friction_normal, vt, ft);
    for (int a = 0; a < count; ++a)
        for (int k = 0; k < 3; ++k) out.node_force[a][k] = weights[a] * ft[k];
    return true;
}

bool BodyContacts::touching(const ContactCandidate& c, const double* x, const double* v, ContactPoint& out) const {
    const sh_contact_params& p = *c.params;
    double vrel[3] = {0.0, 0.0, 0.0};  // velocity of the node side relative to the other side
    out.law_scale = 1.0;
    auto set_nodes = [&](int count, const int32_t* nodes, const double* weights) {
        out.count = count;
        for (int a = 0; a < count; ++a) {
            out.nodes[a] = nodes[a];
            out.weights[a] = weights[a];
            for (int k = 0; k < 3; ++k) out.gradient[a][k] = weights[a] * out.normal[k];
        }
    };
    const double one = 1.0;
    switch (c.kind) {
        case ContactCandidate::kNodeShape:
            if (!node_shape_contact(*c.collider, x, c.node, out)) return false;
            break;
        case ContactCandidate::kEdgeShape:
        case ContactCandidate::kFaceShape: {
            // The law (with its damping in the depth for implicit steps) is part of the
            // excess's maximisation; explicit bodies scale it by the depth rate after.
            if (!excess_shape_contact(*c.collider, step_law(c), x, c.face, c.kind == ContactCandidate::kFaceShape ? 3 : 2,
                                      c.excess_weight, out))
                return false;
            if (!v || implicit_step()) return true;
            velocity_against_collider(*c.collider, out, v, vrel);
            apply_excess_damping(p, vrel, out);
            if (out.net_normal_force > 0.0 && p.static_friction > 0.0) apply_friction(p, out.net_normal_force, out);
            return true;
        }
        case ContactCandidate::kNodeFace:
        case ContactCandidate::kFaceNode: {
            const bool own_node = c.kind == ContactCandidate::kNodeFace;
            const double* xn = own_node ? x : c.other->x.data();
            const double* xf = own_node ? c.other->x.data() : x;
            double w[3];
            if (!node_behind_face(at(xn, c.node), at(xf, c.face[0]), at(xf, c.face[1]), at(xf, c.face[2]), out.depth,
                                  out.normal, w))
                return false;
            for (int k = 0; k < 3; ++k) out.point[k] = at(xn, c.node)[k];
            if (own_node) {
                set_nodes(1, &c.node, &one);
                for (int k = 0; k < 3; ++k) out.other_weights[k] = -w[k];
            } else {
                const double far_side[3] = {-w[0], -w[1], -w[2]};
                set_nodes(3, c.face, far_side);
            }
            if (v) {
                const double* vn = own_node ? v : c.other->v.data();
                const double* vf = own_node ? c.other->v.data() : v;
                for (int k = 0; k < 3; ++k)
                    vrel[k] = at(vn, c.node)[k] - (w[0] * at(vf, c.face[0])[k] + w[1] * at(vf, c.face[1])[k] +
                                                   w[2] * at(vf, c.face[2])[k]);
            }
            break;
        }
    }
    if (v && c.collider) velocity_against_collider(*c.collider, out, v, vrel);
    if (implicit_step() && v) {
        // In an implicit step the depth rate is the step's backward difference, so the normal
        // force is a function of the positions, the gradient of energy(); its friction comes
        // separately from the step's start (evaluate_friction).
        apply_step_normal_law(p, step_law(c), vrel, out);
        return true;
    }
    apply_normal_law(p, v ? vrel : nullptr, out);
    // Explicit bodies evaluate forces at the (sub)step's start: the friction there is
    // proportional to the normal force there.
    if (v && out.normal_force > 0.0 && p.static_friction > 0.0) apply_friction(p, out.normal_force, out);
    return true;
}

template <class Emit>
void BodyContacts::evaluate_friction(const double* v, Emit&& emit) const {
    if (!v || iterates_.size() != candidates_.size()) return;  // iterates_: implicit bodies only
    for (const ContactCandidate& c : candidates_) {
        ContactPoint point;
        if (lagged_friction(c, v, point)) emit(c, point);
    }
}

template <class Emit>
void BodyContacts::evaluate_candidates(const double* x, const double* v, Emit&& emit) const {
    for (const Group& group : groups_) {
        for (int32_t i = group.begin; i < group.end; ++i) {
            const ContactCandidate& c = candidates_[static_cast<size_t>(i)];
            ContactPoint point;
            if (!touching(c, x, v, point)) {
                emit(c, static_cast<const ContactPoint*>(nullptr));
                continue;
            }
            emit(c, &point);
        }
    }
}

template <class Emit>
void BodyContacts::evaluate(const double* x, const double* v, Emit&& emit) const {
    evaluate_candidates(x, v, [&](const ContactCandidate& c, const ContactPoint* point) {
        if (point) emit(c, *point);
    });
}

void BodyContacts::add_forces(const double* x, const double* v, double* f) const {
    const ScopedTimer timer(evaluation_seconds_);
    // Explicit bodies feel their friction in end_explicit_step, not here.
    const bool explicit_friction = !implicit_step();
    const bool record = recording_ && v;
    if (record) friction_records_.clear();
    recording_ = false;
    const auto add = [&](const ContactPoint& p, bool normal_only) {
        for (int a = 0; a < p.count; ++a)
            for (int k = 0; k < 3; ++k)
                f[3 * static_cast<size_t>(p.nodes[a]) + k] += normal_only ? p.normal_force * p.gradient[a][k] : p.node_force[a][k];
    };
    evaluate(x, v, [&](const ContactCandidate& c, const ContactPoint& p) {
        const bool friction = explicit_friction && p.friction_normal > 0.0;
        add(p, friction);
        if (friction && record) friction_records_.push_back(friction_record(p, *c.params, v));
    });
    evaluate_friction(v, [&](const ContactCandidate& c, const ContactPoint& p) {
        record_friction_iterate(c, &p);
        add(p, false);
    });
}

bool BodyContacts::does_work() const {
    for (const ContactCandidate& c : candidates_) {
        if (c.other) return true;
        const double* u = c.collider->velocity;
        const double* w = c.collider->angular;
        if (u[0] != 0.0 || u[1] != 0.0 || u[2] != 0.0 || w[0] != 0.0 || w[1] != 0.0 || w[2] != 0.0) return true;
    }
    return false;
}

double BodyContacts::dissipation(const double* v) const {
    double total = 0.0;
    evaluate_friction(v, [&](const ContactCandidate& c, const ContactPoint& p) {
        const double vn = dot3(p.relative_velocity, p.normal);
        double vt[3];
        for (int k = 0; k < 3; ++k) vt[k] = p.relative_velocity[k] - vn * p.normal[k];
        total += friction_potential(*c.params, p.friction_normal, norm3(vt));
    });
    return total;
}

void BodyContacts::mark_nodes_of_other_contacts(const Collider* except, uint8_t* marks) const {
    for (const ContactCandidate& c : candidates_) {
        if (c.collider && c.collider == except) continue;
        switch (c.kind) {
            case ContactCandidate::kNodeShape:
            case ContactCandidate::kNodeFace: marks[c.node] = 1; break;
            case ContactCandidate::kEdgeShape: marks[c.face[0]] = marks[c.face[1]] = 1; break;
            case ContactCandidate::kFaceShape:
            case ContactCandidate::kFaceNode:
                for (const int32_t node : c.face) marks[node] = 1;
                break;
        }
    }
}

void BodyContacts::begin_explicit_step() const {
    recording_ = true;
    friction_records_.clear();
}

void BodyContacts::end_explicit_step(double h, bool move_positions, double* x, double* v) const {
    // Friction taken implicitly on the velocities the step reached without it, contact by
    // contact (Gauss-Seidel over contacts sharing nodes), with the normal force and normal of
    // the step's start (see apply_implicit_friction).
    recording_ = false;
    for (const FrictionRecord& r : friction_records_)
        apply_implicit_friction(r, body_.inverse_mass.data(), h, move_positions ? x : nullptr, v);
    friction_records_.clear();
}

namespace {

// The blocks of one contact point's tangent among its own nodes (free_index >= 0) into system.
void add_point_tangent(const ContactPoint& p, const PointTangent& tangent, const int32_t* free_index,
                       SparseSystem& system) {
    for (int a = 0; a < p.count; ++a) {
        const int32_t fa = free_index[p.nodes[a]];
        if (fa < 0) continue;
        for (int b = a; b < p.count; ++b) {
            const int32_t fb = free_index[p.nodes[b]];
            if (fb < 0) continue;
            double block[9];
            tangent.block(p.gradient[a], p.weights[a], p.gradient[b], p.weights[b], block);
            system.add_block(fa, fb, block, 1.0);
        }
    }
}

}  // namespace

void BodyContacts::add_tangent(const double* x, const double* v, double stiffness_scale, double damping_scale,
                               const int32_t* free_index, SparseSystem& system) const {
    const ScopedTimer timer(evaluation_seconds_);
    evaluate(x, v, [&](const ContactCandidate& c, const ContactPoint& p) {
        add_point_tangent(p, PointTangent(p, *c.params, stiffness_scale, damping_scale), free_index, system);
    });
    evaluate_friction(v, [&](const ContactCandidate& c, const ContactPoint& p) {
        const PointTangent tangent(p, *c.params, stiffness_scale, damping_scale, friction_chord(c, p));
        add_point_tangent(p, tangent, free_index, system);
    });
}

// Friction's tangent in an implicit step.
//
// With the normal force lagged, friction depends on the slip velocity alone, and its exact
// (positive semi-definite) tangent makes Newton quadratic while the contacts stay in their
// regime. But a step in which a sliding contact comes to stick (a block stopping on a slope, a
// tool stopping) defeats it whenever h mu fn / m is well above slip_velocity s0: from a
// sliding iterate the linearised friction is the saturated force, unchanging along the slip,
// so the update lands far on the other side of the narrow sticking band, and from there back;
// Newton cycles. The secant through zero slip (|F| / s along the slip, "lagged diffusivity")
// cannot overshoot so, but it creeps towards the band at a linear rate.
//
// So the exact tangent until a contact's slip turns back between two tangents of the step
// (the cycle's signature); from then on the contact's tangent along its slip comes from the
// one-dimensional problem it is part of, which the iterates reveal. The update that took it
// from one iterate to the next balanced its rows with the friction of the linear model it was
// given, F_prev - D (vrel - vrel_prev): the residual left at the new iterate (over h) is that
// model's error, F_model - F. The update also shows how stiffly the rest of the system
// answered along it: (J_rest dv) / h = -(residual_prev + D dv). With that stiffness mu_eff
// (N s/m) the contact's own problem near the iterate is mu_eff (v - w) = F(v), the implicit
// friction of a step of a body of mass h mu_eff (implicit_slip_speed), whose solution v* it
// computes exactly; the tangent along the slip is set so that the update (slope mu_eff +
// along) lands on v*. While mu_eff is not known (not positive, or fewer than two updates
// seen), the secant through zero slip. A heuristic for a non-smooth problem, not a proof:
// it converges in the inclined-plane tests of test_contact.c within the default 20 Newton
// iterations (contacts landing, stopping and sliding at dt up to 10 ms), where the exact
// tangent alone fails; with mu_s > mu_d (friction that weakens with speed: the problem is not
// convex) a stopping step can take more, so raise newton_max_iterations there. A line search
// on the step's incremental potential (which with the normal force lagged includes friction's
// dissipation potential, friction_potential) would make it robust.

void BodyContacts::record_friction_iterate(const ContactCandidate& c, const ContactPoint* point) const {
    FrictionIterate& r = iterates_[static_cast<size_t>(&c - candidates_.data())];
    if (!point || !(point->friction_normal > 0.0)) {
        r.has_cur = r.has_prev = false;  // no friction here: the chain of updates breaks
        return;
    }
    const double* u = point->relative_velocity;
    auto same = [](const double* a, const double* b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; };
    if (!r.has_start) {
        for (int k = 0; k < 3; ++k) r.start_vrel[k] = u[k];
        r.has_start = true;
    } else if (same(u, r.start_vrel)) {  // the step starts again (retried, or after half steps)
        r.has_cur = r.has_prev = r.has_tangent = r.reversed = false;
        r.tangents = 0;
    }
    if (r.has_cur && same(u, r.cur.vrel)) return;  // the same iterate again
    if (r.has_prev && same(u, r.prev.vrel)) {      // back to the iterate before (an update taken back)
        r.cur = r.prev;
        r.has_prev = false;
        return;
    }
    // A new iterate, reached from the latest one by an update with the last tangent.
    r.has_prev = r.has_cur;
    if (r.has_cur) r.prev = r.cur;
    r.has_cur = true;
    FrictionIterate::Point& q = r.cur;
    double slip[3];
    const double vn = dot3(u, point->normal);
    for (int k = 0; k < 3; ++k) {
        q.vrel[k] = u[k];
        slip[k] = u[k] - vn * point->normal[k];
    }
    coulomb_friction(*c.params, point->friction_normal, slip, q.force);
    q.has_residual = q.has_response = false;
    q.response = 0.0;
    if (!(r.has_prev && r.has_tangent)) return;
    double dv[3], d_dv[3];  // the update, and the last tangent times it
    for (int k = 0; k < 3; ++k) dv[k] = u[k] - r.prev.vrel[k];
    for (int k = 0; k < 3; ++k) d_dv[k] = r.tangent[3 * k] * dv[0] + r.tangent[3 * k + 1] * dv[1] + r.tangent[3 * k + 2] * dv[2];
    for (int k = 0; k < 3; ++k) q.residual[k] = r.prev.force[k] - d_dv[k] - q.force[k];
    q.has_residual = true;
    const double dv2 = dot3(dv, dv);
    if (r.prev.has_residual && dv2 > 0.0) {
        double answer[3];
        for (int k = 0; k < 3; ++k) answer[k] = -(r.prev.residual[k] + d_dv[k]);
        q.response = dot3(answer, dv) / dv2;
        q.has_response = q.response > 0.0 && std::isfinite(q.response);
    }
}

double BodyContacts::friction_chord(const ContactCandidate& c, const ContactPoint& p) const {
    if (!(p.friction_normal > 0.0) || iterates_.size() != candidates_.size()) return -1.0;
    FrictionIterate& r = iterates_[static_cast<size_t>(&c - candidates_.data())];
    const sh_contact_params& params = *c.params;
    const double s0 = params.slip_velocity;
    const double vn = dot3(p.relative_velocity, p.normal);
    double slip[3], t[3];
    for (int k = 0; k < 3; ++k) slip[k] = p.relative_velocity[k] - vn * p.normal[k];
    const double speed = std::sqrt(dot3(slip, slip));
    for (int k = 0; k < 3; ++k) t[k] = speed > 0.0 ? slip[k] / speed : 0.0;
    if (r.tangents > 0 && dot3(r.last_slip, slip) < 0.0) r.reversed = true;
    for (int k = 0; k < 3; ++k) r.last_slip[k] = slip[k];
    ++r.tangents;

    double chord = -1.0;
    if (r.reversed && speed > s0) {
        const double secant = friction_magnitude(params, p.friction_normal, speed) / speed;
        chord = secant;
        const FrictionIterate::Point& q = r.cur;
        const bool here = r.has_cur && q.vrel[0] == p.relative_velocity[0] && q.vrel[1] == p.relative_velocity[1] &&
                          q.vrel[2] == p.relative_velocity[2];
        if (here && q.has_residual && q.has_response) {
            // The contact's own problem: response (v - w) = F(v), on the tangent plane.
            double w[3];
            for (int k = 0; k < 3; ++k) w[k] = slip[k] - (q.residual[k] + q.force[k]) / q.response;
            const double wn = dot3(w, p.normal);
            for (int k = 0; k < 3; ++k) w[k] -= wn * p.normal[k];
            const double free_speed = std::sqrt(dot3(w, w));
            const double end_speed = implicit_slip_speed(params, p.friction_normal, free_speed, 1.0 / q.response);
            const double target = free_speed > 0.0 ? dot3(w, t) * end_speed / free_speed : 0.0;  // along t
            if (target != speed) {
                // The update solves (response + along) (target - speed) = -residual . t.
                const double along = -dot3(q.residual, t) / (target - speed) - q.response;
                if (std::isfinite(along)) chord = std::min(std::max(along, 0.0), params.static_friction * p.friction_normal / s0);
            }
        }
    }
    const FrictionTangent ft = friction_tangent(params, p.friction_normal, speed, chord);
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const double plane = (a == b ? 1.0 : 0.0) - p.normal[a] * p.normal[b];
            r.tangent[3 * a + b] = ft.across * (plane - t[a] * t[b]) + ft.along * t[a] * t[b];
        }
    r.has_tangent = true;
    return chord;
}

template <class Visit>
void BodyContacts::for_each_pair_candidate(const Body& other, const int32_t* own_index, Visit&& visit) const {
    for (const ContactCandidate& c : candidates_)
        if (c.kind == ContactCandidate::kNodeFace && c.other == &other && own_index[c.node] >= 0) visit(c);
}

void BodyContacts::add_coupling_pattern(const Body& other, const int32_t* own_index, const int32_t* other_index,
                                        vec<int32_t>& pairs) const {
    for_each_pair_candidate(other, own_index, [&](const ContactCandidate& c) {
        for (int k = 0; k < 3; ++k)
            if (other_index[c.face[k]] >= 0) {
                pairs.push_back(own_index[c.node]);
                pairs.push_back(other_index[c.face[k]]);
            }
    });
}

void BodyContacts::add_coupling_tangent(const double* x, const double* v, double stiffness_scale, double damping_scale,
                                        const int32_t* own_index, const Body& other, const int32_t* other_index,
                                        SparseSystem& system) const {
    // A body-pair contact is one term over its node and the face behind it: this body's node
    // with gradient n and share 1, the other's face nodes with -w_k n and -w_k. Each body's
    // add_tangent has the blocks among its own nodes; these are the ones across.
    const ScopedTimer timer(evaluation_seconds_);
    const auto add = [&](const ContactCandidate& c, const ContactPoint& p) {
        const PointTangent tangent(p, *c.params, stiffness_scale, damping_scale);
        for (int k = 0; k < 3; ++k) {
            const int32_t j = other_index[c.face[k]];
            if (j < 0) continue;
            double gradient[3], block[9];
            for (int r = 0; r < 3; ++r) gradient[r] = p.other_weights[k] * p.normal[r];
            tangent.block(p.gradient[0], p.weights[0], gradient, p.other_weights[k], block);
            system.add_block(own_index[c.node], j, block, 1.0);
        }
    };
    for_each_pair_candidate(other, own_index, [&](const ContactCandidate& c) {
        ContactPoint p;
        if (touching(c, x, v, p)) add(c, p);
        if (v && lagged_friction(c, v, p)) add(c, p);
    });
}

double BodyContacts::energy(const double* x) const {
    // The potential of the step's law (its damping is in the depth); at rest its elastic part.
    double e = 0.0;
    evaluate(x, nullptr, [&](const ContactCandidate& c, const ContactPoint& p) {
        const bool pair = c.kind == ContactCandidate::kNodeFace || c.kind == ContactCandidate::kFaceNode;
        const bool excess = c.kind == ContactCandidate::kFaceShape || c.kind == ContactCandidate::kEdgeShape;
        e += excess ? p.energy : (pair ? 0.5 : 1.0) * p.law_scale * hunt_crossley_step_energy(*c.params, step_law(c), p.depth);
    });
    return e;
}

double BodyContacts::stable_step(const double* x, const double* v, const double* mass) const {
    // Each own node's row of k g g^T is at most k |g_a| sum_b |g_b| (Gershgorin), at the depth
    // the contact has now plus what the step may add. A candidate not touching yet is bounded
    // by a share of 1 (its weights sum to 1) on each node it may touch.
    double step = INFINITY;
    evaluate_candidates(x, v, [&](const ContactCandidate& c, const ContactPoint* point) {
        const bool face = c.kind == ContactCandidate::kFaceShape || c.kind == ContactCandidate::kFaceNode ||
                          c.kind == ContactCandidate::kEdgeShape;
        const int count = point ? point->count : c.kind == ContactCandidate::kEdgeShape ? 2 : face ? 3 : 1;
        const NormalForce fn = hunt_crossley(*c.params, (point ? point->depth : 0.0) + anticipated_depth, 0.0);
        double row = 0.0;
        for (int b = 0; point && b < count; ++b) row += std::sqrt(dot3(point->gradient[b], point->gradient[b]));
        for (int a = 0; a < count; ++a) {
            const int32_t node = point ? point->nodes[a] : face ? c.face[a] : c.node;
            if (!body_.is_free(node)) continue;
            const double share = point ? std::sqrt(dot3(point->gradient[a], point->gradient[a])) * row : 1.0;
            step = std::min(step, damped_stable_step(share * fn.stiffness, share * fn.damping, mass[node]));
        }
    });
    return step;
}

int32_t BodyContacts::accumulate_reactions() {
    // The contacts that act: the nodes in contact, and per collider the regions where it
    // reaches beyond them, faces minus edges (their number, see shape_contact.hpp; where the
    // nodes leave holes in such a region the difference falls below 1: one is counted).
    int32_t count = 0, regions = 0;
    bool faces_act = false;
    Collider* region_collider = nullptr;
    const auto close_regions = [&]() {
        const int32_t counted = std::max(regions, faces_act ? 1 : 0);
        faces_act = false;
        count += counted;
        if (region_collider) region_collider->state.contact_count += counted;
        regions = 0;
    };
    const auto accumulate = [&](const ContactCandidate& c, const ContactPoint& p) {
        if (c.kind == ContactCandidate::kFaceNode) return;
        const bool excess = c.kind == ContactCandidate::kFaceShape || c.kind == ContactCandidate::kEdgeShape;
        if (c.collider != region_collider) {
            close_regions();
            region_collider = c.collider;
        }
        if (p.depth > 0.0 && excess) {
            regions += c.kind == ContactCandidate::kEdgeShape ? -1 : 1;
            faces_act |= c.kind == ContactCandidate::kFaceShape;
        }
        if (p.depth > 0.0 && !excess) ++count;
        if (!c.collider) return;
        sh_contact_state& s = c.collider->state;
        for (int a = 0; a < p.count; ++a) {
            double r[3], torque[3];
            const double reaction[3] = {-p.node_force[a][0], -p.node_force[a][1], -p.node_force[a][2]};
            sub3(&body_.x[3 * static_cast<size_t>(p.nodes[a])], c.collider->pose.p, r);
            cross3(r, reaction, torque);
            for (int k = 0; k < 3; ++k) {
                s.force[k] += reaction[k];
                s.torque[k] += torque[k];
            }
        }
        if (!(p.depth > 0.0)) return;  // friction kept through a step on a contact that came off
        if (!excess) ++s.contact_count;
        s.max_depth = std::max(s.max_depth, p.depth);
        if (c.kind == ContactCandidate::kNodeShape) s.penetration_volume += p.depth * node_area_[static_cast<size_t>(c.node)];
    };
    evaluate(body_.x.data(), body_.v.data(), accumulate);
    close_regions();
    region_collider = nullptr;
    evaluate_friction(body_.v.data(), accumulate);
    return count;
}

}  // namespace sh
