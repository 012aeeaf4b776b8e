// The haptic side of the Volumetric Buffer Model: take the newest buffer, step it explicitly
// to the device pose in the context's fixed memory, and render the tool's force. Nothing here
// allocates, locks, logs or throws.
#include "contact/ball_terms.hpp"
#include "contact/hunt_crossley.hpp"
#include "contact/shape_contact.hpp"
#include "core/vec3.hpp"
#include "haptic/haptic_context.hpp"
#include "material/material_table.hpp"
#include "model/fem_kernel.hpp"
#include "solver/substeps.hpp"

#include <Eigen/LU>
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace sh {
namespace {

// Fraction of the critical step taken per sub-step.
constexpr double kSafety = 0.9;

// A step longer than this is not a haptic step (s).
constexpr double kLongestStep = 1.0;

// The buffer's element rotations are settled when a step's last update turns none by more
// than 1e-4 rad: R is then about 1e-8 from the polar factor, a stress error of about 2e-8 mu,
// far below the force's resolution, and one update per step usually does it (the elements
// turn by about 1e-4 rad per tick while pressed; the default's 1e-6 takes two).
constexpr double kBufferRotationSettled2 = 1e-8;

// Where the tool may touch the buffer this pass: its bounding box, and for a sphere the
// sphere itself (its one ball is the shape: a node or feature beyond it has no term), which
// culls about half of the surface features a box lets through.
class ToolReach {
public:
    explicit ToolReach(const Collider& tool) {
        tool.shape.bounds(tool.pose, 0.0, lo_, hi_);
        sphere_ = tool.shape.ball_is_shape();
        if (!sphere_) return;
        const BallRow& row = tool.balls();
        for (int k = 0; k < 3; ++k) centre_[k] = row.first[k];
        radius2_ = tool.shape.ball_radius() * tool.shape.ball_radius();
    }
    /// False if no point of the count nodes' box can be in the tool.
    bool may_touch(const double* const points[3], int count) const {
        const FeatureBox box(points, count);
        for (int k = 0; k < 3; ++k)
            if (box.hi[k] < lo_[k] || box.lo[k] > hi_[k]) return false;
        return !sphere_ || box.distance2(centre_) < radius2_;
    }

private:
    double lo_[3], hi_[3], centre_[3] = {0.0, 0.0, 0.0}, radius2_ = 0.0;
    bool sphere_ = false;
};

void add_reaction(const ContactPoint& p, const double* x, const double tool_position[3], double force[3],
                  double torque[3]) {
    for (int a = 0; a < p.count; ++a) {
        double r[3], t[3];
        const double reaction[3] = {-p.node_force[a][0], -p.node_force[a][1], -p.node_force[a][2]};
        sub3(at(x, p.nodes[a]), tool_position, r);
        cross3(r, reaction, t);
        for (int k = 0; k < 3; ++k) {
            force[k] += reaction[k];
            torque[k] += t[k];
        }
    }
}

// Calls visit(nodes, count, size) for each term of the contact potential (shape_contact.hpp)
// over buffer b's surface at x that the tool may reach: per surface node its depth's term
// (count 1), per edge (count 2) and per triangle (count 3) their excess terms with the
// feature's size.
template <class Visit>
void visit_terms_in_reach(const Buffer& b, const double* x, const ToolReach& reach, Visit&& visit) {
    const auto near = [&](const int32_t* nodes, int count) {
        const double* const points[3] = {at(x, nodes[0]), at(x, nodes[count > 1 ? 1 : 0]), at(x, nodes[count - 1])};
        return reach.may_touch(points, count);
    };
    for (int32_t s = 0; s < b.surface_node_count; ++s)
        if (near(&b.surface_nodes[s], 1)) visit(&b.surface_nodes[s], 1, 0.0);
    for (int32_t e = 0; e < b.edge_count; ++e)
        if (near(b.edges + 2 * e, 2)) visit(b.edges + 2 * e, 2, b.edge_size[e]);
    for (int32_t t = 0; t < b.triangle_count; ++t)
        if (near(b.triangles + 3 * t, 3)) visit(b.triangles + 3 * t, 3, b.triangle_size[t]);
}

// The tool's term of visit_terms_in_reach at rest (the buffer is explicit: the depth rate's
// damping comes after, from the velocities).
bool term_contact(const Collider& tool, const double* x, const int32_t* nodes, int count, double size,
                  const BallMix& balls, ContactPoint& out) {
    if (count == 1) return node_shape_contact(tool, x, nodes[0], out);
    return excess_shape_contact(tool, hunt_crossley_step_law(tool.params, 0.0, 0.0), x, nodes, count,
                                excess_weight(tool, size), &balls, out);
}

// How far past the full model's step (in steps) the boundary keeps its end velocity, when the
// next buffer is late: the haptic clock and the full model's meet every 16 or 17 ticks at
// 1 kHz and 60 Hz, so the boundary must not stop for the odd tick; a late full model is
// reported stale (sh_haptic_def.stale_after) and the boundary waits for it.
constexpr double kOverrun = 0.25;

// Node i's mean velocity across b's full-model step (0 without a step). An explicit body's
// velocity at the end of its last sub-step rings with its fastest modes; the mean is the
// motion the boundary follows (for implicit Euler it is the end velocity).
void mean_velocity(const Buffer& b, int32_t i, double out[3]) {
    const double rate = b.period > 0.0 ? 1.0 / b.period : 0.0;
    for (int k = 0; k < 3; ++k) out[k] = rate * (at(b.x_end, i)[k] - at(b.x_start, i)[k]);
}

}  // namespace

void HapticContext::load_state(const Buffer& b, bool keep) {
    // With keep, nodes the old buffer had keep the haptic side's state (a boundary node's path
    // starts from it); the others start from the full model at the start of its step.
    const int other = 1 - current_;
    const bool same_body = keep && b.body != 0 && b.body == state_body_;
    int32_t j = 0;
    for (int32_t i = 0; i < b.node_count; ++i) {
        const int32_t id = b.node_id[i];
        while (same_body && j < node_count_ && id_[current_][j] < id) ++j;
        const bool kept = same_body && j < node_count_ && id_[current_][j] == id;
        double mean[3];
        mean_velocity(b, i, mean);
        const double* xs = kept ? at(x_[current_], j) : at(b.x_start, i);
        const double* vs = kept ? at(v_[current_], j) : mean;
        for (int k = 0; k < 3; ++k) {
            at(x_[other], i)[k] = xs[k];
            at(v_[other], i)[k] = vs[k];
            at(path_x_, i)[k] = xs[k];
            at(path_v_, i)[k] = vs[k];
        }
        id_[other][i] = id;
    }
    current_ = other;
    node_count_ = b.node_count;
    state_body_ = b.body;
    rotations_from_buffer_ = true;  // the elements' rotations start again from the buffer's too
}

void HapticContext::follow_boundary(const Buffer& b, double t, double* x, double* v) const {
    // The full model drives the boundary nodes across its step: each follows the cubic Hermite
    // path from its state at the hand-over (path_x_, path_v_: the haptic side's, so that
    // nothing jumps when a buffer replaces another or a free node becomes a boundary one) to
    // the full model's end of step; past the step, on at the end velocity for a while; with
    // no step to follow (a jump), it stays at the end.
    const double period = b.period;
    const double s = period > 0.0 ? std::min(t / period, 1.0 + kOverrun) : 1.0;
    double p0 = 0.0, m0 = 0.0, p1 = 1.0, m1 = 0.0;   // weights of x0, T v0, x1, T v1 in x
    double dp0 = 0.0, dm0 = 0.0, dp1 = 0.0, dm1 = 0.0;  // and of their rate (1/T)
    if (period > 0.0 && s <= 1.0) {
        const double s2 = s * s, s3 = s2 * s;
        p0 = 2 * s3 - 3 * s2 + 1, m0 = s3 - 2 * s2 + s, p1 = -2 * s3 + 3 * s2, m1 = s3 - s2;
        dp0 = 6 * s2 - 6 * s, dm0 = 3 * s2 - 4 * s + 1, dp1 = -dp0, dm1 = 3 * s2 - 2 * s;
    } else if (period > 0.0) {
        m1 = s - 1.0;
        dm1 = s < 1.0 + kOverrun ? 1.0 : 0.0;
    }
    const double rate = period > 0.0 ? 1.0 / period : 0.0;
    for (int32_t i = 0; i < b.node_count; ++i) {
        if (b.inverse_mass[i] > 0.0) continue;
        double v1[3];
        mean_velocity(b, i, v1);
        const double *x0 = at(path_x_, i), *x1 = at(b.x_end, i), *v0 = at(path_v_, i);
        for (int k = 0; k < 3; ++k) {
            at(x, i)[k] = p0 * x0[k] + p1 * x1[k] + period * (m0 * v0[k] + m1 * v1[k]);
            at(v, i)[k] = rate * (dp0 * x0[k] + dp1 * x1[k]) + dm0 * v0[k] + dm1 * v1[k];
        }
    }
}

void HapticContext::hold_nodes(const Buffer& b, double* x, double* v) {
    // A physical blade drags the nodes it holds: they move with the device's tool, and the
    // work it does against the material's pull counts towards the break, as the full model
    // counts it (cut/breaking.hpp). Once the work pays for the crack, the haptic side lets
    // them go: the device feels the drop now, the full model breaks the material at its
    // next step, and until a buffer without the hold arrives its nodes follow the full model.
    if (hold_broken(b)) return;
    for (int32_t h = 0; h < b.held_count; ++h) {
        const int32_t i = b.held[h];
        const double* offset = &b.held_offset[3 * h];
        tool_.pose.to_world(offset, at(x, i));
        tool_.point_velocity(at(x, i), at(v, i));
        if (!have_held_pose_) continue;
        double from[3], moved[3];
        held_pose_.to_world(offset, from);
        sub3(at(x, i), from, moved);
        held_work_ += std::max(0.0, -dot3(&held_pull_[3 * h], moved));
    }
    held_pose_ = tool_.pose;
    have_held_pose_ = true;
    if (b.held_needed > 0.0 && held_work_ >= b.held_needed) broken_hold_ = b.held_serial, broken_body_ = b.body;
}

void HapticContext::add_held_reaction(const Buffer& b, const double* x, double force[3], double torque[3]) {
    // The material pulls on the held nodes (force_ holds their weight and elastic force): the
    // blade holding them feels that pull, and the full model's pull on those it holds outside
    // the buffer.
    if (hold_broken(b)) return;
    for (int32_t h = 0; h < b.held_count; ++h) {
        const int32_t i = b.held[h];
        double* pull = &held_pull_[3 * h];
        double arm[3], t[3];
        for (int k = 0; k < 3; ++k) pull[k] = at(force_, i)[k] - b.mass[i] * b.gravity[k];
        sub3(at(x, i), tool_.pose.p, arm);
        cross3(arm, pull, t);
        for (int k = 0; k < 3; ++k) force[k] += pull[k], torque[k] += t[k];
    }
    for (int k = 0; k < 3; ++k) force[k] += b.held_outside_force[k], torque[k] += b.held_outside_torque[k];
}

void HapticContext::adopt(const Buffer& b) {
    load_state(b, b.period > 0.0);
    held_work_ = b.held_work;  // the full model's count up to the buffer's step
    have_held_pose_ = false;
    std::memset(held_pull_, 0, 3 * static_cast<size_t>(b.held_count) * sizeof(double));
    age_ = 0.0;
    for (int k = 0; k < SH_WARN_COUNT; ++k)
        if (b.warnings & (1u << k)) warnings_[k].fetch_add(1, std::memory_order_relaxed);
}

double HapticContext::substep_limit(const Buffer& b) const {
    // The elastic forces are explicit: the buffer's critical step, with room for the implicit
    // contact's share (with the contact's stiffness taken implicitly, symplectic Euler is
    // stable up to sqrt(3) instead of 2 over the elastic frequency). The contact does not
    // limit it: integrate() takes it implicitly.
    const double omega_fem = b.dt_stable > 0.0 && std::isfinite(b.dt_stable) ? 2.0 / b.dt_stable : 0.0;
    return omega_fem > 0.0 ? kSafety * std::sqrt(3.0) / omega_fem : INFINITY;
}

void HapticContext::integrate(const Buffer& b, double h, double* x, double* v, double force[3],
                               double torque[3]) const {
    // Symplectic Euler with the mass damping implicit, and each contacted node's contact
    // stiffness K and damping C (contact_tangent_: its terms' tangents, lumped onto it)
    // implicit, linearised: (m + h^2 K + h C) v' = m v + h f + h C v. At rest (v = 0, f = 0)
    // it stays at rest: the equilibrium, and the force there, are the explicit step's; and a
    // stiff tool needs no more sub-steps than the elements do. The tool feels the contact
    // force the node received, f_c - h K v' - C (v' - v), so that what the tool gives the
    // buffer is what the device feels (momentum is conserved between the two); but for the
    // part of K that bounds a mixed term (a capsule's smooth maximum) isotropically: that is a
    // bound for stability, far stiffer than the mix along the tool's motion (where its balls
    // deepen together it has no curvature), and felt it would drag the device (a capsule
    // pressed at 1.5 cm/s: 1.24 N rendered where its contact gave 1.62 N) and step where its
    // push hands over between balls. The nodes keep it: the buffer is damped by it a little
    // more than the device feels.
    const double damping = 1.0 / (1.0 + h * b.damping_mass);
    for (int32_t i = 0; i < b.node_count; ++i) {
        const double w = b.inverse_mass[i];
        if (w == 0.0) continue;
        double* vi = at(v, i);
        if (in_contact_[i]) {
            const double* tangent = contact_tangent_ + kTangentStride * static_cast<size_t>(i);
            const Eigen::Map<const Eigen::Matrix3d> stiffness(tangent);
            const Eigen::Map<const Eigen::Matrix3d> damping_c(tangent + 9);
            const Eigen::Map<const Eigen::Vector3d> v0(vi), f(at(force_, i));
            const Eigen::Matrix3d a = Eigen::Matrix3d::Identity() + w * (h * h * stiffness + h * damping_c);
            const Eigen::Vector3d v1 = a.inverse() * (v0 + w * h * (f + damping_c * v0));  // SPD, near I: cofactors
            const Eigen::Vector3d received = -(h * (stiffness * v1 - tangent[18] * v1) + damping_c * (v1 - v0));
            double arm[3], t[3];
            sub3(at(x, i), tool_.pose.p, arm);
            cross3(arm, received.data(), t);
            for (int k = 0; k < 3; ++k) {
                force[k] -= received[k];
                torque[k] -= t[k];
                vi[k] = v1[k];
            }
        } else {
            for (int k = 0; k < 3; ++k) vi[k] += h * w * at(force_, i)[k];
        }
        for (int k = 0; k < 3; ++k) {
            vi[k] *= damping;
            at(x, i)[k] += h * vi[k];
        }
    }
}

void HapticContext::add_elastic_forces(const Buffer& b, const double* x, const double* v) {
    const double* damped_v = b.damping_stiffness > 0.0 ? v : nullptr;
    const Mat3L* near = rotations_from_buffer_ ? b.rotations : rotation_;
    for_each_material([&](auto material, int model) {
        const int32_t begin = b.block_begin[model], end = b.block_begin[model + 1];
        add_fem_forces<decltype(material)>(b.blocks + begin, static_cast<size_t>(end - begin), x, damped_v,
                                           b.damping_stiffness, force_,
                                           KeptRotations{near + begin, rotation_ + begin, kBufferRotationSettled2});
    });
    rotations_from_buffer_ = false;
}

void HapticContext::clear_contact() {
    // Only the nodes the last sub-step touched hold contact data.
    for (int32_t j = 0; j < contacted_count_; ++j) {
        const int32_t i = contacted_[j];
        in_contact_[i] = 0;
        std::memset(at(contact_, i), 0, 3 * sizeof(double));
    }
    contacted_count_ = 0;
}

void HapticContext::add_contact_tangent(int32_t node, const double direction[3], double stiffness, double damping) {
    double* tangent = contact_tangent_ + kTangentStride * static_cast<size_t>(node);
    if (!in_contact_[node]) {
        in_contact_[node] = 1;
        contacted_[contacted_count_++] = node;
        std::memset(tangent, 0, kTangentStride * sizeof(double));
    }
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            const double outer = direction[r] * direction[c];
            tangent[3 * c + r] += stiffness * outer;
            tangent[9 + 3 * c + r] += damping * outer;
        }
}

