#include "cut/separation.hpp"

#include "core/union_find.hpp"
#include "cut/tet_cut.hpp"
#include "mesh/tet_mesh.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>

namespace sh {
namespace {

/// A triangle by its three nodes, ascending, packed into one integer: the separation sorts
/// and searches thousands of faces per cut, and an integer compares in one step where three
/// indices take a branch each.
class Face {
public:
    Face(int32_t a, int32_t b, int32_t c) {
        if (a > b) std::swap(a, b);
        if (b > c) std::swap(b, c);
        if (a > b) std::swap(a, b);
        key_ = static_cast<Key>(static_cast<uint32_t>(a)) << 64 | static_cast<Key>(static_cast<uint32_t>(b)) << 32 |
               static_cast<uint32_t>(c);
    }
    /// Its i-th node, ascending.
    int32_t operator[](int i) const { return static_cast<int32_t>(static_cast<uint32_t>(key_ >> (32 * (2 - i)))); }
    bool has(int32_t node) const { return (*this)[0] == node || (*this)[1] == node || (*this)[2] == node; }
    bool operator<(const Face& o) const { return key_ < o.key_; }
    bool operator==(const Face& o) const { return key_ == o.key_; }
    bool operator!=(const Face& o) const { return key_ != o.key_; }

private:
    __extension__ typedef unsigned __int128 Key;
    Key key_;
};

Face sorted_face(const int32_t* tet, int f) { return Face(tet[kTetFaces[f][0]], tet[kTetFaces[f][1]], tet[kTetFaces[f][2]]); }

/// An edge by its two nodes, ascending, packed like a Face.
uint64_t edge_key(int32_t a, int32_t b) {
    if (a > b) std::swap(a, b);
    return static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32 | static_cast<uint32_t>(b);
}
int32_t edge_end(uint64_t edge, int i) { return static_cast<int32_t>(static_cast<uint32_t>(edge >> (32 * (1 - i)))); }

// The separation's working state over the tets at the cut.
struct Separation {
    Separation(TetCut& cut_, int32_t node_count_) : cut(cut_), node_count(node_count_) { mark_cut_nodes(); }

    TetCut& cut;
    int32_t node_count;              // nodes before the cut
    vec<std::pair<int32_t, int32_t>> star;  // (cut node, index into cut.at_cut), by node
    vec<Face> cut_faces;             // faces between tets on opposite sides, sorted
    vec<int32_t> renumbered;         // 4 per tet at the cut: its nodes after copying
    vec<NodeOrigin> copies;          // the copies made
    vec<int32_t> copy_of;            // per copy: the node copied
    vec<uint8_t> on_cut;             // per node before the copies: 1 if cut.cut_nodes has it

    bool is_cut_node(int32_t node) const { return on_cut[static_cast<size_t>(node)] != 0; }

    void mark_cut_nodes() {
        on_cut.assign(static_cast<size_t>(node_count) + cut.origins.size(), 0);
        for (const int32_t n : cut.cut_nodes) on_cut[static_cast<size_t>(n)] = 1;
    }

    const int32_t* tet(size_t k) const { return &cut.tets[4 * static_cast<size_t>(cut.at_cut[k])]; }

    void build_star() {
        for (size_t k = 0; k < cut.at_cut.size(); ++k)
            for (int a = 0; a < 4; ++a)
                if (is_cut_node(tet(k)[a])) star.push_back({tet(k)[a], static_cast<int32_t>(k)});
        std::sort(star.begin(), star.end());
    }

    // Every face among the tets at the cut, by sorted nodes, with its tet: a face two tets
    // share appears twice in a row.
    vec<std::pair<Face, int32_t>> faces;

    void find_cut_faces() {
        for (size_t k = 0; k < cut.at_cut.size(); ++k)
            for (int f = 0; f < 4; ++f) faces.push_back({sorted_face(tet(k), f), static_cast<int32_t>(k)});
        std::sort(faces.begin(), faces.end());
        for (size_t i = 0; i + 1 < faces.size(); ++i) {
            const Face& face = faces[i].first;
            if (face != faces[i + 1].first || !is_cut_node(face[0]) || !is_cut_node(face[1]) || !is_cut_node(face[2])) continue;
            const int8_t a = cut.side[static_cast<size_t>(faces[i].second)], b = cut.side[static_cast<size_t>(faces[i + 1].second)];
            if (a != 0 && b != 0 && a != b) cut_faces.push_back(face);
        }
    }

    // split_stars' union-find over the star entries.
    vec<int32_t> star_parent, star_members, star_number;

