// How a cut surface splits one tet: which corners it separates, and the pieces (a template
// over the tet's corners and the points on its cut edges).
#pragma once

#include <cstdint>

namespace sh {

/// The tet's edges: edge e joins corners kTetEdge[e][0] and kTetEdge[e][1].
constexpr int kTetEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

/// Most pieces a tet splits into (two prisms of three tets).
constexpr int kMaxPieces = 6;

/// How the cut meets one tet: the corners that lie on the cut surface and the edges it crosses
/// between their ends.
struct TetCrossing {
    bool on[4] = {false, false, false, false};  ///< corner lies on the surface
    bool cut[6] = {false, false, false, false, false, false};  ///< edge crossed strictly inside
};

/// Groups the corners that are not on the surface by the uncut edges between them: group[c] is
/// 0 or 1 (-1 for a corner on the surface). Returns the number of groups (0, 1 or 2), or -1 if
/// the crossing cannot split the tet: a cut edge joins two corners of one group (the cut's
/// border runs through the tet) or cut edges with one group.
int group_corners(const TetCrossing& crossing, int group[4]);

/// Splits a tet whose corners form two groups into pieces. The tet's points are numbered 0..3
/// (corners) and 4 + e (the point on cut edge e); global[10] gives each point's node number,
/// which decides every quadrilateral's diagonal (through its lowest node), so that two tets
/// sharing a face split it alike. Writes each piece's four points (orientation not fixed) and
/// its corner group; returns the number of pieces.
int split_tet(const TetCrossing& crossing, const int group[4], const int32_t global[10], int pieces[kMaxPieces][4],
              int piece_group[kMaxPieces]);

}  // namespace sh