void HapticContext::add_mixed_bound(int32_t node, double bound) {
    for (int k = 0; k < 3; ++k) {
        const double axis[3] = {k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0};
        add_contact_tangent(node, axis, bound, 0.0);
    }
    contact_tangent_[kTangentStride * static_cast<size_t>(node) + 18] += bound;
}

void HapticContext::add_contact_forces(const Buffer& b, const double* x, const double* v, double* f, double force[3],
                                       double torque[3], bool& contact) {
    const ToolReach reach(tool_);
    const sh_contact_params& law = tool_.params;
    clear_contact();
    if (tool_.shape.mixes_balls()) {  // their mix first (BallMix)
        balls_.sum(tool_, [&](auto&& add) {
            visit_terms_in_reach(b, x, reach, [&](const int32_t* nodes, int count, double size) {
                if (count > 1) add(hunt_crossley_step_law(law, 0.0, 0.0), x, nodes, count, excess_weight(tool_, size));
            });
        });
    }
    visit_terms_in_reach(b, x, reach, [&](const int32_t* nodes, int count, double size) {
        ContactPoint p;
        if (!term_contact(tool_, x, nodes, count, size, balls_, p)) return;
        double vrel[3];
        velocity_against_collider(tool_, p, v, vrel);
        if (p.count == 1) apply_normal_law(law, vrel, p);
        else apply_excess_damping(law, vrel, p);
        // The term's normal tangent (the full model's, contact_tangent.cpp), k g g^T with g its
        // gradients, bounded by a block diagonal: node a gets k |g_a| (sum_b |g_b|) (its
        // stiffness_share) along g_a (Cauchy-Schwarz), for integrate(). A term mixed over a
        // tool's balls gives node a its mixed_stiffness_bound along every axis.
        const double stiffness = normal_tangent_scale(p, 1.0, 0.0), damping = normal_tangent_scale(p, 0.0, 1.0);
        for (int a = 0; a < p.count; ++a) {
            const double length = norm3(p.gradient[a]), share = stiffness_share(p, a);
            double direction[3] = {0.0, 0.0, 0.0};
            if (length > 0.0)
                for (int k = 0; k < 3; ++k) direction[k] = p.gradient[a][k] / length;
            add_contact_tangent(p.nodes[a], direction, stiffness * share, damping * share);
            const double mixed = mixed_stiffness_bound(p, a);
            if (mixed > 0.0) add_mixed_bound(p.nodes[a], mixed);
            for (int k = 0; k < 3; ++k) {
                at(f, p.nodes[a])[k] += p.node_force[a][k];
                at(contact_, p.nodes[a])[k] += p.node_force[a][k];
            }
        }
        add_reaction(p, x, tool_.pose.p, force, torque);
        contact = true;
    });
    record_node_friction(b, x, v);
}

