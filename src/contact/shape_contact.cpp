#include "contact/shape_contact.hpp"

#include "contact/hunt_crossley.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// Dihedral angle (between the outward normals) from which a convex edge has the whole contact
// law (rad): 15 degrees.
constexpr double kFullEdgeAngle = 0.2617993877991494;

void set_geometry(const Penetration& pen, int count, const int32_t* nodes, const double* weights, ContactPoint& out) {
    out.depth = pen.depth;
    out.count = count;
    out.law_scale = 1.0;
    for (int k = 0; k < 3; ++k) {
        out.normal[k] = pen.normal[k];
        out.point[k] = pen.point[k];
    }
    for (int a = 0; a < count; ++a) {
        out.nodes[a] = nodes[a];
        out.weights[a] = weights[a];
        for (int k = 0; k < 3; ++k) out.gradient[a][k] = weights[a] * out.normal[k];
    }
}

inline const double* at(const double* x, int32_t node) { return x + 3 * static_cast<size_t>(node); }

}  // namespace

bool node_shape_contact(const Collider& collider, const double* x, int32_t node, ContactPoint& out) {
    Penetration pen;
    if (!collider.shape.penetrate_point(collider.pose, at(x, node), pen)) return false;
    const double one = 1.0;
    set_geometry(pen, 1, &node, &one, out);
    return true;
}

namespace {

// Share of a collider's inner radius over which a node's lowering reaches its depth's slope.
constexpr double kLoweringScale = 0.1;

// The lowering of node nodes[node] (0 without nodes).
inline double node_lowering(const NodeDepth* nodes, int32_t node) {
    return nodes ? nodes[static_cast<size_t>(node)].lowering : 0.0;
}

// Adds scale times node nodes[node]'s push times its lowering's slope to g: minus the
// lowering's gradient.
inline void add_node_push(const NodeDepth* nodes, int32_t node, double scale, double g[3]) {
    if (!nodes || !(nodes[static_cast<size_t>(node)].slope > 0.0)) return;
    const NodeDepth& d = nodes[static_cast<size_t>(node)];
    for (int k = 0; k < 3; ++k) g[k] += scale * d.slope * d.normal[k];
}

}  // namespace

NodeDepth node_depth_of(const Collider& collider, const ContactPoint& p) {
    NodeDepth d;
    d.depth = p.depth;
    for (int k = 0; k < 3; ++k) d.normal[k] = p.normal[k];
    const double delta = kLoweringScale * collider.shape.inner_radius();
    // Below delta the cubic 2 d^2 / delta - d^3 / delta^2 (value and slope 0 at 0, d and 1 at
    // delta, never above d); beyond it the depth itself. A plane has no faces to lower.
    const double r = std::isfinite(delta) && delta > 0.0 ? p.depth / delta : INFINITY;
    d.lowering = r < 1.0 ? p.depth * r * (2.0 - r) : p.depth;
    d.slope = r < 1.0 ? r * (4.0 - 3.0 * r) : 1.0;
    return d;
}

bool face_shape_contact(const Collider& collider, const double* x, const int32_t face[3], const NodeDepth* nodes,
                        ContactPoint& out) {
    const double* corner[3] = {at(x, face[0]), at(x, face[1]), at(x, face[2])};
    const double lowered[3] = {node_lowering(nodes, face[0]), node_lowering(nodes, face[1]), node_lowering(nodes, face[2])};
    TrianglePenetration pen;
    if (!collider.shape.penetrate_triangle(collider.pose, corner[0], corner[1], corner[2], lowered, pen)) return false;
    const double* n = pen.normal;
    const double* nt = pen.tilted;
    const double cosine = dot3(n, nt);
    // The depth e = H - sum_j w_j l_j: H the triangle's height over the collider's deepest point
    // s' (along n), l_j the nodes' lowerings, w the weights of s''s foot. As a maximum over the
    // triangle (s' is where the collider reaches deepest below the lowered plane), its gradient
    // holds w fixed (envelope theorem): dH/dx_j = (w_j n' + H (e_j x t) / area2) / (n'.n), t the
    // part of n' across n and e_j the edge opposite node j (the second term is n's turning),
    // and -w_j dl_j/dx_j = w_j times node j's lowering slope times its push.
    double across[3];
    for (int k = 0; k < 3; ++k) across[k] = nt[k] - cosine * n[k];
    double opposite[3][3];
    for (int j = 0; j < 3; ++j) sub3(corner[(j + 2) % 3], corner[(j + 1) % 3], opposite[j]);
    out.depth = pen.depth;
    out.count = 3;
    out.law_scale = 1.0;
    for (int k = 0; k < 3; ++k) {
        out.normal[k] = -nt[k];
        out.point[k] = pen.point[k];
    }
    for (int j = 0; j < 3; ++j) {
        double turn[3], d_depth[3];
        cross3(opposite[j], across, turn);
        for (int k = 0; k < 3; ++k) d_depth[k] = (pen.bary[j] * nt[k] + pen.height * turn[k] / pen.area2) / cosine;
        add_node_push(nodes, face[j], pen.bary[j], d_depth);
        out.nodes[j] = face[j];
        out.weights[j] = pen.bary[j];
        for (int k = 0; k < 3; ++k) out.gradient[j][k] = -d_depth[k];
    }
    return true;
}

