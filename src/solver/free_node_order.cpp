#include "solver/free_node_order.hpp"

#include "core/morton.hpp"

namespace sh {

int32_t number_free_nodes(const Body& body, vec<int32_t>& index) {
    const int32_t n = body.node_count();
    vec<int32_t> free_nodes;
    free_nodes.reserve(static_cast<size_t>(n));
    for (int32_t i = 0; i < n; ++i)
        if (body.is_free(i)) free_nodes.push_back(i);
    const vec<uint32_t> order = morton_order(
        free_nodes.size(), [&](size_t k) { return &body.rest[3 * static_cast<size_t>(free_nodes[k])]; });
    index.assign(static_cast<size_t>(n), -1);
    for (size_t k = 0; k < order.size(); ++k) index[static_cast<size_t>(free_nodes[order[k]])] = static_cast<int32_t>(k);
    return static_cast<int32_t>(free_nodes.size());
}

}  // namespace sh