void HapticContext::record_node_friction(const Buffer& b, const double* x, const double* v) {
    // Friction per surface node, against the net push of all the terms on it (see
    // node_friction_point).
    friction_count_ = 0;
    const sh_contact_params& law = tool_.params;
    if (!(law.static_friction > 0.0)) return;
    for (int32_t s = 0; s < b.surface_node_count; ++s) {
        const int32_t node = b.surface_nodes[s];
        const double* push = at(contact_, node);
        const double fn = norm3(push);
        if (!(fn > 0.0) || b.inverse_mass[node] == 0.0) continue;
        if (friction_count_ == friction_capacity_) {
            step_warnings_ |= 1u << SH_WARN_CAPACITY;
            return;
        }
        friction_[friction_count_++] = friction_record(node_friction_point(tool_, node, push, x, v), law, v);
    }
}

void HapticContext::apply_friction_impulses(const Buffer& b, double h, double* x, double* v, double force[3],
                                            double torque[3]) {
    for (int32_t i = 0; i < friction_count_; ++i) {
        const FrictionRecord& r = friction_[i];
        double impulse[3], reaction[3], arm[3], t[3];
        apply_implicit_friction(r, b.inverse_mass, h, x, v, impulse);
        for (int k = 0; k < 3; ++k) reaction[k] = -impulse[k] / h;
        sub3(r.point, tool_.pose.p, arm);
        cross3(arm, reaction, t);
        for (int k = 0; k < 3; ++k) {
            force[k] += reaction[k];
            torque[k] += t[k];
        }
    }
}

