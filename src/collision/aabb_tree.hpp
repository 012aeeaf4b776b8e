// AabbTree: a bounding-volume hierarchy of axis-aligned boxes over a fixed set of primitives
// (surface triangles, tets), refitted in place as they move.
#pragma once

#include "core/memory.hpp"

#include <cmath>
#include <cstdint>

namespace sh {

/// An axis-aligned box.
struct Aabb {
    double lo[3] = {INFINITY, INFINITY, INFINITY};
    double hi[3] = {-INFINITY, -INFINITY, -INFINITY};

    /// Grows the box to hold point p.
    void add(const double p[3]) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::fmin(lo[k], p[k]);
            hi[k] = std::fmax(hi[k], p[k]);
        }
    }
    /// Grows the box to hold b.
    void add(const Aabb& b) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::fmin(lo[k], b.lo[k]);
            hi[k] = std::fmax(hi[k], b.hi[k]);
        }
    }
    /// Grows every side by margin.
    void inflate(double margin) {
        for (int k = 0; k < 3; ++k) {
            lo[k] -= margin;
            hi[k] += margin;
        }
    }
    /// True if the boxes share a point.
    bool overlaps(const Aabb& b) const {
        for (int k = 0; k < 3; ++k)
            if (lo[k] > b.hi[k] || b.lo[k] > hi[k]) return false;
        return true;
    }
    /// Squared distance from p to the box (0 inside).
    double distance2(const double p[3]) const {
        double s = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double d = std::fmax(0.0, std::fmax(lo[k] - p[k], p[k] - hi[k]));
            s += d * d;
        }
        return s;
    }
};

/// A binary tree of boxes over primitives 0..count-1, built by median splits on the longest
/// axis. Leaves hold up to kLeafSize primitives. Queries are allocation-free.
class AabbTree {
public:
    static constexpr int kLeafSize = 4;

    /// Builds the tree over boxes[count]. Allocates.
    void build(const Aabb* boxes, int32_t count);

    /// Updates every node's box for new primitive boxes (same count and order as build).
    void refit(const Aabb* boxes);

    int32_t primitive_count() const { return static_cast<int32_t>(order_.size()); }

    /// Calls visit(i) for every primitive i whose box overlaps query.
    template <class Visit>
    void query(const Aabb& query, Visit&& visit) const {
        descend([&](const Aabb& box) { return box.overlaps(query); }, visit);
    }

    /// Calls visit(i) for each primitive in every leaf whose box passes enter(box), descending
    /// only into nodes whose box passes enter.
    template <class Enter, class Visit>
    void descend(Enter&& enter, Visit&& visit) const {
        if (nodes_.empty()) return;
        int32_t stack[kMaxDepth];
        int depth = 0;
        stack[depth++] = 0;
        while (depth > 0) {
            const Node& node = nodes_[static_cast<size_t>(stack[--depth])];
            if (!enter(node.box)) continue;
            if (node.count > 0) {
                for (int32_t k = 0; k < node.count; ++k) visit(order_[static_cast<size_t>(node.first + k)]);
            } else {
                stack[depth++] = node.first;
                stack[depth++] = node.first + 1;
            }
        }
    }

    /// The primitive nearest to p by distance(i) (which must be >= the distance from p to the
    /// primitive's box), within max_distance; -1 if none. Branch and bound, allocation-free.
    template <class Distance>
    int32_t nearest(const double p[3], double max_distance, Distance&& distance, double& out_distance) const {
        int32_t best = -1;
        double best2 = max_distance * max_distance;
        out_distance = max_distance;
        descend([&](const Aabb& box) { return box.distance2(p) <= best2; },
                [&](int32_t i) {
                    const double d = distance(i);
                    if (d * d < best2) {
                        best2 = d * d;
                        best = i;
                        out_distance = d;
                    }
                });
        return best;
    }

private:
    // Median splits keep the depth at most log2(count / kLeafSize) + 2, far below this.
    static constexpr int kMaxDepth = 128;
    struct Node {
        Aabb box;
        int32_t first = 0;  ///< leaf: first index into order_; inner: index of the left child
        int32_t count = 0;  ///< leaf: primitives (> 0); inner: 0
    };
    vec<Node> nodes_;      ///< root at 0; children after their parent
    vec<int32_t> order_;   ///< primitives in leaf order
};

}  // namespace sh
