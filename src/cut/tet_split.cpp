#include "cut/tet_split.hpp"

#include <algorithm>

namespace sh {
namespace {

// The tet's faces as corner cycles.
constexpr int kFace[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

int edge_of(int a, int b) {
    for (int e = 0; e < 6; ++e)
        if ((kTetEdge[e][0] == a && kTetEdge[e][1] == b) || (kTetEdge[e][0] == b && kTetEdge[e][1] == a)) return e;
    return -1;
}

// A polygon of at most 4 points of the tet.
struct Polygon {
    int point[4];
    int size = 0;
};

// Face f's part on the side of group g: its corners in g or on the surface and the cut points
// on its edges, in cycle order.
Polygon face_part(const TetCrossing& crossing, const int group[4], int f, int g) {
    Polygon part;
    for (int k = 0; k < 3; ++k) {
        const int a = kFace[f][k], b = kFace[f][(k + 1) % 3];
        if ((group[a] == g || crossing.on[a]) && part.size < 4) part.point[part.size++] = a;
        const int e = edge_of(a, b);
        if (crossing.cut[e] && part.size < 4) part.point[part.size++] = 4 + e;
    }
    return part;
}

// The polygon the cut makes inside the tet: every face crossed by the cut contributes the
// segment between its two points on the surface; the segments chain into a cycle.
Polygon cut_polygon(const TetCrossing& crossing) {
    int segment[4][2], segments = 0;
    for (int f = 0; f < 4; ++f) {
        int ends[3], count = 0;
        for (int k = 0; k < 3; ++k) {
            const int a = kFace[f][k], b = kFace[f][(k + 1) % 3];
            if (crossing.on[a]) ends[count++] = a;
            const int e = edge_of(a, b);
            if (crossing.cut[e] && count < 3) ends[count++] = 4 + e;
        }
        if (count != 2) continue;
        // Two faces through an edge on the surface give that edge twice.
        bool known = false;
        for (int k = 0; k < segments; ++k)
            known = known || (std::min(segment[k][0], segment[k][1]) == std::min(ends[0], ends[1]) &&
                              std::max(segment[k][0], segment[k][1]) == std::max(ends[0], ends[1]));
        if (!known) segment[segments][0] = ends[0], segment[segments][1] = ends[1], ++segments;
    }
    Polygon polygon;
    if (segments < 3) return polygon;
    polygon.point[polygon.size++] = segment[0][0];
    int last = segment[0][1], used = 1;
    bool taken[4] = {true, false, false, false};
    while (last != polygon.point[0] && polygon.size < 4 && used <= segments) {
        polygon.point[polygon.size++] = last;
        for (int s = 1; s < segments; ++s) {
            if (taken[s] || (segment[s][0] != last && segment[s][1] != last)) continue;
            taken[s] = true;
            last = segment[s][0] == last ? segment[s][1] : segment[s][0];
            break;
        }
        ++used;
    }
    return polygon;
}

// Splits polygon into triangles (a quadrilateral along the diagonal through its lowest node)
// and adds a piece joining each triangle that avoids apex to apex.
void cone_from_apex(const Polygon& polygon, int apex, const int32_t global[10], int group, int pieces[kMaxPieces][4],
                    int piece_group[kMaxPieces], int& count) {
    if (polygon.size < 3) return;
    for (int k = 0; k < polygon.size; ++k)
        if (polygon.point[k] == apex) return;  // the polygon lies on a face through the apex
    int triangles[2][3], triangle_count = 1;
    if (polygon.size == 3) {
        std::copy(polygon.point, polygon.point + 3, triangles[0]);
    } else {
        int lowest = 0;
        for (int k = 1; k < 4; ++k)
            if (global[polygon.point[k]] < global[polygon.point[lowest]]) lowest = k;
        const int* p = polygon.point;
        const int a = p[lowest], b = p[(lowest + 1) % 4], c = p[(lowest + 2) % 4], d = p[(lowest + 3) % 4];
        triangles[0][0] = a, triangles[0][1] = b, triangles[0][2] = c;
        triangles[1][0] = a, triangles[1][1] = c, triangles[1][2] = d;
        triangle_count = 2;
    }
    for (int t = 0; t < triangle_count && count < kMaxPieces; ++t) {
        pieces[count][0] = apex;
        std::copy(triangles[t], triangles[t] + 3, pieces[count] + 1);
        piece_group[count++] = group;
    }
}

}  // namespace

int group_corners(const TetCrossing& crossing, int group[4]) {
    int label[4];
    for (int c = 0; c < 4; ++c) label[c] = crossing.on[c] ? -1 : c;
    // Join corners along uncut edges (at most three rounds settle four corners).
    for (int round = 0; round < 3; ++round)
        for (int e = 0; e < 6; ++e) {
            const int a = kTetEdge[e][0], b = kTetEdge[e][1];
            if (crossing.cut[e] || label[a] < 0 || label[b] < 0) continue;
            const int low = std::min(label[a], label[b]);
            for (int c = 0; c < 4; ++c)
                if (label[c] == label[a] || label[c] == label[b]) label[c] = low;
        }
    int distinct[4], groups = 0;
    for (int c = 0; c < 4; ++c) {
        group[c] = -1;
        if (label[c] < 0) continue;
        int g = 0;
        while (g < groups && distinct[g] != label[c]) ++g;
        if (g == groups) distinct[groups++] = label[c];
        group[c] = g;
    }
    if (groups > 2) return -1;  // three groups: the cut surface folds inside the tet
    bool any_cut = false;
    for (int e = 0; e < 6; ++e) {
        if (!crossing.cut[e]) continue;
        any_cut = true;
        if (group[kTetEdge[e][0]] == group[kTetEdge[e][1]]) return -1;  // within a group
    }
    return any_cut && groups < 2 ? -1 : groups;
}

int split_tet(const TetCrossing& crossing, const int group[4], const int32_t global[10], int pieces[kMaxPieces][4],
              int piece_group[kMaxPieces]) {
    const Polygon cut = cut_polygon(crossing);
    int count = 0;
    for (int g = 0; g < 2; ++g) {
        // The region's lowest point is the apex every piece of the region shares.
        int apex = -1;
        for (int p = 0; p < 10; ++p) {
            const bool in_region = p < 4 ? (group[p] == g || crossing.on[p]) : crossing.cut[p - 4];
            if (in_region && (apex < 0 || global[p] < global[apex])) apex = p;
        }
        for (int f = 0; f < 4; ++f) cone_from_apex(face_part(crossing, group, f, g), apex, global, g, pieces, piece_group, count);
        cone_from_apex(cut, apex, global, g, pieces, piece_group, count);
    }
    return count;
}

}  // namespace sh
