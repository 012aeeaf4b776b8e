#include "cut/tet_cut.hpp"

#include "cut/cut_surface.hpp"
#include "collision/aabb_tree.hpp"
#include "cut/edge_split.hpp"
#include "core/vec3.hpp"
#include "mesh/tet_mesh.hpp"
#include "mesh/tets_in_box.hpp"
#include "model/fem_body.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// Pieces below this quality, or with a critical step below kStepRatio times the uncut body's,
// are avoided by cutting through a node instead.
constexpr double kMinQuality = 0.05;
constexpr double kStepRatio = 0.3;

// The tet's edges: edge e joins corners kTetEdge[e][0] and kTetEdge[e][1].
constexpr int kTetEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

// The corners of tet t of body.
const int32_t* corners(const FemBody& body, int32_t t) { return body.element_nodes() + 4 * static_cast<size_t>(t); }

}  // namespace

TetCut::TetCut(const FemBody& body, const CutSurface& surface, const double* frame, bool guard_quality,
               const vec<int32_t>* known_on, const Aabb* focus)
    : frame_(frame) {
    find_candidates(body, focus ? focus->lo : surface.lower(), focus ? focus->hi : surface.upper());
    find_edges(body, surface);
    snap_earlier_cut_nodes(body, surface, known_on);
    mark_cut_edges();
    if (guard_quality) settle(body);
    number_new_nodes(body.node_count());
    tets.assign(body.element_nodes(), body.element_nodes() + 4 * static_cast<size_t>(body.element_count()));
    source.resize(static_cast<size_t>(body.element_count()));
    for (size_t t = 0; t < source.size(); ++t) source[t] = static_cast<int32_t>(t);
    add_pieces(body, bisect(true));
    collect_cut(body, surface);
}

