// Element data of kLanes tets stored lane-wise, so one kernel pass handles kLanes tets with
// SIMD arithmetic and no per-element branch or virtual call.
#pragma once

#include "material/lanes.hpp"

#include <cstddef>
#include <cstdint>

namespace sh {

/// kLanes tets of one material model (104 bytes per tet, streamed once per force pass).
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

/// Blocks needed for count tets.
inline size_t block_count(size_t count) { return (count + kLanes - 1) / kLanes; }

/// Spreads the count tets of members over block_count(count) blocks: lane l of block k takes
/// the (l * nb + k)-th member. Each lane walks its own stretch of members (ordered for
/// locality), so consecutive blocks reuse the previous block's nodes lane by lane, while the
/// kLanes tets of one block lie far apart and rarely share a node: the force scatter's node
/// updates within a block are then independent. Calls fill(tet, used, block, lane) for every
/// lane; an unused lane (used false) repeats its block's lane-0 tet, to be given zero weight.
template <class Index, class Fill>
void spread_over_lanes(const Index* members, size_t count, Fill&& fill) {
    const size_t nb = block_count(count);
    for (size_t k = 0; k < nb; ++k)
        for (int l = 0; l < kLanes; ++l) {
            const size_t slot = static_cast<size_t>(l) * nb + k;
            const bool used = slot < count;
            fill(members[used ? slot : k], used, k, l);
        }
}

}  // namespace sh
