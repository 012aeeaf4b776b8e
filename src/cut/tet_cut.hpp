// TetCut: where a cut surface crosses an FEM body's tets, and the tets it makes there: the
// crossed edges, the nodes the cut goes through, and each crossed tet's pieces.
#pragma once

#include "core/memory.hpp"
#include "cut/tet_split.hpp"
#include "model/body.hpp"

#include <cstdint>
#include <utility>

namespace sh {

class CutSurface;
class FemBody;

/// The cut of one FEM body by one surface, before the material separates: the new nodes on
/// crossed edges and the new element list with a side label for every tet at the cut.
class TetCut {
public:
    /// A cut point within kSnap of an edge's length from a node goes through the node instead,
    /// so that no piece is thinner than about kSnap of its tet.
    static constexpr double kSnap = 0.25;

    /// Finds where surface crosses body's tets with the nodes at frame (3 per node: the current
    /// positions, or the rest shape for a surface given in the material frame) and splits the
    /// crossed tets; see the members for what it leaves.
    TetCut(const FemBody& body, const CutSurface& surface, const double* frame);

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
    void find_candidates(const FemBody& body, const CutSurface& surface);
    void find_edges(const FemBody& body, const CutSurface& surface);
    void settle(const FemBody& body);
    void mark_cut_edges();
    vec<int32_t> unsplittable() const;
    vec<int32_t> bad_splits(const FemBody& body, double largest_omega2) const;
    void snap_nearest_end(int32_t candidate);
    bool pieces_ok(const FemBody& body, int32_t candidate, double largest_omega2, double& quality) const;
    int split_candidate(const FemBody& body, int32_t candidate, bool final_numbers, int pieces[kMaxPieces][4],
                        int piece_group[kMaxPieces], int group[4]) const;
    void number_new_nodes(int32_t node_count);
    void add_pieces(const FemBody& body, const CutSurface& surface, int32_t candidate);
    void collect_cut(const FemBody& body, const CutSurface& surface);
    void build_elements(const FemBody& body, const CutSurface& surface);
    int8_t side_of_group(const FemBody& body, const CutSurface& surface, int32_t candidate, const int group[4], int g) const;
    int8_t side_of_tet(const FemBody& body, const CutSurface& surface, int32_t tet) const;
    TetCrossing crossing_of(int32_t candidate) const;
    /// The entry of nodes_ for node (a node of a candidate).
    size_t node_slot(int32_t node) const;
    bool on(int32_t node) const { return on_[node_slot(node)] != 0; }
    /// The edge slot of candidate tet c's edge e.
    Edge& edge(int32_t c, int e) { return edges_[static_cast<size_t>(tet_edge_[6 * static_cast<size_t>(c) + e])]; }
    const Edge& edge(int32_t c, int e) const { return edges_[static_cast<size_t>(tet_edge_[6 * static_cast<size_t>(c) + e])]; }

    /// Rest position of point (0..3 corners, 4 + e the cut point of edge e) of candidate c.
    void point_rest(const FemBody& body, int32_t c, int point, double out[3]) const;

    const double* frame_;       ///< node positions the surface is given against
    vec<int32_t> candidates_;   ///< body tets whose box meets the surface's
    vec<int32_t> corner_;       ///< 4 per candidate: its nodes
    vec<std::pair<int32_t, int8_t>> piece_side_;  ///< tets at the cut with their side
    vec<Edge> edges_;           ///< their edges, by (lo, hi)
    vec<int32_t> tet_edge_;     ///< 6 per candidate: its edges' slots in edges_
    vec<int32_t> nodes_;        ///< the candidates' nodes, ascending
    vec<uint8_t> on_;           ///< per entry of nodes_: the cut goes through it
};

}  // namespace sh
