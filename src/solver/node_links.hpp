// Node links: the node pairs a Newton matrix's pattern holds blocks for beyond its elements'
// (the coupling of a contact across bodies or across faces), kept from solve to solve and grown
// as contacts come and go, so that the pattern and its symbolic analysis are rebuilt only when a
// contact needs a block they lack.
#pragma once

#include "core/memory.hpp"

#include <cstdint>

namespace sh {

/// The key of the node pair {i, j}: (min << 32) | max.
uint64_t node_link_key(int32_t i, int32_t j);

/// keys := the sorted, distinct keys of pairs (two node indices each).
void collect_link_keys(const vec<int32_t>& pairs, vec<uint64_t>& keys);

/// pairs := the node pairs of keys, two node indices each.
void link_key_pairs(const vec<uint64_t>& keys, vec<int32_t>& pairs);

/// The links a pattern is to be rebuilt with, or false if the pattern built with kept serves:
/// it holds every needed link and nothing else forces a rebuild. Otherwise out gets kept and
/// needed together (earlier contacts' links stay for when they come back), or needed alone if
/// rebuild or if kept has grown beyond twice what needed asks plus 64.
bool links_to_build(const vec<uint64_t>& kept, const vec<uint64_t>& needed, bool rebuild, vec<uint64_t>& out);

}  // namespace sh
