// The tets whose bounding box meets a box: what a cut, or a blade mapped to the rest shape,
// needs to look at instead of every tet.
#pragma once

#include "core/memory.hpp"

#include <cstdint>

namespace sh {

/// Calls visit(t) for each tet t of tets[0..4 count) (node indices into x, 3 doubles per node,
/// node_count nodes) whose box meets the box [lo, hi]. A tet misses it exactly when all its
/// corners lie beyond one of the box's six planes: one bit per plane and node, ANDed over
/// the corners, so it costs a pass over the nodes and one over the tets' corners, not the
/// tets' own boxes. Allocates a byte per node.
template <class Visit>
void for_each_tet_in_box(const double* x, int32_t node_count, const int32_t* tets, int32_t count, const double lo[3],
                         const double hi[3], Visit&& visit) {
    vec<uint8_t> beyond(static_cast<size_t>(node_count));
    for (int32_t n = 0; n < node_count; ++n) {
        const double* p = x + 3 * static_cast<size_t>(n);
        uint8_t bits = 0;
        for (int k = 0; k < 3; ++k)
            bits |= static_cast<uint8_t>((p[k] < lo[k] ? 1 : 0) << k | (p[k] > hi[k] ? 1 : 0) << (k + 3));
        beyond[static_cast<size_t>(n)] = bits;
    }
    for (int32_t t = 0; t < count; ++t) {
        const int32_t* tet = tets + 4 * static_cast<size_t>(t);
        if ((beyond[static_cast<size_t>(tet[0])] & beyond[static_cast<size_t>(tet[1])] & beyond[static_cast<size_t>(tet[2])] &
             beyond[static_cast<size_t>(tet[3])]) == 0)
            visit(t);
    }
}

}  // namespace sh
