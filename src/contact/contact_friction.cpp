// BodyContacts' friction: lagged at the step's start for implicit bodies (a dissipation
// potential, and the tangent heuristic that keeps Newton from cycling where contacts stop),
// taken implicitly after the update for explicit ones.
#include "contact/body_contacts.hpp"

#include "contact/body_contacts_eval.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

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
    for (int k = 0; k < 3; ++k) {
        out.normal[k] = r.lag_normal[k];
        out.point[k] = r.lag_point[k];
    }
    set_contact_nodes(count, nodes, weights, out);
    for (int a = 0; a < count; ++a)
        for (int k = 0; k < 3; ++k) vrel[k] += weights[a] * at(v, nodes[a])[k];
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

void BodyContacts::add_node_push(const ContactPoint& p) const {
    for (int a = 0; a < p.count; ++a) {
        double* push = &scratch_.node_push[3 * static_cast<size_t>(p.nodes[a])];
        if (push[0] == 0.0 && push[1] == 0.0 && push[2] == 0.0) scratch_.pushed_nodes.push_back(p.nodes[a]);
        for (int k = 0; k < 3; ++k) push[k] += p.node_force[a][k];
    }
}

void BodyContacts::begin_explicit_step() const {
    scratch_.recording = true;
    scratch_.friction_records.clear();
}

void BodyContacts::end_explicit_step(double h, bool move_positions, double* x, double* v) const {
    // Friction taken implicitly on the velocities the step reached without it, contact by
    // contact (Gauss-Seidel over contacts sharing nodes), with the normal force and normal of
    // the step's start (see apply_implicit_friction).
    scratch_.recording = false;
    for (const FrictionRecord& r : scratch_.friction_records)
        apply_implicit_friction(r, body_.inverse_mass.data(), h, move_positions ? x : nullptr, v);
    scratch_.friction_records.clear();
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

}  // namespace sh
