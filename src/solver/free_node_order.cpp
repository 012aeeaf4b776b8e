#include "solver/free_node_order.hpp"

#include "core/morton.hpp"

#include <algorithm>
#include <utility>

namespace sh {

int32_t number_free_nodes(const Body& body, vec<int32_t>& index) {
    const int32_t n = body.node_count();
    MortonBox box;
    for (int32_t i = 0; i < n; ++i)
        if (body.is_free(i)) box.include(&body.rest[3 * static_cast<size_t>(i)]);
    vec<std::pair<uint64_t, int32_t>> keyed;
    keyed.reserve(static_cast<size_t>(n));
    for (int32_t i = 0; i < n; ++i)
        if (body.is_free(i)) keyed.emplace_back(box.key(&body.rest[3 * static_cast<size_t>(i)]), i);
    std::sort(keyed.begin(), keyed.end());
    index.assign(static_cast<size_t>(n), -1);
    for (size_t k = 0; k < keyed.size(); ++k) index[static_cast<size_t>(keyed[k].second)] = static_cast<int32_t>(k);
    return static_cast<int32_t>(keyed.size());
}

}  // namespace sh
