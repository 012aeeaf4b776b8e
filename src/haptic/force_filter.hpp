// ForceFilter: the force-output contract of the haptic step. Whatever the buffer computes, the
// device gets a finite force of at most max_force that changes by at most max_force_rate * dt
// per step, ramps in on engagement, and holds then ramps out while the data is stale or faulty.
#pragma once

#include <cstdint>

namespace sh {

/// Limits of the force output (SI units).
struct ForceLimits {
    double max_force = 10.0;        ///< N
    double max_force_rate = 2000.0; ///< N/s
    double ramp_time = 0.05;        ///< s, 0: no ramps
};

/// Shapes the raw wrench into the rendered one, step by step. Allocation-free.
class ForceFilter {
public:
    explicit ForceFilter(const ForceLimits& limits) : limits_(limits) {}

    /// One step of dt (s): healthy raw force (N) and torque (N m) are followed, ramped in after
    /// engagement; when not healthy (or the raw wrench is not finite) the last healthy wrench is
    /// held while the gain ramps out. Writes the rendered wrench; returns SH_WARN bits
    /// (SH_WARN_FORCE_CLAMPED when the magnitude or the rate was clamped).
    uint32_t update(const double raw_force[3], const double raw_torque[3], bool healthy, double dt,
                    double force[3], double torque[3]);

    /// Engagement gain in [0, 1].
    double gain() const { return gain_; }

private:
    ForceLimits limits_;
    double gain_ = 0.0;
    double held_force_[3] = {}, held_torque_[3] = {};
    double force_[3] = {};  ///< the last rendered force
};

}  // namespace sh
