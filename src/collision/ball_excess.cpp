// The excess of a ball's contact potential over a surface edge or triangle: how far the
// potential exceeds the linear interpolant of the nodes' own potentials, the quantity the
// contact potential's face and edge terms take (contact/shape_contact.cpp).
#include "collision/ball_excess.hpp"

#include "collision/unit_vector.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// The nodes' energies interpolated at weights w (J).
double interpolated_energy(const LocalSimplex& s, const double w[3]) {
    double e = 0.0;
    for (int i = 0; i < s.count; ++i) e += w[i] * s.energy[i];
    return e;
}

// A ball of radius R whose centre lies at distance `height` from a line or plane: along a ray
// in that line or plane from the centre's foot, at offset r the ball's potential falls with
// slope phi(r) = psi'(R - rho) r / rho, rho = sqrt(height^2 + r^2); phi rises from 0 and falls
// back to 0 at the rim. The depth R - rho is taken as ((R - h)(R + h) - r^2) / (R + rho): where
// the ball barely reaches (h near R) the plain difference keeps few of its digits, and a noisy
// phi keeps Newton's steps from settling.
class BellSlope {
public:
    BellSlope(const DepthPotential& psi, double radius, double height)
        : psi_(psi), radius_(radius), height2_(height * height),
          rim2_((radius - std::fabs(height)) * (radius + std::fabs(height))) {}
    /// R^2 - h^2 (m^2): the squared radius of the ball's disc on the line or plane.
    double rim2() const { return rim2_; }
    double operator()(double r) const {
        const double rho = std::sqrt(height2_ + r * r);
        return rho > 0.0 ? psi_.force(depth(r, rho)) * r / rho : 0.0;
    }
    /// phi(r) and dphi/dr = psi' h^2 / rho^3 - psi'' r^2 / rho^2.
    void with_rate(double r, double& value, double& rate) const {
        const double rho = std::sqrt(height2_ + r * r);
        value = rate = 0.0;
        if (!(rho > 0.0)) return;
        double force, stiffness;
        psi_.force_and_stiffness(depth(r, rho), force, stiffness);
        value = force * r / rho;
        rate = (force * height2_ / rho - stiffness * r * r) / (rho * rho);
    }

private:
    double depth(double r, double rho) const { return (rim2_ - r * r) / (radius_ + rho); }

    const DepthPotential& psi_;
    double radius_, height2_, rim2_;
};

// The root of f(r) = phi(r) - slope in [lo, hi], where f(lo) < 0 <= f(hi), to within tolerance:
// Newton's method (quadratic on a smooth phi, with phi' from the law's own stiffness: a few of
// the law's evaluations per crossing) from regula falsi's point, kept in the bracket, which
// every evaluation narrows. It bisects where a Newton step would leave the bracket, where phi
// does not rise, or where a step is not under half the one before the last (a slow approach,
// as near phi's maximum), so that it can never do worse than bisection. Stops when a step
// moves r by at most tolerance, and after 100 steps whatever happens.
double refine_crossing(const BellSlope& phi, double slope, double lo, double f_lo, double hi, double f_hi,
                       double tolerance) {
    double r = hi - f_hi * (hi - lo) / (f_hi - f_lo);
    double last = hi - lo, before_last = hi - lo;  // the last two steps' lengths
    for (int it = 0; it < 100; ++it) {
        if (!(r > lo && r < hi)) r = 0.5 * (lo + hi);
        if (!(r > lo && r < hi)) break;  // the bracket is at round-off
        double value, rate;
        phi.with_rate(r, value, rate);
        const double f = value - slope;
        if (f == 0.0) return r;
        if (f > 0.0) hi = r;
        else lo = r;
        if (!(hi - lo > tolerance)) break;
        double step = rate > 0.0 ? -f / rate : INFINITY;
        if (std::fabs(step) <= tolerance) return r + step;
        const bool newton = std::fabs(step) <= 0.5 * before_last && r + step > lo && r + step < hi;
        if (!newton) step = 0.5 * (lo + hi) - r;
        before_last = last;
        last = std::fabs(step);
        r += step;
    }
    return 0.5 * (lo + hi);
}

// The first r where phi reaches `slope` is where the potential minus a linear interpolant of
// that slope stops rising: the local maximum. Returns -1 if phi stays below slope. The first
// crossing is bracketed on a scan of the rim radius, then refined to round-off.
double first_crossing(const DepthPotential& psi, double radius, double height, double slope) {
    const BellSlope phi(psi, radius, height);
    if (!(phi.rim2() > 0.0)) return -1.0;
    if (!(slope > 0.0)) return 0.0;
    const double rim = std::sqrt(phi.rim2());
    constexpr int kScan = 16;
    double lo = 0.0, hi = -1.0, f_lo = -slope, f_hi = 0.0;  // phi(0) = 0
    for (int k = 1; k <= kScan; ++k) {
        const double r = rim * k / kScan, f = phi(r) - slope;
        if (f >= 0.0) {
            hi = r, f_hi = f;
            break;
        }
        lo = r, f_lo = f;
    }
    if (hi < 0.0) return -1.0;
    return refine_crossing(phi, slope, lo, f_lo, hi, f_hi, 1e-15 * rim);
}

