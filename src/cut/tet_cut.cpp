#include "cut/tet_cut.hpp"

#include "cut/cut_surface.hpp"
#include "core/vec3.hpp"
#include "mesh/tet_mesh.hpp"
#include "model/fem_body.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// Pieces below this quality, or with a critical step below kStepRatio times the uncut body's,
// are avoided by cutting through a node instead.
constexpr double kMinQuality = 0.05;
constexpr double kStepRatio = 0.3;

// The corners of tet t of body.
const int32_t* corners(const FemBody& body, int32_t t) { return body.element_nodes() + 4 * static_cast<size_t>(t); }

}  // namespace

TetCut::TetCut(const FemBody& body, const CutSurface& surface, const double* frame) : frame_(frame) {
    find_candidates(body, surface);
    find_edges(body, surface);
    settle(body);
    number_new_nodes(body.node_count());
    tets.assign(body.element_nodes(), body.element_nodes() + 4 * static_cast<size_t>(body.element_count()));
    source.resize(static_cast<size_t>(body.element_count()));
    for (size_t t = 0; t < source.size(); ++t) source[t] = static_cast<int32_t>(t);
    for (size_t c = 0; c < candidates_.size(); ++c) add_pieces(body, surface, static_cast<int32_t>(c));
    collect_cut(body, surface);
}

void TetCut::find_candidates(const FemBody& body, const CutSurface& surface) {
    const double* x = frame_;
    for (int32_t t = 0; t < body.element_count(); ++t) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int a = 0; a < 4; ++a)
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(lo[k], at(x, corners(body, t)[a])[k]);
                hi[k] = std::max(hi[k], at(x, corners(body, t)[a])[k]);
            }
        bool near = true;
        for (int k = 0; k < 3; ++k) near = near && lo[k] <= surface.upper()[k] && hi[k] >= surface.lower()[k];
        if (!near) continue;
        candidates_.push_back(t);
        corner_.insert(corner_.end(), corners(body, t), corners(body, t) + 4);
    }
}

void TetCut::find_edges(const FemBody& body, const CutSurface& surface) {
    for (const int32_t t : candidates_)
        for (int e = 0; e < 6; ++e) {
            const int32_t a = corners(body, t)[kTetEdge[e][0]], b = corners(body, t)[kTetEdge[e][1]];
            edges_.push_back(Edge{std::min(a, b), std::max(a, b)});
            nodes_.push_back(a);
        }
    const auto by_nodes = [](const Edge& p, const Edge& q) { return p.lo != q.lo ? p.lo < q.lo : p.hi < q.hi; };
    std::sort(edges_.begin(), edges_.end(), by_nodes);
    edges_.erase(std::unique(edges_.begin(), edges_.end(), [](const Edge& p, const Edge& q) { return p.lo == q.lo && p.hi == q.hi; }),
                 edges_.end());
    for (const int32_t t : candidates_)
        for (int a = 0; a < 4; ++a) nodes_.push_back(corners(body, t)[a]);
    std::sort(nodes_.begin(), nodes_.end());
    nodes_.erase(std::unique(nodes_.begin(), nodes_.end()), nodes_.end());
    on_.assign(nodes_.size(), 0);
    tet_edge_.resize(6 * candidates_.size());
    for (size_t c = 0; c < candidates_.size(); ++c)
        for (int e = 0; e < 6; ++e) {
            const int32_t a = corners(body, candidates_[c])[kTetEdge[e][0]], b = corners(body, candidates_[c])[kTetEdge[e][1]];
            const Edge key{std::min(a, b), std::max(a, b)};
            tet_edge_[6 * c + e] = static_cast<int32_t>(std::lower_bound(edges_.begin(), edges_.end(), key, by_nodes) - edges_.begin());
        }
    for (Edge& edge : edges_) {
        if (!surface.first_hit(at(frame_, edge.lo), at(frame_, edge.hi), edge.t, edge.triangle)) continue;
        // A crossing near a node goes through the node.
        if (edge.t < kSnap) on_[node_slot(edge.lo)] = 1;
        if (edge.t > 1.0 - kSnap) on_[node_slot(edge.hi)] = 1;
    }
}

size_t TetCut::node_slot(int32_t node) const {
    return static_cast<size_t>(std::lower_bound(nodes_.begin(), nodes_.end(), node) - nodes_.begin());
}

void TetCut::settle(const FemBody& body) {
    const double largest_omega2 = body.reference_frequency_squared();
    // Each round moves at least one more crossing onto a node, or settles: it ends. A round
    // snaps every offending tet at once, so that a long cut settles in a few rounds.
    for (;;) {
        mark_cut_edges();
        vec<int32_t> offending = unsplittable();
        if (offending.empty()) offending = bad_splits(body, largest_omega2);
        if (offending.empty()) return;
        for (const int32_t c : offending) snap_nearest_end(c);
    }
}

