#include "cut/refinement.hpp"

#include "collision/closest_point.hpp"
#include "core/vec3.hpp"
#include "cut/edge_split.hpp"
#include "mesh/tet_mesh.hpp"
#include "model/fem_body.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace sh {
namespace {

// The tet's edges: edge e joins corners kTetEdge[e][0] and kTetEdge[e][1].
constexpr int kTetEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

// Each round halves the longest edges near the segments: 8 rounds take an element 16 times
// the target length down to it, far beyond any mesh a cut should be refining.
constexpr int kRounds = 8;

using EdgeKey = std::pair<int32_t, int32_t>;  // (lo, hi)

EdgeKey key_of(const int32_t* tet, int e) {
    const int32_t a = tet[kTetEdge[e][0]], b = tet[kTetEdge[e][1]];
    return {std::min(a, b), std::max(a, b)};
}

double length_of(const vec<double>& rest, const EdgeKey& edge) {
    double d[3];
    sub3(at(rest.data(), edge.second), at(rest.data(), edge.first), d);
    return norm3(d);
}

// The tets being refined, with the rest positions of their nodes.
struct Working {
    Refinement& out;
    vec<double> rest;  // 3 per node, the body's then the new ones

    const int32_t* tet(size_t t) const { return &out.tets[4 * t]; }
    size_t tet_count() const { return out.tets.size() / 4; }

    // The tet's longest edge (the lowest (lo, hi) among equals, so every tet picks alike).
    EdgeKey longest(size_t t) const {
        EdgeKey best{0, 0};
        double best_length = -1.0;
        for (int e = 0; e < 6; ++e) {
            const EdgeKey edge = key_of(tet(t), e);
            const double length = length_of(rest, edge);
            if (length > best_length || (length == best_length && edge < best)) best = edge, best_length = length;
        }
        return best;
    }

    // True if one of the segments passes through the tet (Cyrus-Beck clipping against its four
    // faces' planes).
    bool crossed(size_t t, const double* segments, int32_t segment_count) const {
        const double* r = rest.data();
        for (int32_t s = 0; s < segment_count; ++s) {
            const double* p = &segments[6 * static_cast<size_t>(s)];
            double d[3];
            sub3(p + 3, p, d);
            double enter = 0.0, leave = 1.0;
            for (int f = 0; f < 4 && enter <= leave; ++f) {
                // Face f's outward normal (kTetFaces is counter-clockwise seen from outside).
                const double* a = at(r, tet(t)[kTetFaces[f][0]]);
                double ab[3], ac[3], n[3], ap[3];
                sub3(at(r, tet(t)[kTetFaces[f][1]]), a, ab);
                sub3(at(r, tet(t)[kTetFaces[f][2]]), a, ac);
                cross3(ab, ac, n);
                sub3(p, a, ap);
                const double height = dot3(ap, n), rate = dot3(d, n);  // outside where height + s rate > 0
                if (rate == 0.0) {
                    if (height > 0.0) enter = 2.0;
                } else if (rate < 0.0) {
                    enter = std::max(enter, -height / rate);
                } else {
                    leave = std::min(leave, -height / rate);
                }
            }
            if (enter <= leave) return true;
        }
        return false;
    }

    bool has_marked(size_t t, const vec<EdgeKey>& marked) const {
        for (int e = 0; e < 6; ++e)
            if (std::binary_search(marked.begin(), marked.end(), key_of(tet(t), e))) return true;
        return false;
    }

    // Adds the longest edge of every tet with a marked edge until none is missing, so that
    // every tet split is split along its longest edge first.
    void close(vec<EdgeKey>& marked) const {
        for (bool grew = true; grew;) {
            grew = false;
            vec<EdgeKey> added;
            for (size_t t = 0; t < tet_count(); ++t) {
                if (!has_marked(t, marked)) continue;
                const EdgeKey edge = longest(t);
                if (!std::binary_search(marked.begin(), marked.end(), edge)) added.push_back(edge);
            }
            if (added.empty()) break;
            marked.insert(marked.end(), added.begin(), added.end());
            std::sort(marked.begin(), marked.end());
            marked.erase(std::unique(marked.begin(), marked.end()), marked.end());
            grew = true;
        }
    }