namespace {

// Unit outward normals n1 of own triangle (a, b, c) and n2 of the one across (b, a, d), if the
// edge (a, b) between them is convex: d lies behind own triangle's plane.
bool convex_edge_normals(const double* a, const double* b, const double* c, const double* d, double n1[3],
                         double n2[3]) {
    double ab[3], ac[3], ad[3];
    sub3(b, a, ab);
    sub3(c, a, ac);
    sub3(d, a, ad);
    cross3(ab, ac, n1);
    cross3(ad, ab, n2);
    const double l1 = norm3(n1), l2 = norm3(n2);
    if (!(l1 > 0.0 && l2 > 0.0)) return false;
    for (int k = 0; k < 3; ++k) {
        n1[k] /= l1;
        n2[k] /= l2;
    }
    return dot3(n1, ad) < -1e-9 * std::sqrt(dot3(ab, ab) * dot3(ad, ad));
}

}  // namespace

bool edge_shape_contact(const Collider& collider, const double* x, const int32_t edge[4], const NodeDepth* nodes,
                        ContactPoint& out) {
    const double *a = at(x, edge[0]), *b = at(x, edge[1]);
    double n1[3], n2[3];
    if (!convex_edge_normals(a, b, at(x, edge[2]), at(x, edge[3]), n1, n2)) return false;
    Penetration pen;
    double t = 0.0;
    if (!collider.shape.penetrate_edge(collider.pose, a, b, n1, n2, pen, t)) return false;
    // The edge's depth D has gradient ((1 - t) m, t m), m = -pen.normal, t where the collider
    // touches the edge (exact: the overlap is least over the directions across the edge). The
    // nodes carry their lowerings interpolated at c, the foot of the collider's centre on the
    // edge's line (clamped to the edge): a smooth share whose gradient holds the centre fixed,
    // dc/da = ((2c - 1) (b - a) - (p - a)) / L^2, dc/db = ((p - a) - 2c (b - a)) / L^2.
    const double da = node_lowering(nodes, edge[0]), db = node_lowering(nodes, edge[1]);
    double ab[3], ap[3];
    sub3(b, a, ab);
    sub3(collider.pose.p, a, ap);
    const double length2 = dot3(ab, ab);
    const double foot = dot3(ap, ab) / length2;
    const double c = std::min(1.0, std::max(0.0, foot));
    const double depth = pen.depth - (1.0 - c) * da - c * db;
    if (!(depth > 0.0)) return false;
    const bool inside = foot > 0.0 && foot < 1.0;
    const double w[2] = {1.0 - t, t};
    double d_depth[2][3];
    for (int k = 0; k < 3; ++k) {
        const double dc_da = inside ? ((2.0 * c - 1.0) * ab[k] - ap[k]) / length2 : 0.0;
        const double dc_db = inside ? (ap[k] - 2.0 * c * ab[k]) / length2 : 0.0;
        d_depth[0][k] = -w[0] * pen.normal[k] - (db - da) * dc_da;
        d_depth[1][k] = -w[1] * pen.normal[k] - (db - da) * dc_db;
    }
    const double share[2] = {1.0 - c, c};
    for (int j = 0; j < 2; ++j) add_node_push(nodes, edge[j], share[j], d_depth[j]);
    out.depth = depth;
    out.count = 2;
    for (int k = 0; k < 3; ++k) {
        out.normal[k] = pen.normal[k];
        out.point[k] = pen.point[k];
    }
    for (int j = 0; j < 2; ++j) {
        out.nodes[j] = edge[j];
        out.weights[j] = w[j];
        for (int k = 0; k < 3; ++k) out.gradient[j][k] = -d_depth[j][k];
    }
    // Where the edge's region meets a face's (the least overlap at n1 or n2), the edge's depth
    // is the face's: the whole law on both sides keeps the potential continuous across it.
    out.law_scale = 1.0;
    return true;
}

double depth_rate(const Collider& collider, const ContactPoint& out, const double* v) {
    // d depth/dt = sum_j (d depth/dx_j) . (v_j - v_c): moving the body and the collider
    // together leaves the depth as it is.
    double vc[3];
    collider.point_velocity(out.point, vc);
    double rate = 0.0;
    for (int a = 0; a < out.count; ++a) {
        double dv[3];
        sub3(at(v, out.nodes[a]), vc, dv);
        rate -= dot3(out.gradient[a], dv);
    }
    return rate;
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
    out.friction = 0.0;
    out.friction_normal = 0.0;
    for (int k = 0; k < 3; ++k) out.relative_velocity[k] = vrel[k];
    for (int a = 0; a < out.count; ++a)
        for (int k = 0; k < 3; ++k) out.node_force[a][k] = out.normal_force * out.gradient[a][k];
}

}  // namespace

void apply_normal_law(const sh_contact_params& p, const double* vrel, double rate, ContactPoint& out) {
    set_normal_force(hunt_crossley(p, out.depth, rate), vrel, out);
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