bool HapticContext::step_buffer(const Buffer& b, double dt, double force[3], double torque[3], int32_t& substeps,
                                bool& contact) {
    const size_t n3 = 3 * static_cast<size_t>(b.node_count);
    double* x = x_[current_];
    double* v = v_[current_];
    std::memcpy(saved_x_, x, n3 * sizeof(double));
    std::memcpy(saved_v_, v, n3 * sizeof(double));
    tool_.pose = tool_.start;
    const double limit = substep_limit(b);
    // A limit that is not positive (NaN too: a runaway state) needs the cap.
    const SubstepCount count = substep_count(dt, limit > 0.0 ? limit : 0.0, kMaxHapticSubsteps);
    substeps = count.count;
    // More than the cap: the step goes ahead with it, warned, and the runaway check decides.
    if (count.clamped) step_warnings_ |= 1u << SH_WARN_SUBSTEPPED;
    const double h = dt / substeps;
    const double t0 = age_ - dt;  // age_ already counts this step
    const Pose start = tool_.start;
    for (int32_t s = 0; s < substeps; ++s) {
        tool_.pose = interpolate(start, tool_.target, static_cast<double>(s + 1) / substeps);
        follow_boundary(b, t0 + (s + 1) * h, x, v);
        hold_nodes(b, x, v);
        for (int32_t i = 0; i < b.node_count; ++i)
            for (int k = 0; k < 3; ++k) at(force_, i)[k] = b.mass[i] * b.gravity[k];
        add_elastic_forces(b, x, v);
        double f_tool[3] = {0.0, 0.0, 0.0}, t_tool[3] = {0.0, 0.0, 0.0};
        add_held_reaction(b, x, f_tool, t_tool);
        bool touching = false;
        add_contact_forces(b, x, v, force_, f_tool, t_tool, touching);
        contact = touching;
        integrate(b, h, x, v, f_tool, t_tool);
        apply_friction_impulses(b, h, x, v, f_tool, t_tool);
        for (int k = 0; k < 3; ++k) {  // the step's mean wrench
            force[k] += f_tool[k] / substeps;
            torque[k] += t_tool[k] / substeps;
        }
    }
    // Finite and not running away, or back to the state before the step.
    const double fastest = b.runaway_speed * b.runaway_speed;
    bool sane = std::isfinite(force[0] + force[1] + force[2] + torque[0] + torque[1] + torque[2]);
    for (int32_t i = 0; i < b.node_count && sane; ++i)
        sane = finite3(at(x, i)) && dot3(at(v, i), at(v, i)) <= fastest;
    if (sane) return true;
    std::memcpy(x, saved_x_, n3 * sizeof(double));
    std::memcpy(v, saved_v_, n3 * sizeof(double));
    for (int k = 0; k < 3; ++k) force[k] = torque[k] = 0.0;
    return false;
}

