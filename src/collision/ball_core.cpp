// The segment of balls a shape's contact takes between nodes: spacing, lookup, and the
// inscribed capsule of a box or convex hull.
#include "collision/ball_core.hpp"

#include "collision/shape_geometry.hpp"
#include "core/vec3.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

constexpr int kDepthSamples = 128;  // along the axis, for the depth profile's peak and plateau
constexpr int kTrialRadii = 16;     // radii tried, fractions of the deepest point's depth
constexpr int kBisections = 48;     // to round-off of the axis's extent

// The points' mean and the unit direction of their largest spread.
void principal_axis(const double* points, int count, double mean[3], double axis[3]) {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (int i = 0; i < count; ++i) m += Eigen::Vector3d(points + 3 * i);
    m /= count;
    Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
    for (int i = 0; i < count; ++i) {
        const Eigen::Vector3d d = Eigen::Vector3d(points + 3 * i) - m;
        spread += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(spread);
    const Eigen::Vector3d a = eigen.eigenvectors().col(2);  // eigenvalues ascend
    for (int k = 0; k < 3; ++k) {
        mean[k] = m[k];
        axis[k] = a[k];
    }
}

// The shape's depth (m, 0 outside) along the line mean + t axis of its local frame.
struct DepthProfile {
    const double* mean;
    const double* axis;
    PenetrateFn penetrate;
    const ShapeGeometry& g;

    double operator()(double t) const {
        const double x[3] = {mean[0] + t * axis[0], mean[1] + t * axis[1], mean[2] + t * axis[2]};
        double depth = 0.0, normal[3];
        return penetrate(g, Pose{}, x, depth, normal) ? depth : 0.0;
    }

    // Where the profile (concave) crosses level between t_out (below it) and t_in (at or above
    // it): the crossing's inner side, to round-off.
    double crossing(double level, double t_out, double t_in) const {
        for (int i = 0; i < kBisections; ++i) {
            const double t = 0.5 * (t_out + t_in);
            ((*this)(t) >= level ? t_in : t_out) = t;
        }
        return t_in;
    }
};

}  // namespace

void set_ball_core(BallCore& core, const double centre[3], const double axis[3], double half_length, double radius) {
    for (int k = 0; k < 3; ++k) {
        core.centre[k] = centre[k];
        core.axis[k] = axis[k];
    }
    // A segment within round-off of a point (a cube's inscribed capsule) is one ball.
    core.half_length = half_length > 1e-9 * radius ? half_length : 0.0;
    core.radius = radius;
    core.count = 1 + static_cast<int>(std::ceil(4.0 * core.half_length / radius));
}

void inscribe_ball_core(BallCore& core, const double* points, int count, PenetrateFn penetrate, const ShapeGeometry& g) {
    core = BallCore{};
    double mean[3], axis[3];
    principal_axis(points, count, mean, axis);
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < count; ++i) {
        double d[3];
        sub3(points + 3 * i, mean, d);
        lo = std::min(lo, dot3(d, axis));
        hi = std::max(hi, dot3(d, axis));
    }
    const DepthProfile profile{mean, axis, penetrate, g};
    double t[kDepthSamples + 1], m[kDepthSamples + 1], deepest = 0.0;
    for (int i = 0; i <= kDepthSamples; ++i) {
        t[i] = lo + (hi - lo) * i / kDepthSamples;
        m[i] = profile(t[i]);
        deepest = std::max(deepest, m[i]);
    }
    if (!(deepest > 0.0)) return;
    // Each trial radius r keeps the stretch of the axis at least r deep (one interval: the
    // profile is concave); the capsule of largest volume, pi r^2 (length + 4 r / 3), wins.
    double best_volume = 0.0, best_radius = 0.0, best_lo = 0.0, best_hi = 0.0;
    for (int k = 1; k <= kTrialRadii; ++k) {
        const double r = deepest * k / kTrialRadii;
        int first = 0, last = kDepthSamples;
        while (m[first] < r) ++first;
        while (m[last] < r) --last;
        const double t0 = first > 0 ? profile.crossing(r, t[first - 1], t[first]) : t[first];
        const double t1 = last < kDepthSamples ? profile.crossing(r, t[last + 1], t[last]) : t[last];
        const double volume = r * r * (t1 - t0 + 4.0 * r / 3.0);
        if (volume > best_volume) best_volume = volume, best_radius = r, best_lo = t0, best_hi = t1;
    }
    const double half_length = 0.5 * (best_hi - best_lo);
    if (!(half_length <= kMaxCoreHalfLength * best_radius)) return;
    double centre[3];
    for (int k = 0; k < 3; ++k) centre[k] = mean[k] + 0.5 * (best_lo + best_hi) * axis[k];
    set_ball_core(core, centre, axis, half_length, best_radius);
}

void core_balls_near(const ShapeGeometry& g, const double x[3], double reach, int& first, int& last) {
    const BallCore& core = g.balls;
    first = 0;
    last = -1;
    double d[3];
    sub3(x, core.centre, d);
    const double along_axis = dot3(d, core.axis);
    const double across2 = std::max(dot3(d, d) - along_axis * along_axis, 0.0);
    if (core.count == 0 || !(across2 <= reach * reach)) return;
    const double along = std::sqrt(reach * reach - across2);
    const int intervals = core.count - 1;
    if (intervals == 0) {
        last = std::fabs(along_axis) <= along ? 0 : -1;
        return;
    }
    const double spacing = 2.0 * core.half_length / intervals;
    const double ball_lo = std::ceil((along_axis - along + core.half_length) / spacing);
    const double ball_hi = std::floor((along_axis + along + core.half_length) / spacing);
    first = static_cast<int>(std::min(std::max(ball_lo, 0.0), intervals + 1.0));
    last = static_cast<int>(std::min(std::max(ball_hi, -1.0), static_cast<double>(intervals)));
}

void core_ball_centre(const ShapeGeometry& g, int i, double centre[3]) {
    const BallCore& core = g.balls;
    const int intervals = core.count - 1;
    const double along = intervals > 0 ? core.half_length * (2.0 * i - intervals) / intervals : 0.0;
    for (int k = 0; k < 3; ++k) centre[k] = core.centre[k] + along * core.axis[k];
}

}  // namespace sh
