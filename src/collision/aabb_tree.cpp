#include "collision/aabb_tree.hpp"

#include <algorithm>

namespace sh {

void AabbTree::build(const Aabb* boxes, int32_t count) {
    vec<int32_t> order(static_cast<size_t>(std::max(count, 0)));
    for (int32_t i = 0; i < count; ++i) order[static_cast<size_t>(i)] = i;
    vec<double> centre(3 * order.size());
    for (int32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k)
            centre[3 * static_cast<size_t>(i) + k] = 0.5 * (boxes[i].lo[k] + boxes[i].hi[k]);
    vec<Node> nodes;
    nodes.reserve(order.empty() ? 0 : 2 * order.size() / kLeafSize + 2);
    if (count > 0) {
        // Each work item: node index and its primitive range [begin, end).
        struct Range {
            int32_t node, begin, end;
        };
        vec<Range> work;
        nodes.push_back(Node{});
        work.push_back({0, 0, count});
        while (!work.empty()) {
            const Range r = work.back();
            work.pop_back();
            Aabb box, centres;
            for (int32_t k = r.begin; k < r.end; ++k) {
                const int32_t i = order[static_cast<size_t>(k)];
                box.add(boxes[i]);
                centres.add(&centre[3 * static_cast<size_t>(i)]);
            }
            nodes[static_cast<size_t>(r.node)].box = box;
            if (r.end - r.begin <= kLeafSize) {
                nodes[static_cast<size_t>(r.node)].first = r.begin;
                nodes[static_cast<size_t>(r.node)].count = r.end - r.begin;
                continue;
            }
            int axis = 0;
            for (int k = 1; k < 3; ++k)
                if (centres.hi[k] - centres.lo[k] > centres.hi[axis] - centres.lo[axis]) axis = k;
            const int32_t mid = r.begin + (r.end - r.begin) / 2;
            std::nth_element(order.begin() + r.begin, order.begin() + mid, order.begin() + r.end,
                             [&](int32_t a, int32_t b) {
                                 return centre[3 * static_cast<size_t>(a) + axis] < centre[3 * static_cast<size_t>(b) + axis];
                             });
            const int32_t left = static_cast<int32_t>(nodes.size());
            nodes.push_back(Node{});
            nodes.push_back(Node{});
            nodes[static_cast<size_t>(r.node)].first = left;
            nodes[static_cast<size_t>(r.node)].count = 0;
            work.push_back({left, r.begin, mid});
            work.push_back({left + 1, mid, r.end});
        }
    }
    nodes_.swap(nodes);
    order_.swap(order);
}

void AabbTree::refit(const Aabb* boxes) {
    // Children come after their parents, so a backward sweep sees children first.
    for (size_t n = nodes_.size(); n-- > 0;) {
        Node& node = nodes_[n];
        Aabb box;
        if (node.count > 0) {
            for (int32_t k = 0; k < node.count; ++k) box.add(boxes[order_[static_cast<size_t>(node.first + k)]]);
        } else {
            box = nodes_[static_cast<size_t>(node.first)].box;
            box.add(nodes_[static_cast<size_t>(node.first) + 1].box);
        }
        node.box = box;
    }
}

}  // namespace sh
