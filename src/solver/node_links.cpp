#include "solver/node_links.hpp"

#include <algorithm>
#include <iterator>
#include <utility>

namespace sh {

uint64_t node_link_key(int32_t i, int32_t j) {
    if (i > j) std::swap(i, j);
    return (static_cast<uint64_t>(static_cast<uint32_t>(i)) << 32) | static_cast<uint32_t>(j);
}

void collect_link_keys(const vec<int32_t>& pairs, vec<uint64_t>& keys) {
    keys.clear();
    for (size_t p = 0; p + 1 < pairs.size(); p += 2) keys.push_back(node_link_key(pairs[p], pairs[p + 1]));
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

void link_key_pairs(const vec<uint64_t>& keys, vec<int32_t>& pairs) {
    pairs.clear();
    for (const uint64_t key : keys) {
        pairs.push_back(static_cast<int32_t>(key >> 32));
        pairs.push_back(static_cast<int32_t>(key & 0xffffffffu));
    }
}

bool links_to_build(const vec<uint64_t>& kept, const vec<uint64_t>& needed, bool rebuild, vec<uint64_t>& out) {
    if (!rebuild && std::includes(kept.begin(), kept.end(), needed.begin(), needed.end())) return false;
    out.clear();
    if (!rebuild) std::set_union(kept.begin(), kept.end(), needed.begin(), needed.end(), std::back_inserter(out));
    if (rebuild || out.size() > 2 * needed.size() + 64) out = needed;
    return true;
}

}  // namespace sh