void TetCut::find_candidates(const FemBody& body, const double* lower, const double* upper) {
    for_each_tet_in_box(frame_, body.node_count(), corners(body, 0), body.element_count(), lower, upper,
                        [&](int32_t t) {
                            candidates_.push_back(t);
                            corner_.insert(corner_.end(), corners(body, t), corners(body, t) + 4);
                        });
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

void TetCut::snap_earlier_cut_nodes(const FemBody& body, const CutSurface& surface, const vec<int32_t>* known_on) {
    if (known_on)
        for (size_t i = 0; i < nodes_.size(); ++i)
            if (std::binary_search(known_on->begin(), known_on->end(), nodes_[i])) on_[i] = 1;
    // Nodes an earlier cut made lie on its surface, so a later cut that passes within a
    // quarter edge of them (extending the earlier one from its border) goes through them.
    vec<double> shortest(nodes_.size(), INFINITY);
    for (const Edge& ed : edges_) {
        double d[3];
        sub3(at(frame_, ed.hi), at(frame_, ed.lo), d);
        for (const int32_t node : {ed.lo, ed.hi}) shortest[node_slot(node)] = std::min(shortest[node_slot(node)], norm3(d));
    }
    // A node made by a cut lies on the body's surface (on a cut face); nodes made inside by
    // refinement ahead of a blade have parents too but lie on no cut.
    for (size_t i = 0; i < nodes_.size(); ++i) {
        if (on_[i] || body.parent_of(nodes_[i]) < 0 || !body.on_surface(nodes_[i])) continue;
        int32_t triangle = -1;
        if (std::fabs(surface.signed_distance(at(frame_, nodes_[i]), triangle)) < kSnap * shortest[i]) on_[i] = 1;
    }
}

size_t TetCut::node_slot(int32_t node) const {
    return static_cast<size_t>(std::lower_bound(nodes_.begin(), nodes_.end(), node) - nodes_.begin());
}

void TetCut::settle(const FemBody& body) {
    const double largest_omega2 = body.reference_frequency_squared();
    // Each round moves at least one more crossing onto a node, or settles: it ends. A round
    // snaps the worst crossing of every offending tet at once, so that it settles in a few.
    for (;;) {
        mark_cut_edges();
        const vec<int32_t> offending = bad_pieces(body, largest_omega2);
        if (offending.empty()) return;
        for (const int32_t c : offending) snap_nearest_end(c);
    }
}

void TetCut::mark_cut_edges() {
    for (Edge& edge : edges_) edge.cut = edge.triangle >= 0 && !on(edge.lo) && !on(edge.hi);
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

vec<TetCut::Piece> TetCut::bisect(bool final_numbers) const {
    // Every crossed edge is split at its crossing in every tet that has it, one edge after the
    // other in one global order: each split halves the tets around one edge, so the mesh stays
    // conforming, and once every crossed edge is split no edge crosses the surface (each has an
    // end on it or both on one side), so the surface inside the tets is made of their faces.
    // Pieces of different candidates never share a split, so each candidate is split alone,
    // with its own crossed edges in the global order.
    vec<Piece> pieces(candidates_.size());
    vec<std::array<int32_t, 4>> split;
    for (size_t c = 0; c < candidates_.size(); ++c) {
        int32_t slots[6], crossed = 0;
        for (int e = 0; e < 6; ++e)
            if (edge(static_cast<int32_t>(c), e).cut) slots[crossed++] = tet_edge_[6 * c + static_cast<size_t>(e)];
        std::sort(slots, slots + crossed);
        EdgeSplit splits[6];
        for (int k = 0; k < crossed; ++k) {
            const Edge& ed = edges_[static_cast<size_t>(slots[k])];
            splits[k] = {ed.lo, ed.hi, final_numbers ? ed.node : kProvisional + slots[k]};
        }
        split.clear();
        split_tet(&corner_[4 * c], splits, crossed, split);
        for (size_t m = 0; m < split.size(); ++m) {
            Piece piece;
            std::copy(split[m].begin(), split[m].end(), piece.node);
            piece.candidate = static_cast<int32_t>(c);
            if (m == 0)
                pieces[c] = piece;
            else
                pieces.push_back(piece);
        }
    }
    return pieces;
}

void TetCut::node_position(const FemBody& body, int32_t node, const double* positions, double out[3]) const {
    if (node < body.node_count()) {
        for (int k = 0; k < 3; ++k) out[k] = at(positions, node)[k];
        return;
    }
    const Edge& ed = edges_[node >= kProvisional ? static_cast<size_t>(node - kProvisional)
                                                 : new_node_edge_[static_cast<size_t>(node - body.node_count())]];
    for (int k = 0; k < 3; ++k) out[k] = (1.0 - ed.t) * at(positions, ed.lo)[k] + ed.t * at(positions, ed.hi)[k];
}

vec<int32_t> TetCut::bad_pieces(const FemBody& body, double largest_omega2) const {
    const vec<Piece> pieces = bisect(false);
    // Only split candidates count: a whole tet keeps whatever quality the mesh gave it.
    vec<uint8_t> split(candidates_.size(), 0);
    for (size_t p = candidates_.size(); p < pieces.size(); ++p) split[static_cast<size_t>(pieces[p].candidate)] = 1;
    vec<int32_t> found;
    for (const Piece& piece : pieces) {
        if (!split[static_cast<size_t>(piece.candidate)] || (!found.empty() && found.back() == piece.candidate)) continue;
        vec<double> rest_points(12);  // the piece's corners at rest, 3 each
        for (int a = 0; a < 4; ++a) node_position(body, piece.node[a], body.rest.data(), &rest_points[3 * static_cast<size_t>(a)]);
        const double* r = rest_points.data();
        const double q = tet_quality(r, r + 3, r + 6, r + 9);
        bool bad = q < kMinQuality;
        if (!bad) {
            const int32_t local[4] = {0, 1, 2, 3};
            double bm[9], v0 = 0.0;
            FemBody::shape_from_rest(rest_points, local, bm, v0);
            const sh_material& material = body.material(static_cast<size_t>(candidates_[static_cast<size_t>(piece.candidate)]));
            // The bound settles most pieces without the eigenproblem.
            const auto too_stiff = [&](double omega2) { return omega2 * kStepRatio * kStepRatio > largest_omega2; };
            bad = too_stiff(FemBody::element_frequency_bound(bm, material)) &&
                  too_stiff(FemBody::element_max_frequency_squared(bm, v0, material));
        }
        if (bad && std::find(found.begin(), found.end(), piece.candidate) == found.end()) found.push_back(piece.candidate);
    }
    return found;
}

void TetCut::number_new_nodes(int32_t node_count) {
    for (Edge& ed : edges_) {
        if (!ed.cut) continue;
        ed.node = node_count + static_cast<int32_t>(origins.size());
        origins.push_back(NodeOrigin{ed.lo, ed.hi, ed.t});
        new_node_edge_.push_back(static_cast<size_t>(&ed - edges_.data()));
    }
}

void TetCut::add_pieces(const FemBody& body, const vec<Piece>& pieces) {
    // A candidate's first piece takes its place, the others are appended.
    vec<uint8_t> placed(candidates_.size(), 0);
    vec<uint8_t> split(candidates_.size(), 0);
    for (size_t p = candidates_.size(); p < pieces.size(); ++p) split[static_cast<size_t>(pieces[p].candidate)] = 1;
    for (const Piece& piece : pieces) {
        const size_t c = static_cast<size_t>(piece.candidate);
        if (!split[c]) continue;
        const int32_t original = candidates_[c];
        const size_t slot = placed[c] ? source.size() : static_cast<size_t>(original);
        if (placed[c]) {
            tets.resize(tets.size() + 4);
            source.push_back(0);
        }
        placed[c] = 1;
        std::copy(piece.node, piece.node + 4, &tets[4 * slot]);
        source[slot] = -1 - original;
        double r[4][3];
        for (int a = 0; a < 4; ++a) node_position(body, piece.node[a], body.rest.data(), r[a]);
        min_quality = std::min(min_quality, tet_quality(r[0], r[1], r[2], r[3]));
        piece_side_.push_back({static_cast<int32_t>(slot), 0});
    }
    for (size_t c = 0; c < candidates_.size(); ++c) split_count += split[c];
}

int8_t TetCut::side_of_tet(const FemBody& body, const CutSurface& surface, const int32_t* tet, vec<double>& distance) const {
    // The corner off the surface farthest from it decides; corners on the surface (nodes the
    // cut goes through, nodes made on crossed edges) have no side. A tet whose corners are all
    // on the surface (a thin one, its nodes passed through within the snapping distance) lies
    // on the side its centre does.
    double farthest = 0.0;
    for (int a = 0; a < 4; ++a) {
        const int32_t node = tet[a];
        if (node >= body.node_count()) continue;
        const size_t slot = node_slot(node);
        if (slot < nodes_.size() && nodes_[slot] == node && on_[slot]) continue;
        double& d = distance[static_cast<size_t>(node)];
        int32_t triangle = -1;
        if (std::isnan(d)) d = surface.signed_distance(at(frame_, node), triangle);
        if (std::fabs(d) > std::fabs(farthest)) farthest = d;
    }
    if (farthest == 0.0) {
        double centre[3] = {0, 0, 0};
        for (int a = 0; a < 4; ++a) {
            double p[3];
            node_position(body, tet[a], frame_, p);
            for (int k = 0; k < 3; ++k) centre[k] += 0.25 * p[k];
        }
        int32_t triangle = -1;
        farthest = surface.signed_distance(centre, triangle);
    }
    return farthest > 0.0 ? 1 : (farthest < 0.0 ? -1 : 0);
}

void TetCut::collect_cut(const FemBody& body, const CutSurface& surface) {
    for (size_t i = 0; i < nodes_.size(); ++i)
        if (on_[i]) cut_nodes.push_back(nodes_[i]);
    for (size_t k = 0; k < origins.size(); ++k) cut_nodes.push_back(body.node_count() + static_cast<int32_t>(k));
    // Each node's distance from the surface once, not once per tet on it.
    vec<double> distance(static_cast<size_t>(body.node_count()), NAN);
    for (auto& entry : piece_side_) entry.second = side_of_tet(body, surface, &tets[4 * static_cast<size_t>(entry.first)], distance);
    // Whole tets with a node the cut goes through.
    vec<uint8_t> on_node(static_cast<size_t>(body.node_count()), 0);
    for (size_t i = 0; i < nodes_.size(); ++i) on_node[static_cast<size_t>(nodes_[i])] = on_[i];
    for (int32_t t = 0; t < body.element_count(); ++t) {
        const int32_t* tet = corners(body, t);
        const bool touches = on_node[static_cast<size_t>(tet[0])] | on_node[static_cast<size_t>(tet[1])] |
                             on_node[static_cast<size_t>(tet[2])] | on_node[static_cast<size_t>(tet[3])];
        if (touches && source[static_cast<size_t>(t)] >= 0) piece_side_.push_back({t, side_of_tet(body, surface, tet, distance)});
    }
    std::sort(piece_side_.begin(), piece_side_.end());
    for (const auto& entry : piece_side_) {
        at_cut.push_back(entry.first);
        side.push_back(entry.second);
    }
}

}  // namespace sh