bool HapticContext::proxy_force(const Buffer& b, double force[3], double torque[3]) const {
    // The tool's deepest point behind the last known surface plane.
    const double* n = b.proxy_normal;
    const double inward[3] = {-n[0], -n[1], -n[2]};
    double s[3], d[3];
    tool_.shape.support(tool_.target, inward, s);
    sub3(b.proxy_point, s, d);
    const double depth = dot3(d, n);
    // Deeper than the tool's inner radius, the tool has passed through the surface, as the
    // full model lets it (its contact potential holds a tool only up to that depth): the
    // device follows the full model instead of a plane the tool is past.
    if (!(depth <= tool_.shape.inner_radius())) return false;
    const NormalForce fn = hunt_crossley(tool_.params, depth, -dot3(tool_.velocity, n));
    if (!(fn.force > 0.0)) return false;
    double r[3];
    sub3(s, tool_.target.p, r);
    for (int k = 0; k < 3; ++k) force[k] = fn.force * n[k];
    cross3(r, force, torque);
    return true;
}

sh_status HapticContext::step(const double position[3], const double orientation[4], double dt,
                              sh_haptic_output& out) noexcept {
    sh_status status = SH_OK;
    uint32_t faults = 0;
    step_warnings_ = 0;
    const bool dt_ok = std::isfinite(dt) && dt > 0.0 && dt <= kLongestStep;
    if (!dt_ok) {
        faults |= SH_HAPTIC_FAULT_DT;
        status = SH_ERR_INVALID_ARGUMENT;
    }
    const double step_dt = dt_ok ? dt : def_.dt;  // what the force ramps move by
    Pose pose = pose_;
    const bool pose_ok = read_pose(position, orientation, pose);
    if (pose_ok) {
        DevicePose& d = device_[device_index_.back()];
        d.pose = pose;
        d.valid = true;
        device_index_.publish();
    } else {
        faults |= SH_HAPTIC_FAULT_POSE;
        status = SH_ERR_INVALID_ARGUMENT;
    }
    if (buffer_index_.take()) adopt(buffers_[buffer_index_.front()]);
    const Buffer& b = buffers_[buffer_index_.front()];
    if (detached_.load(std::memory_order_acquire) || !b.tool_alive) faults |= SH_HAPTIC_FAULT_NO_TOOL;
    if (dt_ok) age_ += dt;

    double raw_force[3] = {0.0, 0.0, 0.0}, raw_torque[3] = {0.0, 0.0, 0.0};
    bool contact = false;
    int32_t substeps = 0;
    if (dt_ok && pose_ok && !(faults & SH_HAPTIC_FAULT_NO_TOOL)) {
        tool_.start = have_pose_ ? pose_ : pose;
        tool_.target = pose;
        tool_.velocity_given = false;
        tool_.begin_step(dt);
        if (b.node_count > 0) {
            if (!step_buffer(b, dt, raw_force, raw_torque, substeps, contact)) {
                faults |= SH_HAPTIC_FAULT_UNSTABLE;
                warnings_[SH_WARN_UNSTABLE].fetch_add(1, std::memory_order_relaxed);
                // The state before this step led there: start again from the full model's.
                load_state(b, false);
            }
        } else if (b.has_proxy) {
            contact = proxy_force(b, raw_force, raw_torque);
        }
        pose_ = pose;
        have_pose_ = true;
    }
    if (age_ > def_.stale_after) faults |= SH_HAPTIC_FAULT_STALE;

    out = sh_haptic_output{};
    const uint32_t warnings =
        step_warnings_ | filter_.update(raw_force, raw_torque, faults == 0, step_dt, out.force, out.torque);
    for (int k = 0; k < SH_WARN_COUNT; ++k)
        if (warnings & (1u << k)) warnings_[k].fetch_add(1, std::memory_order_relaxed);
    for (int k = 0; k < 3; ++k) out.raw_force[k] = std::isfinite(raw_force[k]) ? raw_force[k] : 0.0;
    out.contact = contact ? 1 : 0;
    out.buffer_tets = b.tet_count;
    out.buffer_nodes = b.node_count;
    out.substeps = substeps;
    out.data_age = age_;
    out.faults = faults;
    out.warnings = warnings | (faults & SH_HAPTIC_FAULT_UNSTABLE ? 1u << SH_WARN_UNSTABLE : 0u);
    return status;
}

}  // namespace sh