    // The entry of star for node and the tet at the cut k.
    int32_t star_entry(int32_t node, int32_t k) const {
        return static_cast<int32_t>(std::lower_bound(star.begin(), star.end(), std::make_pair(node, k)) - star.begin());
    }

    // Joins, for each face two tets share that is not a cut face, the two tets in the star of
    // each cut node of the face: the pieces of each star, connected through its faces.
    void join_stars_across_faces() {
        star_parent.resize(star.size());
        std::iota(star_parent.begin(), star_parent.end(), 0);
        for (size_t i = 0; i + 1 < faces.size(); ++i) {
            const Face& face = faces[i].first;
            if (face != faces[i + 1].first || std::binary_search(cut_faces.begin(), cut_faces.end(), face)) continue;
            for (int c = 0; c < 3; ++c)
                if (const int32_t node = face[c]; is_cut_node(node))
                    union_join(star_parent, star_entry(node, faces[i].second), star_entry(node, faces[i + 1].second));
        }
    }

    // Copies the node whose star is star[begin, end) once per extra piece of its star: the
    // largest piece keeps the node.
    void number_star_pieces(size_t begin, size_t end) {
        const int32_t node = star[begin].first;
        for (size_t i = begin; i < end; ++i) star_members[static_cast<size_t>(union_root(star_parent, static_cast<int32_t>(i)))] = 0;
        for (size_t i = begin; i < end; ++i) ++star_members[static_cast<size_t>(union_root(star_parent, static_cast<int32_t>(i)))];
        size_t keeper = begin;
        for (size_t i = begin; i < end; ++i)
            if (star_members[i] > star_members[keeper]) keeper = i;
        for (size_t i = begin; i < end; ++i) star_number[i] = -1;
        star_number[keeper] = node;
        for (size_t i = begin; i < end; ++i) {
            int32_t& n = star_number[static_cast<size_t>(union_root(star_parent, static_cast<int32_t>(i)))];
            if (n < 0) {
                n = node_count + static_cast<int32_t>(cut.origins.size() + copies.size());
                copies.push_back(NodeOrigin{node, node, 0.0});
                copy_of.push_back(node);
            }
            const size_t k = static_cast<size_t>(star[i].second);
            for (int a = 0; a < 4; ++a)
                if (tet(k)[a] == node) renumbered[4 * k + static_cast<size_t>(a)] = n;
        }
    }

    void split_stars() {
        copies.clear();
        copy_of.clear();
        renumbered.resize(4 * cut.at_cut.size());
        for (size_t k = 0; k < cut.at_cut.size(); ++k) std::copy(tet(k), tet(k) + 4, &renumbered[4 * k]);
        join_stars_across_faces();
        star_members.assign(star.size(), 0);
        star_number.assign(star.size(), -1);
        for (size_t begin = 0; begin < star.size();) {
            size_t end = begin + 1;
            while (end < star.size() && star[end].first == star[begin].first) ++end;
            number_star_pieces(begin, end);
            begin = end;
        }
    }

    int32_t original(int32_t node) const {
        const int32_t first_copy = node_count + static_cast<int32_t>(cut.origins.size());
        return node >= first_copy ? copy_of[static_cast<size_t>(node - first_copy)] : node;
    }

    bool touches_cut(const Face& f) const {
        return is_cut_node(original(f[0])) || is_cut_node(original(f[1])) || is_cut_node(original(f[2]));
    }

    // The surface faces among the tets at the cut that have a node on the cut, by renumbered
    // nodes. (Every face with a node on the cut lies between tets at the cut, so the surface
    // faces there are those named once among them.)
    vec<Face> surface_at_cut() const {
        vec<Face> faces;
        for (size_t k = 0; k < cut.at_cut.size(); ++k)
            for (int f = 0; f < 4; ++f) {
                const Face face = sorted_face(&renumbered[4 * k], f);
                if (touches_cut(face)) faces.push_back(face);
            }
        std::sort(faces.begin(), faces.end());
        vec<Face> surface;
        for (size_t i = 0; i < faces.size(); ++i) {
            const bool shared = (i + 1 < faces.size() && faces[i + 1] == faces[i]) || (i > 0 && faces[i - 1] == faces[i]);
            if (!shared) surface.push_back(faces[i]);
        }
        return surface;
    }

