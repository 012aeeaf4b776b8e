#include "contact/shape_contact.hpp"

#include "collision/ball_excess.hpp"
#include "collision/unit_vector.hpp"
#include "contact/hunt_crossley.hpp"
#include "core/vec3.hpp"

#include <Eigen/Dense>

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

namespace {

// The step's Hunt-Crossley law as the potential the excess maximises.
class StepLawPotential final : public DepthPotential {
public:
    StepLawPotential(const sh_contact_params& params, const StepLaw& law) : params_(params), law_(law) {}
    double energy(double depth) const override { return hunt_crossley_step_energy(params_, law_, depth); }
    double force(double depth) const override { return hunt_crossley_step(params_, law_, depth).force; }
    double stiffness(double depth) const override { return hunt_crossley_step(params_, law_, depth).stiffness; }

private:
    const sh_contact_params& params_;
    const StepLaw& law_;
};

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

double excess_weight(const Collider& collider, double size) {
    const double t = std::min(std::max(collider.shape.inner_radius() / size - 1.0, 0.0), 1.0);
    return std::isfinite(t) ? 1.0 - t * t * (3.0 - 2.0 * t) : 0.0;
}

double resolved_band(const Collider& collider) { return 0.02 * collider.shape.inner_radius(); }

namespace {

// The feature's bounding sphere: centre and radius (m).
double feature_bounds(const double* const points[3], int count, double centre[3]) {
    for (int k = 0; k < 3; ++k) {
        centre[k] = 0.0;
        for (int a = 0; a < count; ++a) centre[k] += points[a][k] / count;
    }
    double radius = 0.0;
    for (int a = 0; a < count; ++a) {
        double d[3];
        sub3(points[a], centre, d);
        radius = std::max(radius, norm3(d));
    }
    return radius;
}

// A node's depth (m) in the ball at centre, and its push's direction.
double ball_depth(const Collider& collider, const double centre[3], const double* p, double normal[3]) {
    sub3(p, centre, normal);
    const double dist = norm3(normal);
    if (dist > 1e-12 * collider.shape.ball_radius()) {
        for (int k = 0; k < 3; ++k) normal[k] /= dist;
    } else {  // at the centre: any direction; the collider's local x axis
        const double ex[3] = {1.0, 0.0, 0.0};
        collider.pose.rotate(ex, normal);
    }
    return collider.shape.ball_radius() - dist;
}

// The excess term of the ball at centre over the feature (points, nodes, count), as
// excess_shape_contact describes it for a sphere: its nodes' depths are the ball's.
bool ball_term(const Collider& collider, const DepthPotential& psi, const double* const points[3], const int32_t* nodes,
               int count, double weight, const double centre[3], ContactPoint& out) {
    LocalSimplex s;
    s.count = count;
    double node_push[3][3], node_normal[3][3];
    ResolvedFade fade(resolved_band(collider));
    for (int a = 0; a < count; ++a) {
        const double depth = ball_depth(collider, centre, points[a], node_normal[a]);
        const bool inside = depth > 0.0;
        s.energy[a] = inside ? psi.energy(depth) : 0.0;
        const double force = inside ? psi.force(depth) : 0.0;
        for (int k = 0; k < 3; ++k) {
            s.p[a][k] = points[a][k];
            node_push[a][k] = force * node_normal[a][k];
        }
        fade.add_node(inside ? depth : 0.0);
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
    // the fade's: -excess d(factor)/dx_a, along the node's push.
    for (int a = 0; a < count; ++a) {
        const double fade_slope = sign * e.value * fade.slope(a);
        for (int k = 0; k < 3; ++k) {
            out.node_force[a][k] = scale * e.w[a] * (e.push[k] - node_push[a][k]) + fade_slope * node_normal[a][k];
            // For the tangent, stiffness times gradient gradient^T: the law's curvature at the
            // maximiser through its weights (the positive part of the term's Hessian; the
            // nodes' own curvature it subtracts, the maximiser's motion and the fade are left
            // to the line search). Not the node forces over the law's force: that ratio grows
            // without bound where the maximiser is shallow and its nodes deep.
            out.net_normal_force += out.node_force[a][k] * out.normal[k];
        }
    }
    return true;
}

// Calls visit(i, term) for each ball i of the collider with an excess term over the feature.
template <class Visit>
void for_each_ball_term(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes, int count,
                        double weight, Visit&& visit) {
    if (collider.shape.ball_count() == 0 || !(weight > 0.0)) return;
    const StepLawPotential psi(collider.params, law);
    const double* points[3];
    for (int a = 0; a < count; ++a) points[a] = at(x, nodes[a]);
    double centre[3];
    const double reach = feature_bounds(points, count, centre) + collider.shape.ball_radius();
    int first = 0, last = -1;
    collider.shape.balls_near(collider.pose, centre, reach, first, last);
    for (int i = first; i <= last; ++i) {
        double ball[3];
        collider.shape.ball_centre(collider.pose, i, ball);
        ContactPoint term;
        if (ball_term(collider, psi, points, nodes, count, weight, ball, term)) visit(i, term);
    }
}

// Adds `share` of term's energy and geometry, and `coefficient` of its forces, to out;
// geometry weighs by |share * energy| (`mass` keeps the sum).
void mix_term(const ContactPoint& term, double share, double coefficient, ContactPoint& out, double& mass) {
    const double w = std::fabs(share * term.energy);
    out.energy += share * term.energy;
    out.stiffness += share * term.stiffness;
    out.normal_force += coefficient * term.normal_force;
    out.net_normal_force += coefficient * term.net_normal_force;
    out.depth += w * term.depth;
    for (int k = 0; k < 3; ++k) {
        out.point[k] += w * term.point[k];
        out.normal[k] += w * term.normal[k];
    }
    for (int a = 0; a < term.count; ++a) {
        out.weights[a] += w * term.weights[a];
        for (int k = 0; k < 3; ++k) {
            out.node_force[a][k] += coefficient * term.node_force[a][k];
            out.gradient[a][k] += w * term.gradient[a][k];
        }
    }
    mass += w;
}

// The Hessian of a mixed term over its nodes' 3 count coordinates: sum_i c_i H_i (each
// ball's own, its stiffness k g g^T) + sum_ij (d c_i / d P_j) G_i G_j^T, G_i the gradient of
// ball i's term (minus its node forces), with d c_i / d P_j from BallMix: the smooth maximum's
// curvature within this term (across terms it is left out, as the tangent keeps to a term's
// nodes).
class MixedHessian {
public:
    void add(const ContactPoint& term, double coefficient, double curvature, double cross) {
        double g[9] = {}, G[9] = {};
        for (int a = 0; a < term.count; ++a)
            for (int k = 0; k < 3; ++k) {
                g[3 * a + k] = term.gradient[a][k];
                G[3 * a + k] = -term.node_force[a][k];
            }
        for (int r = 0; r < 9; ++r) {
            b_[r] += cross * G[r];
            c_[r] += coefficient * G[r];
            for (int s = 0; s < 9; ++s) k_[r][s] += coefficient * term.stiffness * g[r] * g[s] + curvature * G[r] * G[s];
        }
    }
    void write(double out[9][9]) const {
        for (int r = 0; r < 9; ++r)
            for (int s = 0; s < 9; ++s) out[r][s] = k_[r][s] - b_[r] * c_[s] - c_[r] * b_[s];
    }

private:
    double k_[9][9] = {}, b_[9] = {}, c_[9] = {};
};

// The mixed term of a collider of several balls (see BallMix).
bool mixed_term(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes, int count,
                double weight, const BallMix& mix, ContactPoint& out) {
    out = ContactPoint{};
    out.count = count;
    out.law_scale = count == 2 ? -1.0 : 1.0;
    for (int a = 0; a < count; ++a) out.nodes[a] = nodes[a];
    double mass = 0.0;
    bool any = false;
    MixedHessian hessian;
    for_each_ball_term(collider, law, x, nodes, count, weight, [&](int i, const ContactPoint& term) {
        if (mix.share(i) == 0.0 && mix.coefficient(i) == 0.0) return;
        mix_term(term, mix.share(i), mix.coefficient(i), out, mass);
        hessian.add(term, mix.coefficient(i), mix.curvature(i), mix.cross(i));
        any = true;
    });
    if (!any || !(mass > 0.0)) return false;
    hessian.write(out.hessian);
    out.has_hessian = true;
    out.depth /= mass;
    for (int k = 0; k < 3; ++k) out.point[k] /= mass;
    if (!normalize3(out.normal)) return false;
    for (int a = 0; a < count; ++a) {
        out.weights[a] /= mass;
        for (int k = 0; k < 3; ++k) out.gradient[a][k] /= mass;
    }
    return true;
}

}  // namespace

void BallMix::reserve(int count) {
    if (mix_.size() < kFields * static_cast<size_t>(count)) mix_.resize(kFields * static_cast<size_t>(count));
}

void BallMix::begin(const Collider& collider) {
    count_ = collider.shape.ball_count();
    for (int i = 0; i < count_; ++i) mix_[kFields * static_cast<size_t>(i)] = 0.0;
}

void BallMix::add(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes, int count,
                  double weight) {
    for_each_ball_term(collider, law, x, nodes, count, weight,
                       [&](int i, const ContactPoint& term) { mix_[kFields * static_cast<size_t>(i)] += term.energy; });
}

void BallMix::finish() {
    // In units u_i = P_i / P_max of the largest total, so that the powers stay in range.
    double largest = 0.0;
    for (int i = 0; i < count_; ++i) largest = std::max(largest, mix_[kFields * static_cast<size_t>(i)]);
    double sum_p = 0.0, sum_p1 = 0.0;
    for (int i = 0; i < count_ && largest > 0.0; ++i) {
        const double u = std::max(mix_[kFields * static_cast<size_t>(i)], 0.0) / largest;
        const double power = std::pow(u, kOrder);
        sum_p += power;
        sum_p1 += power * u;
    }
    const double mean = sum_p > 0.0 ? sum_p1 / sum_p : 0.0, p = kOrder;
    for (int i = 0; i < count_; ++i) {
        double* m = &mix_[kFields * static_cast<size_t>(i)];
        const double u = largest > 0.0 ? std::max(m[0], 0.0) / largest : 0.0;
        const double power = u > 0.0 ? std::pow(u, kOrder - 2) : 0.0;  // u^(p-2)
        m[1] = power > 0.0 ? power * u * u / sum_p : 0.0;
        m[2] = power > 0.0 ? power * u * ((p + 1.0) * u - p * mean) / sum_p : 0.0;
        m[3] = power > 0.0 ? p * power * ((p + 1.0) * u - (p - 1.0) * mean) / (sum_p * largest) : 0.0;
        m[4] = power > 0.0 ? p * power * u / (sum_p * largest) : 0.0;
    }
}

bool excess_shape_contact(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes,
                          int count, double weight, const BallMix* mix, ContactPoint& out) {
    if (collider.shape.ball_count() > 1) return mix && mixed_term(collider, law, x, nodes, count, weight, *mix, out);
    bool found = false;
    for_each_ball_term(collider, law, x, nodes, count, weight, [&](int, const ContactPoint& term) {
        out = term;
        found = true;
    });
    return found;
}

void positive_hessian(const ContactPoint& p, double out[9][9]) {
    using Matrix9 = Eigen::Matrix<double, 9, 9>;
    const Eigen::Map<const Eigen::Matrix<double, 9, 9, Eigen::RowMajor>> h(&p.hessian[0][0]);
    const Matrix9 symmetric = 0.5 * (h + h.transpose());
    const Eigen::SelfAdjointEigenSolver<Matrix9> eigen(symmetric);
    const Matrix9 positive =
        eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
    for (int r = 0; r < 9; ++r)
        for (int s = 0; s < 9; ++s) out[r][s] = positive(r, s);
}

void apply_excess_damping(const sh_contact_params& p, const double vrel[3], ContactPoint& out) {
    const double factor = std::max(0.0, 1.0 - 1.5 * p.damping * dot3(out.normal, vrel));
    for (int k = 0; k < 3; ++k) out.relative_velocity[k] = vrel[k];
    out.normal_force *= factor;
    out.net_normal_force *= factor;
    out.stiffness *= factor;
    for (int r = 0; r < 9 && out.has_hessian; ++r)
        for (int s = 0; s < 9; ++s) out.hessian[r][s] *= factor;
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
