// Element data of kLanes tets stored lane-wise, so one kernel pass handles kLanes tets with
// SIMD arithmetic and no per-element branch or virtual call.
#pragma once

#include "material/lanes.hpp"

#include <cstdint>

namespace sh {

/// kLanes tets of one material model (832 bytes: 104 per tet, streamed once per force pass).
/// The Lame parameters are stored pre-multiplied by -V0: every material law is homogeneous of
/// degree one in (lambda, mu), so the kernels get the nodal-force matrix -V0 P(F) Bm^T and the
/// energy -V0 psi(F) without multiplying by the volume. Unused lanes repeat a real tet of the
/// block with zero weights: finite, and no force and no energy.
struct TetBlock {
    Mat3L Bm;                   ///< inverse rest shape matrix Dm^-1 (1/m)
    Lanes lambda_w;             ///< -V0 lambda (J): Lame lambda times minus the rest volume
    Lanes mu_w;                 ///< -V0 mu (J): Lame mu times minus the rest volume
    int32_t node[4][kLanes];    ///< node indices
};

}  // namespace sh