    // Surface edges (renumbered) on more than two surface faces, as edges of original nodes.
    vec<uint64_t> pinched_edges(const vec<Face>& surface) const {
        vec<uint64_t> edges, pinched;
        for (const Face& f : surface)
            edges.push_back(edge_key(f[0], f[1])), edges.push_back(edge_key(f[0], f[2])), edges.push_back(edge_key(f[1], f[2]));
        std::sort(edges.begin(), edges.end());
        for (size_t i = 0; i + 2 < edges.size(); ++i)
            if (edges[i] == edges[i + 2]) pinched.push_back(edge_key(original(edge_end(edges[i], 0)), original(edge_end(edges[i], 1))));
        return pinched;
    }

    // Surface nodes (renumbered) on the cut whose surface faces form more than one fan, as
    // original nodes.
    vec<int32_t> pinched_nodes(const vec<Face>& surface) const {
        vec<std::pair<int32_t, std::array<int32_t, 2>>> links;  // (node, the opposite edge of a face on it)
        for (const Face& f : surface)
            for (int k = 0; k < 3; ++k) links.push_back({f[k], {f[(k + 1) % 3], f[(k + 2) % 3]}});
        std::sort(links.begin(), links.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
        vec<int32_t> pinched, ends, parent;
        for (size_t begin = 0; begin < links.size();) {
            size_t end = begin + 1;
            while (end < links.size() && links[end].first == links[begin].first) ++end;
            ends.clear();
            for (size_t i = begin; i < end; ++i) ends.push_back(links[i].second[0]), ends.push_back(links[i].second[1]);
            std::sort(ends.begin(), ends.end());
            ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
            parent.resize(ends.size());
            std::iota(parent.begin(), parent.end(), 0);
            const auto slot = [&](int32_t n) { return static_cast<int32_t>(std::lower_bound(ends.begin(), ends.end(), n) - ends.begin()); };
            for (size_t i = begin; i < end; ++i)
                union_join(parent, slot(links[i].second[0]), slot(links[i].second[1]));
            int32_t fans = 0;
            for (size_t i = 0; i < ends.size(); ++i) fans += union_root(parent, static_cast<int32_t>(i)) == static_cast<int32_t>(i) ? 1 : 0;
            if (fans > 1 && is_cut_node(original(links[begin].first))) pinched.push_back(original(links[begin].first));
            begin = end;
        }
        return pinched;
    }

    // Cut faces along an edge that would join more than two surface faces, or at a node whose
    // surface would be two fans touching at a point, are glued back; true if any was.
    bool glue_pinches() {
        const vec<Face> surface = surface_at_cut();
        const vec<uint64_t> edges = pinched_edges(surface);
        vec<int32_t> nodes = pinched_nodes(surface);
        if (edges.empty() && nodes.empty()) return false;
        std::sort(nodes.begin(), nodes.end());
        const size_t before = cut_faces.size();
        const auto pinched = [&](const Face& f) {
            for (int c = 0; c < 3; ++c)
                if (std::binary_search(nodes.begin(), nodes.end(), f[c])) return true;
            for (const uint64_t e : edges)
                if (f.has(edge_end(e, 0)) && f.has(edge_end(e, 1))) return true;
            return false;
        };
        cut_faces.erase(std::remove_if(cut_faces.begin(), cut_faces.end(), pinched), cut_faces.end());
        return cut_faces.size() < before;  // a pinch no cut face made stays as it came
    }

    // Cut faces whose two tets no longer name the same three nodes.
    int32_t parted_faces() const {
        vec<std::pair<Face, Face>> sides;  // (cut face, the face as a tet on it names it now)
        for (size_t k = 0; k < cut.at_cut.size(); ++k)
            for (int f = 0; f < 4; ++f) {
                const Face face = sorted_face(tet(k), f);
                if (std::binary_search(cut_faces.begin(), cut_faces.end(), face))
                    sides.push_back({face, sorted_face(&renumbered[4 * k], f)});
            }
        std::sort(sides.begin(), sides.end());
        int32_t parted = 0;
        for (size_t i = 0; i + 1 < sides.size(); ++i)
            parted += sides[i].first == sides[i + 1].first && sides[i].second != sides[i + 1].second ? 1 : 0;
        return parted;
    }
};

}  // namespace

int32_t separate(TetCut& cut, int32_t node_count) {
    Separation s(cut, node_count);
    s.build_star();
    s.find_cut_faces();
    do s.split_stars();
    while (s.glue_pinches());
    const int32_t parted = s.parted_faces();
    for (size_t k = 0; k < cut.at_cut.size(); ++k)
        std::copy(&s.renumbered[4 * k], &s.renumbered[4 * k] + 4, &cut.tets[4 * static_cast<size_t>(cut.at_cut[k])]);
    cut.origins.insert(cut.origins.end(), s.copies.begin(), s.copies.end());
    return parted;
}

}  // namespace sh
