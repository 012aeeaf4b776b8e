// Element data of kLanes tets stored lane-wise, so one kernel pass handles kLanes tets with
// SIMD arithmetic and no per-element branch or virtual call.
#pragma once

#include "material/lanes.hpp"

#include <cstdint>

namespace sh {

/// kLanes tets of one material model. Unused lanes have zero volume (no force, no energy).
struct TetBlock {
    Mat3L Bm;                   ///< inverse rest shape matrix Dm^-1 (1/m)
    Lanes volume;               ///< rest volume V0 (m^3)
    Lanes lambda;               ///< Lame lambda (Pa)
    Lanes mu;                   ///< Lame mu (Pa)
    int32_t node[4][kLanes];    ///< node indices
};

}  // namespace sh
