// TetCut: where a cut surface crosses an FEM body's tets, and the tets it makes there: the
// crossed edges, the nodes the cut goes through, and each crossed tet's pieces.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <cstdint>
#include <utility>

namespace sh {

struct Aabb;
class CutSurface;
class FemBody;

/// The cut of one FEM body by one surface, before the material separates: every edge the
/// surface crosses is split at the crossing (a crossing near a node goes through the node),
/// which leaves the surface inside the body made of tet faces; the new nodes and element list,
/// with a side label for every tet at the cut.
class TetCut {
public:
    /// A crossing within kSnap of an edge's length from a node goes through the node instead,
    /// so that no piece is thinner than about kSnap of its tet.
    static constexpr double kSnap = 0.25;

    /// Finds where surface crosses body's tets with the nodes at frame (3 per node: the current
    /// positions, or the rest shape for a surface given in the material frame) and splits the
    /// crossed tets; see the members for what it leaves. With guard_quality, crossings that
    /// would make a piece below the quality bound, or too stiff for 0.3 of the uncut body's
    /// critical step, go through a node instead. (Without it, cutting again along the same
    /// surface finds the same crossings: a sweep that is cut with again as it grows.)
    /// Nodes listed in known_on (ascending; may be null) lie on the surface whatever their
    /// distance from it: the nodes an earlier cut along a part of the same surface went through.
    /// Only tets whose box meets focus (in frame; null: the surface's box) are cut: a surface
    /// grown by a new part, cut with again, has nothing new to part away from that part.
    TetCut(const FemBody& body, const CutSurface& surface, const double* frame, bool guard_quality,
           const vec<int32_t>* known_on = nullptr, const Aabb* focus = nullptr);

    /// New nodes (appended after the body's), each on a crossed edge.
    vec<NodeOrigin> origins;
    /// The element list after the split: the body's tets, crossed ones replaced by their first
    /// piece and the other pieces appended (4 nodes each, positively oriented at rest).
    vec<int32_t> tets;
    /// Per tet of tets: the body tet it comes from, or -1 - s for a piece of tet s.
    vec<int32_t> source;
    /// The tets at the cut (those with a node on the cut), ascending, with the side of the
    /// surface each lies on: +1, -1, or 0 for a tet flat on the surface.
    vec<int32_t> at_cut;
    vec<int8_t> side;
    /// The nodes on the cut (nodes the surface goes through and the new nodes), ascending.
    vec<int32_t> cut_nodes;
    /// Lowest quality (tet_quality at rest) of the pieces; 1 if none.
    double min_quality = 1.0;
    /// Tets split.
    int32_t split_count = 0;

private:
    struct Edge {
        int32_t lo, hi;       ///< its nodes, lo < hi
        double t = 0.0;       ///< where the surface crosses it, from lo (0) to hi (1)
        int32_t triangle = -1;///< the surface triangle crossed, -1 if none
        bool cut = false;     ///< crossed strictly between its nodes (not through a node)
        int32_t node = -1;    ///< the new node on it, once numbered
    };
    /// A tet made by splitting a candidate along its crossed edges.
    struct Piece {
        int32_t node[4];      ///< positively oriented
        int32_t candidate;    ///< the candidate it is part of
    };
    /// Stands in for the node of crossed edge e (kProvisional + e) before nodes are numbered.
    static constexpr int32_t kProvisional = 1 << 30;

    void find_candidates(const FemBody& body, const double* lower, const double* upper);
    void find_edges(const FemBody& body, const CutSurface& surface);
    void snap_earlier_cut_nodes(const FemBody& body, const CutSurface& surface, const vec<int32_t>* known_on);
    void settle(const FemBody& body);
    void mark_cut_edges();
    void snap_nearest_end(int32_t candidate);
    /// The candidates split along every crossed edge: each candidate's own entry first (as its
    /// first piece), then the other pieces; new nodes numbered for real or provisionally.
    vec<Piece> bisect(bool final_numbers) const;
    /// Candidates with a piece below the quality bound or too stiff for the critical step.
    vec<int32_t> bad_pieces(const FemBody& body, double largest_omega2) const;
    /// Where node (a body node or a new one, numbered either way) is at positions.
    void node_position(const FemBody& body, int32_t node, const double* positions, double out[3]) const;
    void number_new_nodes(int32_t node_count);
    void add_pieces(const FemBody& body, const vec<Piece>& pieces);
    /// The side of surface tet lies on; distance (per body node, NaN until known) caches the
    /// nodes' signed distances from it.
    int8_t side_of_tet(const FemBody& body, const CutSurface& surface, const int32_t* tet, vec<double>& distance) const;
    void collect_cut(const FemBody& body, const CutSurface& surface);
    /// The entry of nodes_ for node (a node of a candidate).
    size_t node_slot(int32_t node) const;
    bool on(int32_t node) const { return on_[node_slot(node)] != 0; }
    /// The edge slot of candidate tet c's edge e.
    Edge& edge(int32_t c, int e) { return edges_[static_cast<size_t>(tet_edge_[6 * static_cast<size_t>(c) + e])]; }
    const Edge& edge(int32_t c, int e) const { return edges_[static_cast<size_t>(tet_edge_[6 * static_cast<size_t>(c) + e])]; }

    const double* frame_;       ///< node positions the surface is given against
    vec<int32_t> candidates_;   ///< body tets whose box meets the surface's
    vec<int32_t> corner_;       ///< 4 per candidate: its nodes
    vec<std::pair<int32_t, int8_t>> piece_side_;  ///< tets at the cut with their side
    vec<Edge> edges_;           ///< their edges, by (lo, hi)
    vec<int32_t> tet_edge_;     ///< 6 per candidate: its edges' slots in edges_
    vec<int32_t> nodes_;        ///< the candidates' nodes, ascending
    vec<size_t> new_node_edge_; ///< per new node (in origins' order): its edge's slot
    vec<uint8_t> on_;           ///< per entry of nodes_: the cut goes through it
};

}  // namespace sh