    // Splits every marked edge at its midpoint in every tet that has it, longer edges first.
    void split(const vec<EdgeKey>& marked, int32_t body_node_count) {
        const int32_t first_new = body_node_count + static_cast<int32_t>(out.origins.size());
        vec<std::pair<double, size_t>> order(marked.size());  // (-length, slot): the global order
        for (size_t m = 0; m < marked.size(); ++m) order[m] = {-length_of(rest, marked[m]), m};
        std::sort(order.begin(), order.end());
        vec<size_t> rank(marked.size());
        for (size_t r = 0; r < order.size(); ++r) rank[order[r].second] = r;
        for (const EdgeKey& edge : marked) {
            out.origins.push_back(NodeOrigin{edge.first, edge.second, 0.5});
            for (int k = 0; k < 3; ++k) rest.push_back(0.5 * (at(rest.data(), edge.first)[k] + at(rest.data(), edge.second)[k]));
        }
        vec<std::array<int32_t, 4>> pieces;
        const size_t count = tet_count();
        for (size_t t = 0; t < count; ++t) {
            std::pair<size_t, EdgeSplit> mine[6];
            int n = 0;
            for (int e = 0; e < 6; ++e) {
                const EdgeKey edge = key_of(tet(t), e);
                const auto it = std::lower_bound(marked.begin(), marked.end(), edge);
                if (it == marked.end() || *it != edge) continue;
                const size_t m = static_cast<size_t>(it - marked.begin());
                mine[n++] = {rank[m], EdgeSplit{edge.first, edge.second, first_new + static_cast<int32_t>(m)}};
            }
            if (n == 0) continue;
            for (int k = 1; k < n; ++k)  // at most six: insertion sort by rank
                for (int j = k; j > 0 && mine[j].first < mine[j - 1].first; --j) std::swap(mine[j], mine[j - 1]);
            EdgeSplit splits[6];
            for (int k = 0; k < n; ++k) splits[k] = mine[k].second;
            pieces.clear();
            const std::array<int32_t, 4> whole{tet(t)[0], tet(t)[1], tet(t)[2], tet(t)[3]};
            split_tet(whole.data(), splits, n, pieces);
            add_pieces(t, pieces);
        }
    }

    void add_pieces(size_t t, const vec<std::array<int32_t, 4>>& pieces) {
        const int32_t from = out.source[t] >= 0 ? out.source[t] : -1 - out.source[t];
        for (size_t p = 0; p < pieces.size(); ++p) {
            const size_t slot = p == 0 ? t : tet_count();
            if (p > 0) out.tets.resize(out.tets.size() + 4), out.source.push_back(0);
            std::copy(pieces[p].begin(), pieces[p].end(), &out.tets[4 * slot]);
            out.source[slot] = -1 - from;
        }
    }
};

}  // namespace

Refinement refine_near(const FemBody& body, const double* segments, int32_t segment_count, double edge_length,
                       int32_t max_new_tets) {
    Refinement out;
    out.tets.assign(body.element_nodes(), body.element_nodes() + 4 * static_cast<size_t>(body.element_count()));
    out.source.resize(static_cast<size_t>(body.element_count()));
    for (size_t t = 0; t < out.source.size(); ++t) out.source[t] = static_cast<int32_t>(t);
    Working w{out, body.rest};
    const size_t limit = static_cast<size_t>(body.element_count()) + static_cast<size_t>(std::max(max_new_tets, 0));
    for (int round = 0; round < kRounds; ++round) {
        vec<EdgeKey> marked;
        for (size_t t = 0; t < w.tet_count(); ++t) {
            const EdgeKey edge = w.longest(t);
            if (length_of(w.rest, edge) > edge_length && w.crossed(t, segments, segment_count)) marked.push_back(edge);
        }
        if (marked.empty()) break;
        std::sort(marked.begin(), marked.end());
        marked.erase(std::unique(marked.begin(), marked.end()), marked.end());
        w.close(marked);
        // A bisection at least doubles the tets around each edge: stop before passing the limit.
        if (w.tet_count() + 8 * marked.size() > limit) break;
        w.split(marked, body.node_count());
    }
    if (out.origins.empty()) out.tets.clear(), out.source.clear();
    return out;
}

}  // namespace sh
