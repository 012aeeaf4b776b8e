#include "contact/body_contacts.hpp"

#include "collision/closest_point.hpp"
#include "contact/hunt_crossley.hpp"
#include "core/clock.hpp"
#include "solver/sparse_system.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

inline void sub(const double* a, const double* b, double* out) {
    for (int k = 0; k < 3; ++k) out[k] = a[k] - b[k];
}
inline double dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline void cross(const double* a, const double* b, double* out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

// A node p behind triangle (a, b, c) of another body: depth below its plane along the outward
// unit normal n, and the barycentric weights of the nearest point of the triangle to p's
// projection. False if p is in front, the triangle is degenerate, or p has slid off it.
bool node_behind_face(const double* p, const double* a, const double* b, const double* c, double& depth, double n[3],
                      double w[3]) {
    double ab[3], ac[3], ap[3];
    sub(b, a, ab);
    sub(c, a, ac);
    cross(ab, ac, n);
    const double area2 = std::sqrt(dot(n, n));
    const double edge2 = std::max(dot(ab, ab), dot(ac, ac));
    if (!(area2 > 1e-14 * edge2)) return false;
    for (int k = 0; k < 3; ++k) n[k] /= area2;
    sub(p, a, ap);
    depth = -dot(n, ap);
    if (!(depth > 0.0)) return false;
    double q[3];
    for (int k = 0; k < 3; ++k) q[k] = p[k] + depth * n[k];
    const double lateral = closest_on_triangle(q, a, b, c, w);
    return lateral * lateral <= edge2;
}

inline const double* at(const double* x, int32_t node) { return x + 3 * static_cast<size_t>(node); }


}  // namespace

BodyContacts::BodyContacts(const Body& body) : body_(body) {
    const size_t n = static_cast<size_t>(body.node_count());
    vec<uint8_t> on_surface(n, 0);
    node_area_.assign(n, 0.0);
    const vec<int32_t>& tris = body.surface_triangles;
    if (!tris.empty()) {
        for (size_t t = 0; t < tris.size(); t += 3) {
            double ab[3], ac[3], c[3];
            sub(at(body.x.data(), tris[t + 1]), at(body.x.data(), tris[t]), ab);
            sub(at(body.x.data(), tris[t + 2]), at(body.x.data(), tris[t]), ac);
            cross(ab, ac, c);
            const double third = std::sqrt(dot(c, c)) / 6.0;
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
    stamp_.assign(n, 0);
    node_depth_.assign(n, 0.0);
}

void BodyContacts::clear() {
    candidates_.clear();
    groups_.clear();
}

void BodyContacts::refit(double margin) {
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
            sub(at(x, node), collider.pose.p, d);
            if (dot(d, normal) > reach) return;
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
            candidates_.push_back({ContactCandidate::kFaceShape, -1, {t[0], t[1], t[2]}, target, nullptr, &collider.params});
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
            for (int k = 0; k < 3; ++k) sub(at(xb, tet[k + 1]), v0, e[k]);
            sub(p, v0, r);
            double c12[3], c20[3], c01[3];
            cross(e[1], e[2], c12);
            cross(e[2], e[0], c20);
            cross(e[0], e[1], c01);
            const double det = dot(e[0], c12);
            if (!(std::fabs(det) > 0.0)) return;
            const double l1 = dot(r, c12) / det, l2 = dot(r, c20) / det, l3 = dot(r, c01) / det;
            inside = l1 >= 0.0 && l2 >= 0.0 && l3 >= 0.0 && l1 + l2 + l3 <= 1.0;
        });
        if (!inside) continue;
        double distance = 0.0;
        const int32_t tri = b.tree_.nearest(p, INFINITY, [&](int32_t t) {
            double w[3];
            const int32_t* f = &tris[3 * static_cast<size_t>(t)];
            return closest_on_triangle(p, at(xb, f[0]), at(xb, f[1]), at(xb, f[2]), w);
        }, distance);
        if (tri < 0) continue;
        const int32_t* f = &tris[3 * static_cast<size_t>(tri)];
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
        keys_[static_cast<size_t>(i)] = contact(c, body_.x.data(), nullptr, point) ? point.depth : -1.0;
    }
    // Order the group by depth, deepest first, and keep the first `capacity`.
    vec<int32_t> order(static_cast<size_t>(count));
    for (int32_t i = 0; i < count; ++i) order[static_cast<size_t>(i)] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](int32_t p, int32_t q) { return keys_[static_cast<size_t>(p)] > keys_[static_cast<size_t>(q)]; });
    vec<ContactCandidate> kept;
    kept.reserve(static_cast<size_t>(capacity));
    for (int32_t i = 0; i < capacity; ++i) kept.push_back(candidates_[static_cast<size_t>(group.begin + order[static_cast<size_t>(i)])]);
    // Node kinds before face kinds, so that a face sees its nodes' contacts first.
    std::stable_partition(kept.begin(), kept.end(), [](const ContactCandidate& c) {
        return c.kind == ContactCandidate::kNodeShape || c.kind == ContactCandidate::kNodeFace;
    });
    candidates_.resize(static_cast<size_t>(group.begin));
    candidates_.insert(candidates_.end(), kept.begin(), kept.end());
    group.end = static_cast<int32_t>(candidates_.size());
    return true;
}

