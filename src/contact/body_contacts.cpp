// BodyContacts' contact potential: the surface it covers, and the candidates' forces,
// energy and stable step at any state the integrators try.
#include "contact/body_contacts.hpp"

#include "collision/closest_point.hpp"
#include "contact/body_contacts_eval.hpp"
#include "contact/hunt_crossley.hpp"
#include "core/clock.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

BodyContacts::BodyContacts(const Body& body, bool implicit, ContactScratch& scratch)
    : body_(body), implicit_(implicit), scratch_(scratch) {
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
    if (scratch_.node_push.size() < 3 * n) scratch_.node_push.resize(3 * n, 0.0);  // the pushes already there are 0
}

void BodyContacts::clear() {
    candidates_.clear();
    groups_.clear();
}

StepLaw BodyContacts::step_law(const ContactCandidate& c) const {
    return hunt_crossley_step_law(*c.params, c.start_depth, step_);
}

const Collider* BodyContacts::ball_mix_collider(const Group& group) const {
    if (group.end <= group.begin) return nullptr;
    const Collider* collider = candidates_[static_cast<size_t>(group.begin)].collider;
    return collider && collider->shape.mixes_balls() ? collider : nullptr;
}

void BodyContacts::mix_balls(const Group& group, const double* x) const {
    const Collider* collider = ball_mix_collider(group);
    if (!collider) return;
    scratch_.balls.reserve(collider->shape.ball_count());
    scratch_.balls.sum(*collider, [&](auto&& add) {
        for_each_excess_candidate(group, [&](const ContactCandidate& c, int count) {
            add(step_law(c), x, c.face, count, c.excess_weight);
        });
    });
}

bool BodyContacts::touching(const ContactCandidate& c, const double* x, const double* v, ContactPoint& out) const {
    const sh_contact_params& p = *c.params;
    double vrel[3] = {0.0, 0.0, 0.0};  // velocity of the node side relative to the other side
    out.law_scale = 1.0;
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
                                      c.excess_weight, &scratch_.balls, out))
                return false;
            if (!v || implicit_step()) return true;
            velocity_against_collider(*c.collider, out, v, vrel);
            apply_excess_damping(p, vrel, out);  // friction per node (add_forces)
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
                set_contact_nodes(1, &c.node, &one, out);
                for (int k = 0; k < 3; ++k) out.other_weights[k] = -w[k];
            } else {
                const double far_side[3] = {-w[0], -w[1], -w[2]};
                set_contact_nodes(3, c.face, far_side, out);
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
    // proportional to the normal force there; a collider's per node (add_forces).
    if (v && !c.collider && out.normal_force > 0.0 && p.static_friction > 0.0) apply_friction(p, out.normal_force, out);
    return true;
}

void BodyContacts::add_forces(const double* x, const double* v, double* f) const {
    const ScopedTimer timer(scratch_.evaluation_seconds);
    // Explicit bodies feel their friction in end_explicit_step, not here: against another
    // body per contact, against a collider per node (node_friction_point), recorded at the
    // (sub)step's first evaluation.
    const bool explicit_friction = !implicit_step();
    const bool record = scratch_.recording && v;
    if (record) scratch_.friction_records.clear();
    scratch_.recording = false;
    const auto add = [&](const ContactPoint& p, bool normal_only) {
        for (int a = 0; a < p.count; ++a)
            for (int k = 0; k < 3; ++k)
                f[3 * static_cast<size_t>(p.nodes[a]) + k] += normal_only ? p.normal_force * p.gradient[a][k] : p.node_force[a][k];
    };
    const auto add_point = [&](const ContactCandidate& c, const ContactPoint& p) {
        const bool friction = explicit_friction && p.friction_normal > 0.0;
        add(p, friction);
        if (friction && record) scratch_.friction_records.push_back(friction_record(p, *c.params, v));
    };
    const auto record_node = [&](const Collider& collider, int32_t node, const double* push) {
        if (collider.params.static_friction > 0.0 && norm3(push) > 0.0)
            scratch_.friction_records.push_back(friction_record(node_friction_point(collider, node, push, x, v), collider.params, v));
    };
    evaluate_with_node_pushes(x, v, explicit_friction && record, add_point, record_node);
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
        for (int a = 0; a < count; ++a) {
            const int32_t node = point ? point->nodes[a] : face ? c.face[a] : c.node;
            if (!body_.is_free(node)) continue;
            const double share = point ? stiffness_share(*point, a) : 1.0;
            const double mixed = point ? mixed_stiffness_bound(*point, a) : 0.0;  // a capsule's mix
            step = std::min(step, damped_stable_step(share * fn.stiffness + mixed, share * fn.damping, mass[node]));
        }
    });
    return step;
}

}  // namespace sh