void TetCut::mark_cut_edges() {
    for (Edge& edge : edges_) edge.cut = edge.triangle >= 0 && !on(edge.lo) && !on(edge.hi);
}

vec<int32_t> TetCut::unsplittable() const {
    // A tet the cut crosses without separating its corners holds the cut's border: the cut
    // there goes through a node instead (the tet then stays whole and touches the cut).
    vec<int32_t> found;
    for (size_t c = 0; c < candidates_.size(); ++c) {
        int group[4];
        if (group_corners(crossing_of(static_cast<int32_t>(c)), group) == -1) found.push_back(static_cast<int32_t>(c));
    }
    return found;
}

vec<int32_t> TetCut::bad_splits(const FemBody& body, double largest_omega2) const {
    vec<int32_t> found;
    for (size_t c = 0; c < candidates_.size(); ++c) {
        double quality = 1.0;
        if (!pieces_ok(body, static_cast<int32_t>(c), largest_omega2, quality)) found.push_back(static_cast<int32_t>(c));
    }
    return found;
}

void TetCut::snap_nearest_end(int32_t c) {
    // The crossing nearest to a node of the tet moves onto that node (another tet of this
    // round may have snapped it already).
    int best = -1;
    double nearest = INFINITY;
    for (int e = 0; e < 6; ++e) {
        const Edge& ed = edge(c, e);
        if (ed.cut && !on(ed.lo) && !on(ed.hi) && std::min(ed.t, 1.0 - ed.t) < nearest) nearest = std::min(ed.t, 1.0 - ed.t), best = e;
    }
    if (best < 0) return;
    const Edge& ed = edge(c, best);
    on_[node_slot(ed.t < 0.5 ? ed.lo : ed.hi)] = 1;
}

TetCrossing TetCut::crossing_of(int32_t c) const {
    TetCrossing crossing;
    for (int e = 0; e < 6; ++e) crossing.cut[e] = edge(c, e).cut;
    for (int a = 0; a < 4; ++a) crossing.on[a] = on(corner_[4 * static_cast<size_t>(c) + a]);
    return crossing;
}

int TetCut::split_candidate(const FemBody& body, int32_t c, bool final_numbers, int pieces[kMaxPieces][4],
                            int piece_group[kMaxPieces], int group[4]) const {
    const TetCrossing crossing = crossing_of(c);
    if (group_corners(crossing, group) != 2) return 0;
    int32_t global[10];
    for (int a = 0; a < 4; ++a) global[a] = corner_[4 * static_cast<size_t>(c) + a];
    for (int e = 0; e < 6; ++e) {
        // Before numbering, an edge's slot stands in for its node: both grow in the same order.
        const size_t slot = static_cast<size_t>(tet_edge_[6 * static_cast<size_t>(c) + e]);
        global[4 + e] = final_numbers ? edges_[slot].node : body.node_count() + static_cast<int32_t>(slot);
    }
    return split_tet(crossing, group, global, pieces, piece_group);
}

void TetCut::point_rest(const FemBody& body, int32_t c, int point, double out[3]) const {
    if (point < 4) {
        for (int k = 0; k < 3; ++k) out[k] = at(body.rest.data(), corner_[4 * static_cast<size_t>(c) + point])[k];
        return;
    }
    const Edge& ed = edge(c, point - 4);
    for (int k = 0; k < 3; ++k) out[k] = (1.0 - ed.t) * at(body.rest.data(), ed.lo)[k] + ed.t * at(body.rest.data(), ed.hi)[k];
}

bool TetCut::pieces_ok(const FemBody& body, int32_t c, double largest_omega2, double& quality) const {
    int pieces[kMaxPieces][4], piece_group[kMaxPieces], group[4];
    const int count = split_candidate(body, c, false, pieces, piece_group, group);
    const sh_material& material = body.material(static_cast<size_t>(candidates_[static_cast<size_t>(c)]));
    for (int p = 0; p < count; ++p) {
        double r[4][3];
        for (int a = 0; a < 4; ++a) point_rest(body, c, pieces[p][a], r[a]);
        const double q = std::fabs(tet_quality(r[0], r[1], r[2], r[3]));
        quality = std::min(quality, q);
        if (q < kMinQuality) return false;
        vec<double> rest_points(r[0], r[0] + 12);
        const int32_t local[4] = {0, 1, 2, 3};
        double bm[9], v0 = 0.0;
        FemBody::shape_from_rest(rest_points, local, bm, v0);
        const double omega2 = FemBody::element_max_frequency_squared(bm, std::fabs(v0), material);
        if (omega2 * kStepRatio * kStepRatio > largest_omega2) return false;
    }
    return true;
}

