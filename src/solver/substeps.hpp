// Sub-steps: how many equal sub-steps a step is split into so that none is longer than what is
// allowed, and the caps on that count. Every place that sub-steps (explicit bodies, a world's
// contact sub-steps, implicit retries, the haptic step) counts with substep_count and its cap.
#pragma once

#include <cmath>
#include <cstdint>

namespace sh {

/// Most sub-steps of an explicit body's step: more means its critical step is unreasonably
/// small for dt, so the step is rejected instead.
constexpr int32_t kMaxExplicitSubsteps = 1 << 20;

/// Most contact sub-steps of a world step: bounds a step's detection passes when a tool jumps
/// far (the tool then moves farther than half its inner radius per sub-step).
constexpr int32_t kMaxContactSubsteps = 1024;

/// Most sub-steps of one haptic step: what fits the device rate's time budget; beyond, the step
/// takes this many and its runaway check decides.
constexpr int32_t kMaxHapticSubsteps = 64;

// An implicit body's failed step is retried in 2, 4, ... sub-steps up to its settings'
// implicit.max_substeps (the host's cap: how much time it gives one step), counted here too.

/// How many equal sub-steps to take, and whether the cap clamped it.
struct SubstepCount {
    int32_t count;  ///< sub-steps to take (the cap if clamped)
    bool clamped;   ///< more than the cap were needed: the sub-steps are longer than longest
};

/// Splits a step of length dt into the fewest equal sub-steps no longer than longest, at most
/// cap of them. A step that fits (dt <= longest, or either is NaN) is one sub-step; a longest
/// of 0 needs infinitely many, so the cap, clamped. dt and longest are in one unit (seconds,
/// or a distance for a tool's travel).
inline SubstepCount substep_count(double dt, double longest, int32_t cap) {
    if (!(dt > longest)) return {1, false};
    const double needed = std::ceil(dt / longest);
    if (!(needed <= cap)) return {cap, true};
    return {static_cast<int32_t>(needed), false};
}

}  // namespace sh
