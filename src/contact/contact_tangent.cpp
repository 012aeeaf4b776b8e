// BodyContacts' tangent: the contact potential's positive semi-definite Hessian and
// friction's -dF/dv, within a body and across a pair of bodies in contact.
#include "contact/body_contacts.hpp"

#include "contact/body_contacts_eval.hpp"
#include "core/clock.hpp"
#include "core/vec3.hpp"
#include "linalg/sparse_system.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

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
          normal_scale_(normal_tangent_scale(p, stiffness_scale, damping_scale)),
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
    const ScopedTimer timer(scratch_.evaluation_seconds);
    evaluate_candidates(
        x, v,
        [&](const ContactCandidate& c, const ContactPoint* p) {
            if (p) add_point_tangent(*p, PointTangent(*p, *c.params, stiffness_scale, damping_scale), free_index, system);
        },
        [&](const Group& group) {
            if (stiffness_scale != 0.0) add_ball_mix_tangent(group, x, stiffness_scale, free_index, system);
        });
    evaluate_friction(v, [&](const ContactCandidate& c, const ContactPoint& p) {
        const PointTangent tangent(p, *c.params, stiffness_scale, damping_scale, friction_chord(c, p));
        add_point_tangent(p, tangent, free_index, system);
    });
}

void BodyContacts::add_tangent_links(vec<int32_t>& pairs) const {
    vec<int32_t> nodes;
    for (const Group& group : groups_) {
        if (!ball_mix_collider(group)) continue;
        nodes.clear();
        for_each_excess_candidate(group, [&](const ContactCandidate& c, int count) {
            nodes.insert(nodes.end(), c.face, c.face + count);
        });
        std::sort(nodes.begin(), nodes.end());
        nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
        if (nodes.size() > kMaxLinkedNodes) continue;
        for (size_t a = 0; a < nodes.size(); ++a)
            for (size_t b = a + 1; b < nodes.size(); ++b) {
                pairs.push_back(nodes[a]);
                pairs.push_back(nodes[b]);
            }
    }
}

void BodyContacts::add_ball_mix_tangent(const Group& group, const double* x, double stiffness_scale,
                                        const int32_t* free_index, SparseSystem& system) const {
    const Collider* collider = ball_mix_collider(group);
    if (!collider) return;
    BallMix& mix = scratch_.balls;
    mix.begin_tangent();
    for_each_excess_candidate(group, [&](const ContactCandidate& c, int count) {
        mix.add_tangent_term(*collider, step_law(c), x, c.face, count, c.excess_weight);
    });
    // The pattern holds the blocks between the nodes of the collider's candidates
    // (add_tangent_links). A block it lacks (more candidate nodes than kMaxLinkedNodes) goes
    // onto both nodes' own blocks as its norm times the identity, which bounds it from above
    // but slows Newton to a linear rate: the smooth maximum couples the nodes under a lying
    // capsule about as strongly as each node's own stiffness.
    mix.tangent([&](int32_t a, int32_t b, const double* block) {
        const int32_t fa = free_index[a], fb = free_index[b];
        if (fa < 0 || fb < 0) return;
        if (fa == fb || system.has_block(fa, fb)) {
            system.add_block(fa, fb, block, stiffness_scale);
            return;
        }
        const double norm = block_norm(block, 3, 1);
        const double bound[9] = {norm, 0.0, 0.0, 0.0, norm, 0.0, 0.0, 0.0, norm};
        system.add_block(fa, fa, bound, stiffness_scale);
        system.add_block(fb, fb, bound, stiffness_scale);
    });
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
    const ScopedTimer timer(scratch_.evaluation_seconds);
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

}  // namespace sh
