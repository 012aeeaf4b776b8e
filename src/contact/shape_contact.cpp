#include "contact/shape_contact.hpp"

#include "contact/hunt_crossley.hpp"

namespace sh {
namespace {

void set_geometry(const Penetration& pen, int count, const int32_t* nodes, const double* weights, ContactPoint& out) {
    out.depth = pen.depth;
    out.count = count;
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

bool face_shape_contact(const Collider& collider, const double* x, const int32_t face[3], ContactPoint& out) {
    Penetration pen;
    double w[3];
    if (!collider.shape.penetrate_triangle(collider.pose, at(x, face[0]), at(x, face[1]), at(x, face[2]), pen, w))
        return false;
    set_geometry(pen, 3, face, w, out);
    return true;
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

void apply_contact_law(const sh_contact_params& p, const double* vrel, double friction_cap, ContactPoint& out) {
    const double normal_speed =
        vrel ? out.normal[0] * vrel[0] + out.normal[1] * vrel[1] + out.normal[2] * vrel[2] : 0.0;
    const NormalForce fn = hunt_crossley(p, out.depth, -normal_speed);
    out.stiffness = fn.stiffness;
    out.damping = fn.damping;
    out.friction = 0.0;
    double ft[3] = {0.0, 0.0, 0.0};
    if (vrel && fn.force > 0.0 && p.static_friction > 0.0) {
        double vt[3];
        for (int k = 0; k < 3; ++k) vt[k] = vrel[k] - normal_speed * out.normal[k];
        out.friction = coulomb_friction(p, fn.force, vt, ft);
        if (friction_cap > 0.0 && out.friction > friction_cap) {
            const double scale = friction_cap / out.friction;
            out.friction *= scale;
            for (double& f : ft) f *= scale;
        }
    }
    for (int a = 0; a < out.count; ++a)
        for (int k = 0; k < 3; ++k) out.node_force[a][k] = fn.force * out.gradient[a][k] + out.weights[a] * ft[k];
}

}  // namespace sh
