// Z-order (Morton) curve keys of points in a box: points close in space get close keys, so
// sorting by key gives an order with locality (elements for the kernels' caches, free nodes
// for the Newton matrix's columns) whatever order a file listed them in.
#pragma once

#include "core/memory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

namespace sh {

/// The bounding box the keys are taken in; each axis is cut into 2^21 cells over its extent.
struct MortonBox {
    double lo[3] = {INFINITY, INFINITY, INFINITY};
    double hi[3] = {-INFINITY, -INFINITY, -INFINITY};

    /// Grows the box to hold p (3 values).
    void include(const double* p) {
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    }
    /// p's key: its cell's coordinates interleaved bit by bit (x lowest); points outside the
    /// box or not finite go to its nearest face.
    uint64_t key(const double* p) const {
        uint64_t key = 0;
        for (int a = 0; a < 3; ++a) {
            const double extent = hi[a] - lo[a];
            const double u = extent > 0.0 ? (p[a] - lo[a]) / extent : 0.0;
            const uint64_t q = u >= 0.0 ? static_cast<uint64_t>(std::min(u, 1.0) * 2097151.0) : 0;  // NaN: 0
            key |= spread_bits(q) << a;
        }
        return key;
    }

private:
    // The low 21 bits of v spread to every third bit.
    static uint64_t spread_bits(uint64_t v) {
        v &= 0x1fffff;
        v = (v | v << 32) & 0x1f00000000ffffULL;
        v = (v | v << 16) & 0x1f0000ff0000ffULL;
        v = (v | v << 8) & 0x100f00f00f00f00fULL;
        v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
        v = (v | v << 2) & 0x1249249249249249ULL;
        return v;
    }
};

/// 0 .. count - 1 sorted along the Z-order curve through the box of the points point(k) (each
/// 3 values), ties by k. Allocates.
template <class Point>
vec<uint32_t> morton_order(size_t count, const Point& point) {
    MortonBox box;
    for (size_t k = 0; k < count; ++k) box.include(point(k));
    vec<std::pair<uint64_t, uint32_t>> keyed(count);
    for (size_t k = 0; k < count; ++k) keyed[k] = {box.key(point(k)), static_cast<uint32_t>(k)};
    std::sort(keyed.begin(), keyed.end());
    vec<uint32_t> order(count);
    for (size_t k = 0; k < count; ++k) order[k] = keyed[k].second;
    return order;
}

}  // namespace sh
