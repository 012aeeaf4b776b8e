// BodyContacts' reactions: what the body's contacts do to the colliders (force, torque,
// count, depth), and which nodes they hold.
#include "contact/body_contacts.hpp"

#include "contact/body_contacts_eval.hpp"
#include "core/vec3.hpp"

#include <algorithm>

namespace sh {
namespace {

// Adds the reaction of contact p (its node forces at positions x) to collider's force and torque.
void add_reaction(const double* x, Collider& collider, const ContactPoint& p) {
    sh_contact_state& s = collider.state;
    for (int a = 0; a < p.count; ++a) {
        double r[3], torque[3];
        const double reaction[3] = {-p.node_force[a][0], -p.node_force[a][1], -p.node_force[a][2]};
        sub3(at(x, p.nodes[a]), collider.pose.p, r);
        cross3(r, reaction, torque);
        for (int k = 0; k < 3; ++k) {
            s.force[k] += reaction[k];
            s.torque[k] += torque[k];
        }
    }
}

}  // namespace

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
        add_reaction(body_.x.data(), *c.collider, p);
        if (!(p.depth > 0.0)) return;  // friction kept through a step on a contact that came off
        if (!excess) ++s.contact_count;
        s.max_depth = std::max(s.max_depth, p.depth);
        if (c.kind == ContactCandidate::kNodeShape) s.penetration_volume += p.depth * node_area_[static_cast<size_t>(c.node)];
    };
    // Explicit bodies' friction against a collider acts per node (add_forces): its reaction is
    // Coulomb's law on each node's net push at the body's state. Implicit bodies' is their
    // lagged friction (evaluate_friction).
    const double* x = body_.x.data();
    const auto node_friction = [&](Collider& collider, int32_t node, const double* push) {
        if (!(collider.params.static_friction > 0.0 && norm3(push) > 0.0)) return;
        ContactPoint p = node_friction_point(collider, node, push, x, body_.v.data());
        apply_friction(collider.params, p.friction_normal, p);
        add_reaction(x, collider, p);
    };
    evaluate_with_node_pushes(x, body_.v.data(), !implicit_step(), accumulate, node_friction);
    close_regions();
    region_collider = nullptr;
    evaluate_friction(body_.v.data(), accumulate);
    return count;
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

}  // namespace sh
