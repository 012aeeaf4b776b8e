#include "linalg/node_aggregates.hpp"

namespace sh {
namespace {

constexpr int32_t kFree = -1;

// Node i's neighbours (its row's entries after the diagonal one).
template <class Visit>
void for_each_neighbour(const BlockRows& rows, int32_t i, Visit visit) {
    for (int32_t e = rows.first[static_cast<size_t>(i)] + 1; e < rows.first[static_cast<size_t>(i) + 1]; ++e)
        visit(rows.column[static_cast<size_t>(e)]);
}

// Founds an aggregate of node i and its neighbours (all free); returns the new count.
int32_t found(const BlockRows& rows, int32_t i, int32_t count, vec<int32_t>& aggregate) {
    aggregate[static_cast<size_t>(i)] = count;
    for_each_neighbour(rows, i, [&](int32_t j) {
        if (aggregate[static_cast<size_t>(j)] == kFree) aggregate[static_cast<size_t>(j)] = count;
    });
    return count + 1;
}

}  // namespace

int32_t aggregate_nodes(const BlockRows& rows, vec<int32_t>& aggregate) {
    const int32_t n = rows.node_count();
    aggregate.assign(static_cast<size_t>(n), kFree);
    int32_t count = 0;
    for (int32_t i = 0; i < n; ++i) {
        bool all_free = aggregate[static_cast<size_t>(i)] == kFree;
        for_each_neighbour(rows, i, [&](int32_t j) { all_free = all_free && aggregate[static_cast<size_t>(j)] == kFree; });
        if (all_free) count = found(rows, i, count, aggregate);
    }
    // Joining reads the founders' aggregates only, so that no chain of joins grows one.
    const vec<int32_t> founded = aggregate;
    for (int32_t i = 0; i < n; ++i) {
        if (founded[static_cast<size_t>(i)] != kFree) continue;
        for_each_neighbour(rows, i, [&](int32_t j) {
            if (aggregate[static_cast<size_t>(i)] == kFree) aggregate[static_cast<size_t>(i)] = founded[static_cast<size_t>(j)];
        });
    }
    return count;
}

}  // namespace sh
