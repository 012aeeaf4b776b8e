#include "haptic/force_filter.hpp"

#include <softhap/softhap.h>

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

double norm(const double a[3]) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

bool finite(const double a[3]) { return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]); }

}  // namespace

uint32_t ForceFilter::update(const double raw_force[3], const double raw_torque[3], bool healthy, double dt,
                             double force[3], double torque[3]) {
    uint32_t warnings = 0;
    healthy = healthy && finite(raw_force) && finite(raw_torque);
    if (healthy)
        for (int k = 0; k < 3; ++k) {
            held_force_[k] = raw_force[k];
            held_torque_[k] = raw_torque[k];
        }
    const double ramp = limits_.ramp_time > 0.0 ? dt / limits_.ramp_time : 1.0;
    gain_ = healthy ? std::min(1.0, gain_ + ramp) : std::max(0.0, gain_ - ramp);

    double wanted[3];
    for (int k = 0; k < 3; ++k) wanted[k] = gain_ * held_force_[k];
    const double magnitude = norm(wanted);
    double scale = gain_;  // of the held torque, to follow the force's clamps
    if (magnitude > limits_.max_force) {
        const double s = limits_.max_force / magnitude;
        for (double& w : wanted) w *= s;
        scale *= s;
        warnings |= 1u << SH_WARN_FORCE_CLAMPED;
    }
    double change[3];
    for (int k = 0; k < 3; ++k) change[k] = wanted[k] - force_[k];
    const double largest = limits_.max_force_rate * dt, moved = norm(change);
    if (moved > largest) {
        const double s = largest / moved;
        for (double& c : change) c *= s;
        warnings |= 1u << SH_WARN_FORCE_CLAMPED;
    }
    for (int k = 0; k < 3; ++k) force_[k] += change[k];
    // The torque shrinks with the force when the rate limit holds the force back.
    const double wanted_norm = norm(wanted);
    if (wanted_norm > 0.0) scale *= std::min(1.0, norm(force_) / wanted_norm);
    for (int k = 0; k < 3; ++k) {
        force[k] = force_[k];
        torque[k] = scale * held_torque_[k];
    }
    return warnings;
}

}  // namespace sh
