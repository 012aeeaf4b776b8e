// BodyContacts' broad phase: the surface hierarchy, and the candidates a step may meet
// against colliders and other bodies.
#include "contact/body_contacts.hpp"

#include "collision/closest_point.hpp"
#include "contact/body_contacts_eval.hpp"
#include "contact/hunt_crossley.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

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
    const bool plane = collider.shape.is_half_space();
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
    scratch_.keys.resize(static_cast<size_t>(count));
    mix_balls(group, body_.x.data());
    for (int32_t i = 0; i < count; ++i) {
        ContactPoint point;
        const ContactCandidate& c = candidates_[static_cast<size_t>(group.begin + i)];
        scratch_.keys[static_cast<size_t>(i)] = touching(c, body_.x.data(), nullptr, point) ? point.depth : -1.0;
    }
    // Order the group by depth, deepest first, and keep the first `capacity`.
    vec<int32_t> order(static_cast<size_t>(count));
    for (int32_t i = 0; i < count; ++i) order[static_cast<size_t>(i)] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](int32_t p, int32_t q) { return scratch_.keys[static_cast<size_t>(p)] > scratch_.keys[static_cast<size_t>(q)]; });
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

}  // namespace sh
