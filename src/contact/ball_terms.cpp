// A ball's excess term over a surface edge or triangle: its nodes' depths in the ball, the
// fade as they come in, and the ball's excess (collision/ball_excess.hpp) at the maximiser.
#include "contact/ball_terms.hpp"

#include "collision/ball_excess.hpp"
#include "contact/shape_contact.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// Where every node of a feature is in the collider, the mesh resolves the contact there and
// its node terms carry it: the feature's excess (then only the interpolant's own small error,
// whose maximiser wanders with every node's motion and slows Newton) fades out as its
// shallowest nodes come in: factor 1 - prod_a s(d_a), s a C^1 smoothstep from 0 at depth 0 to
// 1 at the band. A feature with a node outside keeps its whole excess, so a tool smaller than
// the triangles is held exactly as the potential says.
class ResolvedFade {
public:
    explicit ResolvedFade(double band) : band_(band) {}
    void add_node(double depth) {
        const double t = std::min(std::max(depth / band_, 0.0), 1.0);
        step_[count_] = t * t * (3.0 - 2.0 * t);
        slope_[count_] = 6.0 * t * (1.0 - t) / band_;
        ++count_;
    }
    /// Multiplies the factor (and its slopes) by a constant weight.
    void scale(double weight) { weight_ = weight; }
    double factor() const {
        double product = 1.0;
        for (int a = 0; a < count_; ++a) product *= step_[a];
        return weight_ * (1.0 - product);
    }
    /// d factor / d depth of node a.
    double slope(int a) const {
        double product = -weight_ * slope_[a];
        for (int b = 0; b < count_; ++b)
            if (b != a) product *= step_[b];
        return product;
    }

private:
    double band_, weight_ = 1.0;
    double step_[3] = {}, slope_[3] = {};
    int count_ = 0;
};

}  // namespace

FeatureNodes::FeatureNodes(const Collider& collider, const double* x, const int32_t* nodes, int count)
    : count(count), own_depths(!collider.shape.ball_is_shape()), measured(false) {
    for (int a = 0; a < count; ++a) points[a] = at(x, nodes[a]);
}

void FeatureNodes::measure(const Collider& collider) {
    if (measured || !own_depths) return;
    measured = true;
    for (int a = 0; a < count; ++a) {
        Penetration pen;
        depth[a] = collider.shape.penetrate_point(collider.pose, points[a], pen) ? pen.depth : 0.0;
        for (int k = 0; k < 3; ++k) normal[a][k] = depth[a] > 0.0 ? pen.normal[k] : 0.0;
    }
}

bool feature_normal(const double* const points[3], double normal[3]) {
    double ab[3], ac[3];
    sub3(points[1], points[0], ab);
    sub3(points[2], points[0], ac);
    cross3(ab, ac, normal);
    // A sliver (its smallest angle below 1e-6 rad, or a degenerate triangle) counts as none:
    // its normal and its closest points are at the mercy of round-off.
    const double length = norm3(normal), scale = norm3(ab) * norm3(ac);
    const bool flat = length > 1e-6 * scale;
    for (int k = 0; k < 3; ++k) normal[k] = flat ? normal[k] / length : 0.0;
    return flat;
}

double feature_distance(const double* p, const double* const points[3], int count, bool flat) {
    if (count == 2) return distance_to_segment(p, points[0], points[1]);
    double w[3];
    return flat ? closest_on_triangle(p, points[0], points[1], points[2], w) : 0.0;
}

bool ball_term(const Collider& collider, const DepthPotential& psi, FeatureNodes& feature, const int32_t* nodes,
               int count, double weight, const double centre[3], ContactPoint& out) {
    feature.measure(collider);
    LocalSimplex s;
    s.count = count;
    double node_push[3][3], node_normal[3][3];
    ResolvedFade fade(resolved_band(collider));
    // The fade takes the nodes' depths in the collider (a sphere's: in its one ball).
    double fade_normal[3][3];
    for (int a = 0; a < count; ++a) {
        const double depth =
            ball_depth(centre, collider.shape.ball_radius(), collider.pose, feature.points[a], node_normal[a]);
        const bool inside = depth > 0.0;
        s.energy[a] = inside ? psi.energy(depth) : 0.0;
        const double force = inside ? psi.force(depth) : 0.0;
        for (int k = 0; k < 3; ++k) {
            s.p[a][k] = feature.points[a][k];
            node_push[a][k] = force * node_normal[a][k];
        }
        fade.add_node(feature.own_depths ? feature.depth[a] : std::max(depth, 0.0));
        for (int k = 0; k < 3; ++k) fade_normal[a][k] = feature.own_depths ? feature.normal[a][k] : node_normal[a][k];
    }
    if (!(fade.factor() > 0.0)) return false;
    fade.scale(weight);
    const LocalExcess e = ball_excess(s, psi, centre, collider.shape.ball_radius());
    if (!(e.value > 0.0) || !std::isfinite(e.value)) return false;
    out.depth = e.depth;
    for (int k = 0; k < 3; ++k) {
        out.normal[k] = e.n[k];
        out.point[k] = e.x[k];
    }
    // For the tangent, stiffness times gradient gradient^T (set_contact_nodes: the weights
    // times the normal): the law's curvature at the maximiser through its weights (the
    // positive part of the term's Hessian; the nodes' own curvature it subtracts, the
    // maximiser's motion and the fade are left to the line search). Not the node forces over
    // the law's force: that ratio grows without bound where the maximiser is shallow and its
    // nodes deep.
    set_contact_nodes(count, nodes, e.w, out);
    const double sign = count == 2 ? -1.0 : 1.0;  // faces add, edges subtract
    const double scale = sign * fade.factor();
    out.law_scale = sign;
    out.energy = scale * e.value;
    out.normal_force = scale * psi.force(e.depth);
    // For the tangent: the law's curvature at the maximiser times the excess's share of the
    // law's energy there, which vanishes with the excess (where the law's own curvature does
    // not, as for a linear law at its onset).
    const double law_energy = psi.energy(e.depth);
    out.stiffness = scale * psi.stiffness(e.depth) * (law_energy > 0.0 ? std::min(e.value / law_energy, 1.0) : 0.0);
    out.damping = out.friction = out.friction_normal = 0.0;
    out.net_normal_force = 0.0;
    for (int k = 0; k < 3; ++k) out.relative_velocity[k] = 0.0;
    // Node a: w_a (push at the maximiser - its own push), the gradient of the excess, and
    // the fade's: -excess d(factor)/dx_a, along the node's push out of the collider.
    for (int a = 0; a < count; ++a) {
        const double fade_slope = sign * e.value * fade.slope(a);
        for (int k = 0; k < 3; ++k) {
            out.node_force[a][k] = scale * e.w[a] * (e.push[k] - node_push[a][k]) + fade_slope * fade_normal[a][k];
            out.net_normal_force += out.node_force[a][k] * out.normal[k];
        }
    }
    return true;
}

}  // namespace sh