// Fills candidate c at local point x with weights w against a ball (centre, radius).
void ball_candidate(const LocalSimplex& s, const DepthPotential& psi, const double centre[3], double radius,
                    const double x[3], const double w[3], LocalExcess& best) {
    double d[3];
    sub3(x, centre, d);
    const double rho = norm3(d);
    const double depth = radius - rho;
    if (!(depth > 0.0)) return;
    const double value = psi.energy(depth) - interpolated_energy(s, w);
    if (!(value > best.value)) return;
    best.value = value;
    best.depth = depth;
    const double force = psi.force(depth);
    for (int k = 0; k < 3; ++k) {
        best.w[k] = w[k];
        best.x[k] = x[k];
        // At the centre any direction pushes out: the local z.
        best.n[k] = rho > 0.0 ? d[k] / rho : (k == 2 ? 1.0 : 0.0);
        best.push[k] = force * best.n[k];
    }
}

// Along the segment from node i to node j: its local maximum (the potential is a bell around
// the centre's foot, the interpolant a line) and its ends.
void ball_on_segment(const LocalSimplex& s, const DepthPotential& psi, const double centre[3], double radius, int i,
                     int j, LocalExcess& best) {
    const double *a = s.p[i], *b = s.p[j];
    double e[3], ac[3];
    sub3(b, a, e);
    sub3(centre, a, ac);
    const double len = norm3(e);
    for (const int end : {i, j}) {
        double w[3] = {0.0, 0.0, 0.0};
        w[end] = 1.0;
        ball_candidate(s, psi, centre, radius, s.p[end], w, best);
    }
    if (!(len > 0.0)) return;
    const double foot = dot3(ac, e) / len;
    const double height = std::sqrt(std::max(dot3(ac, ac) - foot * foot, 0.0));
    const double slope = (s.energy[j] - s.energy[i]) / len;
    const double r = first_crossing(psi, radius, height, std::fabs(slope));
    if (r < 0.0) return;
    const double t = foot - (slope > 0.0 ? r : -r);
    if (!(t > 0.0 && t < len)) return;
    const double u = t / len;
    double w[3] = {0.0, 0.0, 0.0}, x[3];
    w[i] = 1.0 - u;
    w[j] = u;
    for (int k = 0; k < 3; ++k) x[k] = a[k] + u * e[k];
    ball_candidate(s, psi, centre, radius, x, w, best);
}

// The triangle's interior local maximum: on the ray from the centre's foot against the
// in-plane gradient g of the interpolant, where the bell's slope reaches |g|.
void ball_inside_triangle(const LocalSimplex& s, const DepthPotential& psi, const double centre[3], double radius,
                          LocalExcess& best) {
    double e1[3], e2[3], normal[3];
    sub3(s.p[1], s.p[0], e1);
    sub3(s.p[2], s.p[0], e2);
    const double g11 = dot3(e1, e1), g12 = dot3(e1, e2), g22 = dot3(e2, e2);
    const double det = g11 * g22 - g12 * g12;
    if (!(det > 1e-14 * g11 * g22)) return;  // degenerate: its edges decide
    const double d1 = s.energy[1] - s.energy[0], d2 = s.energy[2] - s.energy[0];
    const double a1 = (g22 * d1 - g12 * d2) / det, a2 = (g11 * d2 - g12 * d1) / det;
    double g[3];
    for (int k = 0; k < 3; ++k) g[k] = a1 * e1[k] + a2 * e2[k];
    const double slope = norm3(g);
    cross3(e1, e2, normal);
    const double nl = norm3(normal);
    double r0[3];
    sub3(centre, s.p[0], r0);
    const double height = dot3(r0, normal) / nl;
    const double r = first_crossing(psi, radius, height, slope);
    if (r < 0.0) return;
    double x[3];
    for (int k = 0; k < 3; ++k) x[k] = centre[k] - height * normal[k] / nl - (slope > 0.0 ? r * g[k] / slope : 0.0);
    sub3(x, s.p[0], r0);
    const double b1 = dot3(e1, r0), b2 = dot3(e2, r0);
    const double u = (g22 * b1 - g12 * b2) / det, v = (g11 * b2 - g12 * b1) / det;
    if (!(u >= 0.0 && v >= 0.0 && u + v <= 1.0)) return;
    const double w[3] = {1.0 - u - v, u, v};
    ball_candidate(s, psi, centre, radius, x, w, best);
}

}  // namespace

LocalExcess ball_excess(const LocalSimplex& s, const DepthPotential& psi, const double centre[3], double radius) {
    LocalExcess best;
    if (s.count == 3) ball_inside_triangle(s, psi, centre, radius, best);
    for (int i = 0; i < s.count; ++i) {
        if (s.count == 2 && i == 1) break;
        ball_on_segment(s, psi, centre, radius, i, (i + 1) % s.count, best);
    }
    return best;
}

double ball_depth(const double centre[3], double radius, const Pose& pose, const double x[3], double normal[3]) {
    sub3(x, centre, normal);
    const double dist = norm3(normal);
    if (!(dist > 1e-12 * radius && normalize3(normal))) {  // at the centre: any direction
        const double ex[3] = {1.0, 0.0, 0.0};
        pose.rotate(ex, normal);
    }
    return radius - dist;
}

}  // namespace sh
