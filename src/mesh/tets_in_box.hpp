// The tets whose bounding box meets a box: what a cut, or a blade mapped to the rest shape,
// needs to look at instead of every tet.
#pragma once

#include "core/memory.hpp"

#include <algorithm>
#include <cstdint>

namespace sh {

/// Calls visit(t, first, hits) for each tet t of tets[0..4 count) (node indices into x, 3
/// doubles per node, node_count nodes) whose box meets at least one of the box_count boxes
/// (6 doubles each: lo then hi), taken 8 at a time: bit i of hits is set when it meets box
/// first + i. A tet misses a box exactly when all its corners lie beyond one of the box's six
/// planes: one bit per plane and node, ANDed over the corners, a byte per box, so a group of
/// boxes costs one pass over the nodes and one over the tets' corners, not the tets' own
/// boxes. Allocates 8 bytes per node.
template <class Visit>
void for_each_tet_in_boxes(const double* x, int32_t node_count, const int32_t* tets, int32_t count, const double* boxes,
                           int box_count, Visit&& visit) {
    constexpr uint64_t kOnes = 0x0101010101010101ull, kHighs = 0x8080808080808080ull;
    vec<uint64_t> beyond(static_cast<size_t>(node_count));
    for (int first = 0; first < box_count; first += 8) {
        const int group = std::min(8, box_count - first);
        for (int32_t n = 0; n < node_count; ++n) {
            const double* p = x + 3 * static_cast<size_t>(n);
            uint64_t bits = ~0ull;  // the bytes of boxes past the group: beyond every plane
            for (int i = 0; i < group; ++i) {
                const double* lo = boxes + 6 * static_cast<size_t>(first + i);
                const double* hi = lo + 3;
                uint64_t byte = 0;
                for (int k = 0; k < 3; ++k) byte |= static_cast<uint64_t>((p[k] < lo[k] ? 1 : 0) << k | (p[k] > hi[k] ? 1 : 0) << (k + 3));
                bits &= ~(0xffull << (8 * i));
                bits |= byte << (8 * i);
            }
            beyond[static_cast<size_t>(n)] = bits;
        }
        for (int32_t t = 0; t < count; ++t) {
            const int32_t* tet = tets + 4 * static_cast<size_t>(t);
            const uint64_t all = beyond[static_cast<size_t>(tet[0])] & beyond[static_cast<size_t>(tet[1])] &
                                 beyond[static_cast<size_t>(tet[2])] & beyond[static_cast<size_t>(tet[3])];
            if (((all - kOnes) & ~all & kHighs) == 0) continue;  // no byte is zero: no box met
            uint32_t hits = 0;
            for (int i = 0; i < group; ++i) hits |= ((all >> (8 * i)) & 0xff) == 0 ? 1u << i : 0u;
            visit(t, first, hits);
        }
    }
}

/// Calls visit(t) for each tet t of tets[0..4 count) whose box meets the box [lo, hi]
/// (for_each_tet_in_boxes with one box).
template <class Visit>
void for_each_tet_in_box(const double* x, int32_t node_count, const int32_t* tets, int32_t count, const double lo[3],
                         const double hi[3], Visit&& visit) {
    const double box[6] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
    for_each_tet_in_boxes(x, node_count, tets, count, box, 1, [&](int32_t t, int, uint32_t) { visit(t); });
}

}  // namespace sh
