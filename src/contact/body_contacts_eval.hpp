// BodyContacts' evaluation loops over its candidates, for the files that implement it (the
// potential, its tangent, friction and reactions): not for other users.
#pragma once

#include "contact/body_contacts.hpp"

namespace sh {

template <class Emit>
void BodyContacts::evaluate_friction(const double* v, Emit&& emit) const {
    if (!v || iterates_.size() != candidates_.size()) return;  // iterates_: implicit bodies only
    for (const ContactCandidate& c : candidates_) {
        ContactPoint point;
        if (lagged_friction(c, v, point)) emit(c, point);
    }
}

template <class Visit>
void BodyContacts::for_each_excess_candidate(const Group& group, Visit&& visit) const {
    for (int32_t i = group.begin; i < group.end; ++i) {
        const ContactCandidate& c = candidates_[static_cast<size_t>(i)];
        if (c.kind == ContactCandidate::kFaceShape) visit(c, 3);
        if (c.kind == ContactCandidate::kEdgeShape) visit(c, 2);
    }
}

template <class Emit, class AfterGroup>
void BodyContacts::evaluate_candidates(const double* x, const double* v, Emit&& emit, AfterGroup&& after_group) const {
    for (const Group& group : groups_) {
        mix_balls(group, x);
        for (int32_t i = group.begin; i < group.end; ++i) {
            const ContactCandidate& c = candidates_[static_cast<size_t>(i)];
            ContactPoint point;
            if (!touching(c, x, v, point)) {
                emit(c, static_cast<const ContactPoint*>(nullptr));
                continue;
            }
            emit(c, &point);
        }
        after_group(group);
    }
}

template <class Emit>
void BodyContacts::evaluate_candidates(const double* x, const double* v, Emit&& emit) const {
    evaluate_candidates(x, v, emit, [](const Group&) {});
}

template <class Emit>
void BodyContacts::evaluate(const double* x, const double* v, Emit&& emit) const {
    evaluate_candidates(x, v, [&](const ContactCandidate& c, const ContactPoint* point) {
        if (point) emit(c, *point);
    });
}

template <class Visit>
void BodyContacts::for_each_pair_candidate(const Body& other, const int32_t* own_index, Visit&& visit) const {
    for (const ContactCandidate& c : candidates_)
        if (c.kind == ContactCandidate::kNodeFace && c.other == &other && own_index[c.node] >= 0) visit(c);
}

template <class Emit>
void BodyContacts::drain_node_pushes(Emit&& emit) const {
    for (const int32_t node : scratch_.pushed_nodes) {
        double* push = &scratch_.node_push[3 * static_cast<size_t>(node)];
        emit(node, static_cast<const double*>(push));
        push[0] = push[1] = push[2] = 0.0;
    }
    scratch_.pushed_nodes.clear();
}

template <class OnPoint, class OnNode>
void BodyContacts::evaluate_with_node_pushes(const double* x, const double* v, bool pushes, OnPoint&& on_point,
                                             OnNode&& on_node) const {
    Collider* pushing = nullptr;
    const auto drain = [&]() {
        drain_node_pushes([&](int32_t node, const double* push) { on_node(*pushing, node, push); });
    };
    evaluate(x, v, [&](const ContactCandidate& c, const ContactPoint& p) {
        on_point(c, p);
        if (!pushes || !c.collider) return;
        if (c.collider != pushing) {  // candidates come collider by collider
            if (pushing) drain();
            pushing = c.collider;
        }
        add_node_push(p);
    });
    if (pushing) drain();
}

}  // namespace sh
