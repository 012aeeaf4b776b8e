#include "contact/shape_contact.hpp"

#include "contact/ball_mix.hpp"
#include "contact/ball_terms.hpp"
#include "contact/hunt_crossley.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

void set_geometry(const Penetration& pen, int count, const int32_t* nodes, const double* weights, ContactPoint& out) {
    out.depth = pen.depth;
    out.law_scale = 1.0;
    for (int k = 0; k < 3; ++k) {
        out.normal[k] = pen.normal[k];
        out.point[k] = pen.point[k];
    }
    set_contact_nodes(count, nodes, weights, out);
}

}  // namespace

bool node_shape_contact(const Collider& collider, const double* x, int32_t node, ContactPoint& out) {
    Penetration pen;
    if (!collider.shape.penetrate_point(collider.pose, at(x, node), pen)) return false;
    const double one = 1.0;
    set_geometry(pen, 1, &node, &one, out);
    return true;
}

double excess_weight(const Collider& collider, double size) {
    const double t = std::min(std::max(collider.shape.inner_radius() / size - 1.0, 0.0), 1.0);
    return std::isfinite(t) ? 1.0 - t * t * (3.0 - 2.0 * t) : 0.0;
}

double resolved_band(const Collider& collider) {
    return collider.shape.ball_is_shape() ? 0.02 * collider.shape.inner_radius() : collider.shape.ball_radius();
}

bool excess_shape_contact(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes,
                          int count, double weight, const BallMix* mix, ContactPoint& out) {
    if (collider.shape.mixes_balls()) return mix && mix->term(collider, law, x, nodes, count, weight, out);
    bool found = false;
    for_each_ball_term(collider, law, x, nodes, count, weight, [&](int, const ContactPoint& term) {
        out = term;
        found = true;
    });
    return found;
}

void apply_excess_damping(const sh_contact_params& p, const double vrel[3], ContactPoint& out) {
    const double factor = std::max(0.0, 1.0 - 1.5 * p.damping * dot3(out.normal, vrel));
    for (int k = 0; k < 3; ++k) out.relative_velocity[k] = vrel[k];
    out.normal_force *= factor;
    out.net_normal_force *= factor;
    out.stiffness *= factor;
    for (int a = 0; a < 3 && out.mixed; ++a) out.stiffness_bound[a] *= factor;
    for (int a = 0; a < out.count; ++a)
        for (int k = 0; k < 3; ++k) out.node_force[a][k] *= factor;
}

void velocity_against_collider(const Collider& collider, const ContactPoint& out, const double* v, double vrel[3]) {
    double vc[3];
    collider.point_velocity(out.point, vc);
    for (int k = 0; k < 3; ++k) {
        double s = 0.0;
        for (int a = 0; a < out.count; ++a) s += out.weights[a] * at(v, out.nodes[a])[k];
        vrel[k] = s - vc[k];
    }
}

namespace {

// out's normal force, its derivatives and node forces from fn, scaled by out.law_scale.
void set_normal_force(const NormalForce& fn, const double* vrel, ContactPoint& out) {
    const double zero[3] = {0.0, 0.0, 0.0};
    if (!vrel) vrel = zero;
    out.stiffness = out.law_scale * fn.stiffness;
    out.damping = out.law_scale * fn.damping;
    out.normal_force = out.law_scale * fn.force;
    out.net_normal_force = out.normal_force;
    out.energy = 0.0;
    out.friction = 0.0;
    out.friction_normal = 0.0;
    for (int k = 0; k < 3; ++k) out.relative_velocity[k] = vrel[k];
    for (int a = 0; a < out.count; ++a)
        for (int k = 0; k < 3; ++k) out.node_force[a][k] = out.normal_force * out.gradient[a][k];
}

}  // namespace

void apply_normal_law(const sh_contact_params& p, const double* vrel, ContactPoint& out) {
    const double normal_speed = vrel ? dot3(out.normal, vrel) : 0.0;
    set_normal_force(hunt_crossley(p, out.depth, -normal_speed), vrel, out);
}

void apply_step_normal_law(const sh_contact_params& p, const StepLaw& law, const double* vrel, ContactPoint& out) {
    set_normal_force(hunt_crossley_step(p, law, out.depth), vrel, out);
}

void apply_friction(const sh_contact_params& p, double friction_normal, ContactPoint& out) {
    const double normal_speed = dot3(out.normal, out.relative_velocity);
    double vt[3], ft[3];
    for (int k = 0; k < 3; ++k) vt[k] = out.relative_velocity[k] - normal_speed * out.normal[k];
    out.friction_normal = friction_normal;
    out.friction = coulomb_friction(p, friction_normal, vt, ft);
    for (int a = 0; a < out.count; ++a)
        for (int k = 0; k < 3; ++k) out.node_force[a][k] += out.weights[a] * ft[k];
}

double stiffness_share(const ContactPoint& p, int a) {
    double row = 0.0;
    for (int b = 0; b < p.count; ++b) row += norm3(p.gradient[b]);
    return norm3(p.gradient[a]) * row;
}

