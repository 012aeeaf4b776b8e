// The rotations a FEM body's corotational elements had at its last force or energy pass, per
// kernel block: the next pass's warm start (polar_rotation_near). Between the passes of a step
// (Newton's residual, tangent and line search; an explicit step's sub-steps) an element turns
// little, and one or two updates from its last rotation replace the five to eight polar
// iterations from F alone.
#pragma once

#include "core/memory.hpp"
#include "model/fem_kernel.hpp"

#include <softhap/softhap.h>

#include <cstddef>
#include <cstdint>

namespace sh {

/// Blocks per material model that keep a rotation (0 for a law that keeps none).
using RotatingBlocks = size_t[SH_MATERIAL_COUNT];

class BlockRotations {
public:
    /// Room for counts' rotations; throws std::bad_alloc, changing nothing else.
    void reserve(const RotatingBlocks& counts) {
        for (int m = 0; m < SH_MATERIAL_COUNT; ++m) reserve_growing(rotations_[m], counts[m]);
    }
    /// Sizes them for counts (after reserve: allocation-free). After blocks were rebuilt
    /// (keep false) they are forgotten; after blocks were appended (keep true) the old ones
    /// stay, and the new ones start as zero, from which the first pass finds no rotation and
    /// falls back to F alone (polar_rotation_near's guard), as it does for a lane a cut
    /// emptied and refilled with another tet.
    void fit(const RotatingBlocks& counts, bool keep) noexcept {
        for (int m = 0; m < SH_MATERIAL_COUNT; ++m) {
            rotations_[m].resize(counts[m]);
            known_[m] = known_[m] && keep;
        }
    }
    /// For a pass over model's blocks: warm from the last pass's rotations if there was one
    /// since fit, else found from F alone; kept for the next. Nothing for a law without them.
    KeptRotations pass(int model) {
        vec<Mat3L>& kept = rotations_[model];
        if (kept.empty()) return KeptRotations{};
        const bool warm = known_[model];
        known_[model] = true;
        return KeptRotations{warm ? kept.data() : nullptr, kept.data()};
    }
    /// The last pass's rotations of model's blocks (one Mat3L per block), or null if there was
    /// no pass since fit or its law keeps none.
    const Mat3L* last(int model) const { return known_[model] && !rotations_[model].empty() ? rotations_[model].data() : nullptr; }
private:
    vec<Mat3L> rotations_[SH_MATERIAL_COUNT];
    bool known_[SH_MATERIAL_COUNT] = {};
};

}  // namespace sh