bool BodyContacts::contact(const ContactCandidate& c, const double* x, const double* v, ContactPoint& out) const {
    const sh_contact_params& p = *c.params;
    double vrel[3] = {0.0, 0.0, 0.0};  // velocity of the node side relative to the other side
    double touched_mass = INFINITY;    // smallest own mass the friction acts on
    const double* mass = body_.mass.data();
    auto set_nodes = [&](int count, const int32_t* nodes, const double* weights) {
        out.count = count;
        for (int a = 0; a < count; ++a) {
            out.nodes[a] = nodes[a];
            out.weights[a] = weights[a];
            for (int k = 0; k < 3; ++k) out.gradient[a][k] = weights[a] * out.normal[k];
            touched_mass = std::min(touched_mass, mass[nodes[a]]);
        }
    };
    const double one = 1.0;
    switch (c.kind) {
        case ContactCandidate::kNodeShape: {
            Penetration pen;
            if (!c.collider->shape.penetrate_point(c.collider->pose, at(x, c.node), pen)) return false;
            out.depth = pen.depth;
            for (int k = 0; k < 3; ++k) {
                out.normal[k] = pen.normal[k];
                out.point[k] = pen.point[k];
            }
            set_nodes(1, &c.node, &one);
            if (v) {
                double vc[3];
                c.collider->point_velocity(out.point, vc);
                sub(at(v, c.node), vc, vrel);
            }
            break;
        }
        case ContactCandidate::kFaceShape: {
            Penetration pen;
            double w[3];
            if (!c.collider->shape.penetrate_triangle(c.collider->pose, at(x, c.face[0]), at(x, c.face[1]),
                                                      at(x, c.face[2]), pen, w))
                return false;
            // A tool between the nodes: once one of them touches the same collider, the node
            // contacts carry it (their constraint is what the mesh can resolve).
            for (int k = 0; k < 3; ++k)
                if (node_depth_[static_cast<size_t>(c.face[k])] > 0.0) return false;
            out.depth = pen.depth;
            for (int k = 0; k < 3; ++k) {
                out.normal[k] = pen.normal[k];
                out.point[k] = pen.point[k];
            }
            set_nodes(3, c.face, w);
            if (v) {
                double vc[3];
                c.collider->point_velocity(out.point, vc);
                for (int k = 0; k < 3; ++k)
                    vrel[k] = w[0] * at(v, c.face[0])[k] + w[1] * at(v, c.face[1])[k] + w[2] * at(v, c.face[2])[k] - vc[k];
            }
            break;
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
    const double normal_speed = dot(out.normal, vrel);
    const NormalForce fn = hunt_crossley(p, out.depth, -normal_speed);
    out.stiffness = fn.stiffness;
    out.damping = fn.damping;
    out.friction = 0.0;
    double ft[3] = {0.0, 0.0, 0.0};
    if (v && fn.force > 0.0 && p.static_friction > 0.0) {
        double vt[3];
        for (int k = 0; k < 3; ++k) vt[k] = vrel[k] - normal_speed * out.normal[k];
        out.friction = coulomb_friction(p, fn.force, vt, ft);
        if (friction_rate_limit > 0.0 && out.friction > touched_mass * friction_rate_limit) {
            const double scale = touched_mass * friction_rate_limit / out.friction;
            out.friction *= scale;
            for (double& f : ft) f *= scale;
        }
    }
    for (int a = 0; a < out.count; ++a)
        for (int k = 0; k < 3; ++k) out.node_force[a][k] = fn.force * out.gradient[a][k] + out.weights[a] * ft[k];
    return true;
}

template <class Emit>
void BodyContacts::evaluate_candidates(const double* x, const double* v, Emit&& emit) const {
    for (const Group& group : groups_) {
        for (int32_t i = group.begin; i < group.end; ++i) {
            const ContactCandidate& c = candidates_[static_cast<size_t>(i)];
            ContactPoint point;
            if (!contact(c, x, v, point)) {
                emit(c, static_cast<const ContactPoint*>(nullptr));
                continue;
            }
            if (c.kind == ContactCandidate::kNodeShape) node_depth_[static_cast<size_t>(c.node)] = point.depth;
            emit(c, &point);
        }
        for (int32_t i = group.begin; i < group.end; ++i) {
            const ContactCandidate& c = candidates_[static_cast<size_t>(i)];
            if (c.kind == ContactCandidate::kNodeShape) node_depth_[static_cast<size_t>(c.node)] = 0.0;
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
    evaluate(x, v, [&](const ContactCandidate&, const ContactPoint& p) {
        for (int a = 0; a < p.count; ++a)
            for (int k = 0; k < 3; ++k) f[3 * static_cast<size_t>(p.nodes[a]) + k] += p.node_force[a][k];
    });
}

void BodyContacts::add_tangent(const double* x, const double* v, double stiffness_scale, double damping_scale,
                               const int32_t* free_index, SparseSystem& system) const {
    const ScopedTimer timer(evaluation_seconds_);
    evaluate(x, v, [&](const ContactCandidate&, const ContactPoint& p) {
        // K_ab = k g_a g_b^T, D_ab = c g_a g_b^T + friction w_a w_b (I - n n^T).
        for (int a = 0; a < p.count; ++a) {
            const int32_t fa = free_index[p.nodes[a]];
            if (fa < 0) continue;
            for (int b = a; b < p.count; ++b) {
                const int32_t fb = free_index[p.nodes[b]];
                if (fb < 0) continue;
                const double sliding = damping_scale * p.friction * p.weights[a] * p.weights[b];
                double block[9];
                for (int r = 0; r < 3; ++r)
                    for (int s = 0; s < 3; ++s)
                        block[3 * r + s] =
                            (stiffness_scale * p.stiffness + damping_scale * p.damping) * p.gradient[a][r] * p.gradient[b][s] +
                            sliding * ((r == s ? 1.0 : 0.0) - p.normal[r] * p.normal[s]);
                system.add_block(fa, fb, block, 1.0);
            }
        }
    });
}

double BodyContacts::energy(const double* x) const {
    double e = 0.0;
    evaluate(x, nullptr, [&](const ContactCandidate& c, const ContactPoint& p) { e += hunt_crossley_energy(*c.params, p.depth); });
    return e;
}

double BodyContacts::stable_step(const double* x, const double* v, const double* mass) const {
    // Each own node's row of k g g^T is at most k |g_a| sum_b |g_b| (Gershgorin), at the depth
    // the contact has now plus what the step may add. A candidate not touching yet is bounded
    // by a share of 1 (its weights sum to 1) on each node it may touch.
    double step = INFINITY;
    evaluate_candidates(x, v, [&](const ContactCandidate& c, const ContactPoint* point) {
        const bool face = c.kind == ContactCandidate::kFaceShape || c.kind == ContactCandidate::kFaceNode;
        const int count = point ? point->count : face ? 3 : 1;
        const NormalForce fn = hunt_crossley(*c.params, (point ? point->depth : 0.0) + anticipated_depth, 0.0);
        double row = 0.0;
        for (int b = 0; point && b < count; ++b) row += std::sqrt(dot(point->gradient[b], point->gradient[b]));
        for (int a = 0; a < count; ++a) {
            const int32_t node = point ? point->nodes[a] : face ? c.face[a] : c.node;
            if (!body_.is_free(node)) continue;
            const double share = point ? std::sqrt(dot(point->gradient[a], point->gradient[a])) * row : 1.0;
            step = std::min(step, damped_stable_step(share * fn.stiffness, share * fn.damping, mass[node]));
        }
    });
    return step;
}

int32_t BodyContacts::accumulate_reactions() {
    int32_t count = 0;
    evaluate(body_.x.data(), body_.v.data(), [&](const ContactCandidate& c, const ContactPoint& p) {
        if (c.kind == ContactCandidate::kFaceNode) return;
        ++count;
        if (!c.collider) return;
        sh_contact_state& s = c.collider->state;
        for (int a = 0; a < p.count; ++a) {
            double r[3], torque[3];
            const double reaction[3] = {-p.node_force[a][0], -p.node_force[a][1], -p.node_force[a][2]};
            sub(&body_.x[3 * static_cast<size_t>(p.nodes[a])], c.collider->pose.p, r);
            cross(r, reaction, torque);
            for (int k = 0; k < 3; ++k) {
                s.force[k] += reaction[k];
                s.torque[k] += torque[k];
            }
        }
        ++s.contact_count;
        s.max_depth = std::max(s.max_depth, p.depth);
        if (c.kind == ContactCandidate::kNodeShape) s.penetration_volume += p.depth * node_area_[static_cast<size_t>(c.node)];
    });
    return count;
}

}  // namespace sh