void TetCut::number_new_nodes(int32_t node_count) {
    for (Edge& ed : edges_) {
        if (!ed.cut) continue;
        ed.node = node_count + static_cast<int32_t>(origins.size());
        origins.push_back(NodeOrigin{ed.lo, ed.hi, ed.t});
    }
}

void TetCut::add_pieces(const FemBody& body, const CutSurface& surface, int32_t c) {
    int pieces[kMaxPieces][4], piece_group[kMaxPieces], group[4];
    const int count = split_candidate(body, c, true, pieces, piece_group, group);
    if (count == 0) return;
    ++split_count;
    const int32_t original = candidates_[static_cast<size_t>(c)];
    const int8_t sides[2] = {side_of_group(body, surface, c, group, 0), side_of_group(body, surface, c, group, 1)};
    for (int p = 0; p < count; ++p) {
        int32_t nodes[4];
        double r[4][3];
        for (int a = 0; a < 4; ++a) {
            point_rest(body, c, pieces[p][a], r[a]);
            nodes[a] = pieces[p][a] < 4 ? corner_[4 * static_cast<size_t>(c) + pieces[p][a]] : edge(c, pieces[p][a] - 4).node;
        }
        if (signed_tet_volume(r[0], r[1], r[2], r[3]) < 0.0) std::swap(nodes[2], nodes[3]), std::swap(r[2], r[3]);
        min_quality = std::min(min_quality, tet_quality(r[0], r[1], r[2], r[3]));
        const size_t slot = p == 0 ? static_cast<size_t>(original) : source.size();
        if (p > 0) {
            tets.resize(tets.size() + 4);
            source.push_back(0);
        }
        std::copy(nodes, nodes + 4, &tets[4 * slot]);
        source[slot] = -1 - original;
        piece_side_.push_back({static_cast<int32_t>(slot), sides[piece_group[p]]});
    }
}

int8_t TetCut::side_of_group(const FemBody& body, const CutSurface& surface, int32_t c, const int group[4], int g) const {
    // Across a cut edge from a corner of group g: the side of the crossed triangle it is on.
    for (int e = 0; e < 6; ++e) {
        const Edge& ed = edge(c, e);
        if (!ed.cut) continue;
        const int a = kTetEdge[e][0], b = kTetEdge[e][1];
        const int mine = group[a] == g ? a : (group[b] == g ? b : -1);
        if (mine < 0) continue;
        const double* corner = at(frame_, corner_[4 * static_cast<size_t>(c) + mine]);
        double offset[3];
        for (int k = 0; k < 3; ++k)
            offset[k] = corner[k] - ((1.0 - ed.t) * at(frame_, ed.lo)[k] + ed.t * at(frame_, ed.hi)[k]);
        return dot3(offset, surface.normal(ed.triangle)) >= 0.0 ? 1 : -1;
    }
    return 0;
}

int8_t TetCut::side_of_tet(const FemBody& body, const CutSurface& surface, int32_t t) const {
    // The corner farthest from the surface decides.
    double farthest = 0.0;
    for (int a = 0; a < 4; ++a) {
        const int32_t node = corners(body, t)[a];
        const size_t slot = node_slot(node);
        if (slot < nodes_.size() && nodes_[slot] == node && on_[slot]) continue;
        int32_t triangle = -1;
        const double d = surface.signed_distance(at(frame_, node), triangle);
        if (std::fabs(d) > std::fabs(farthest)) farthest = d;
    }
    return farthest > 0.0 ? 1 : (farthest < 0.0 ? -1 : 0);
}

void TetCut::collect_cut(const FemBody& body, const CutSurface& surface) {
    for (size_t i = 0; i < nodes_.size(); ++i)
        if (on_[i]) cut_nodes.push_back(nodes_[i]);
    for (size_t k = 0; k < origins.size(); ++k) cut_nodes.push_back(body.node_count() + static_cast<int32_t>(k));
    // Whole tets with a node the cut goes through, then the pieces.
    std::sort(piece_side_.begin(), piece_side_.end());
    for (int32_t t = 0; t < body.element_count(); ++t) {
        if (source[static_cast<size_t>(t)] < 0) continue;
        bool touches = false;
        for (int a = 0; a < 4 && !touches; ++a) {
            const int32_t node = corners(body, t)[a];
            const size_t slot = node_slot(node);
            touches = slot < nodes_.size() && nodes_[slot] == node && on_[slot];
        }
        if (touches) piece_side_.push_back({t, side_of_tet(body, surface, t)});
    }
    std::sort(piece_side_.begin(), piece_side_.end());
    for (const auto& entry : piece_side_) {
        at_cut.push_back(entry.first);
        side.push_back(entry.second);
    }
}

}  // namespace sh