void set_contact_nodes(int count, const int32_t* nodes, const double* weights, ContactPoint& out) {
    out.count = count;
    for (int a = 0; a < count; ++a) {
        out.nodes[a] = nodes[a];
        out.weights[a] = weights[a];
        for (int k = 0; k < 3; ++k) out.gradient[a][k] = weights[a] * out.normal[k];
    }
}

FrictionRecord friction_record(const ContactPoint& p, const sh_contact_params& params, const double* v) {
    FrictionRecord r;
    r.count = p.count;
    r.normal_force = p.friction_normal;
    r.params = &params;
    for (int k = 0; k < 3; ++k) {
        r.normal[k] = p.normal[k];
        r.offset[k] = -p.relative_velocity[k];
        r.point[k] = p.point[k];
    }
    for (int a = 0; a < p.count; ++a) {
        r.nodes[a] = p.nodes[a];
        r.weights[a] = p.weights[a];
        for (int k = 0; k < 3; ++k) r.offset[k] += p.weights[a] * at(v, p.nodes[a])[k];
    }
    return r;
}

ContactPoint node_friction_point(const Collider& collider, int32_t node, const double push[3], const double* x,
                                 const double* v) {
    ContactPoint p{};
    p.law_scale = 1.0;
    const double fn = norm3(push), one = 1.0;
    for (int k = 0; k < 3; ++k) {
        p.point[k] = at(x, node)[k];
        p.normal[k] = fn > 0.0 ? push[k] / fn : 0.0;
    }
    set_contact_nodes(1, &node, &one, p);
    velocity_against_collider(collider, p, v, p.relative_velocity);
    p.friction_normal = fn;
    return p;
}

void apply_implicit_friction(const FrictionRecord& r, const double* inverse_mass, double h, double* x, double* v,
                             double impulse[3]) {
    if (impulse) impulse[0] = impulse[1] = impulse[2] = 0.0;
    // Backward Euler on the velocities the step reached without friction, with the normal
    // force and normal of the step's start. An explicit viscous friction mu_s fn / s0 would
    // need a step below the node's mass over it (or a cap there, which lets a node that carries
    // more weight than its own creep at its load times h over its mass); this one holds a
    // sticking contact at the regularised law's creep, at most slip_velocity, at any step.
    double w = 0.0;  // effective inverse mass of the contact (1/kg)
    double vt[3];
    for (int k = 0; k < 3; ++k) vt[k] = -r.offset[k];
    for (int a = 0; a < r.count; ++a) {
        const size_t node = static_cast<size_t>(r.nodes[a]);
        w += r.weights[a] * r.weights[a] * inverse_mass[node];
        for (int k = 0; k < 3; ++k) vt[k] += r.weights[a] * v[3 * node + k];
    }
    if (!(w > 0.0)) return;
    const double vn = dot3(vt, r.normal);
    for (int k = 0; k < 3; ++k) vt[k] -= vn * r.normal[k];
    const double speed = norm3(vt);
    if (!(speed > 0.0)) return;
    const double slowed = implicit_slip_speed(*r.params, r.normal_force, speed, w * h);
    // The impulse J = -(speed - slowed) / w along vt changes node a's velocity by
    // weights[a] J / m_a, and the contact's relative velocity by w J.
    const double scale = -(speed - slowed) / (w * speed);
    if (impulse)
        for (int k = 0; k < 3; ++k) impulse[k] = scale * vt[k];
    for (int a = 0; a < r.count; ++a) {
        const size_t node = static_cast<size_t>(r.nodes[a]);
        const double share = scale * r.weights[a] * inverse_mass[node];
        for (int k = 0; k < 3; ++k) {
            v[3 * node + k] += share * vt[k];
            if (x) x[3 * node + k] += h * share * vt[k];
        }
    }
}

void pair_triangles_across_edges(const int32_t* tris, size_t count, int32_t* neighbor) {
    struct Side {
        int32_t lo, hi, index;  ///< node pair, and 3 triangle + k
    };
    const size_t sides_count = 3 * count;
    vec<Side> sides(sides_count);
    for (size_t i = 0; i < sides_count; ++i) {
        const int32_t a = tris[i], b = tris[i - i % 3 + (i % 3 + 1) % 3];
        sides[i] = {std::min(a, b), std::max(a, b), static_cast<int32_t>(i)};
        neighbor[i] = -1;
    }
    std::sort(sides.begin(), sides.end(),
              [](const Side& p, const Side& q) { return p.lo != q.lo ? p.lo < q.lo : p.hi != q.hi ? p.hi < q.hi : p.index < q.index; });
    for (size_t i = 0; i < sides.size();) {
        size_t j = i;
        while (j < sides.size() && sides[j].lo == sides[i].lo && sides[j].hi == sides[i].hi) ++j;
        if (j - i == 2) {  // a manifold edge
            neighbor[static_cast<size_t>(sides[i].index)] = sides[i + 1].index / 3;
            neighbor[static_cast<size_t>(sides[i + 1].index)] = sides[i].index / 3;
        }
        i = j;
    }
}

}  // namespace sh
