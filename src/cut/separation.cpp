#include "cut/separation.hpp"

#include "cut/tet_cut.hpp"
#include "mesh/tet_mesh.hpp"

#include <algorithm>
#include <numeric>

namespace sh {
namespace {

using Face = std::array<int32_t, 3>;


Face sorted_face(const int32_t* tet, int f) {
    Face face{tet[kTetFaces[f][0]], tet[kTetFaces[f][1]], tet[kTetFaces[f][2]]};
    std::sort(face.begin(), face.end());
    return face;
}

bool contains(const vec<int32_t>& sorted, int32_t value) { return std::binary_search(sorted.begin(), sorted.end(), value); }

// Union-find over a star's tets.
int32_t root(vec<int32_t>& parent, int32_t i) {
    while (parent[static_cast<size_t>(i)] != i) i = parent[static_cast<size_t>(i)] = parent[static_cast<size_t>(parent[static_cast<size_t>(i)])];
    return i;
}

// The separation's working state over the tets at the cut.
struct Separation {
    TetCut& cut;
    int32_t node_count;              // nodes before the cut
    vec<std::pair<int32_t, int32_t>> star;  // (cut node, index into cut.at_cut), by node
    vec<Face> cut_faces;             // faces between tets on opposite sides, sorted
    vec<int32_t> renumbered;         // 4 per tet at the cut: its nodes after copying
    vec<NodeOrigin> copies;          // the copies made
    vec<int32_t> copy_of;            // per copy: the node copied

    const int32_t* tet(size_t k) const { return &cut.tets[4 * static_cast<size_t>(cut.at_cut[k])]; }

    void build_star() {
        for (size_t k = 0; k < cut.at_cut.size(); ++k)
            for (int a = 0; a < 4; ++a)
                if (contains(cut.cut_nodes, tet(k)[a])) star.push_back({tet(k)[a], static_cast<int32_t>(k)});
        std::sort(star.begin(), star.end());
    }

    void find_cut_faces() {
        vec<std::pair<Face, int32_t>> faces;
        for (size_t k = 0; k < cut.at_cut.size(); ++k)
            for (int f = 0; f < 4; ++f) {
                const Face face = sorted_face(tet(k), f);
                if (contains(cut.cut_nodes, face[0]) && contains(cut.cut_nodes, face[1]) && contains(cut.cut_nodes, face[2]))
                    faces.push_back({face, static_cast<int32_t>(k)});
            }
        std::sort(faces.begin(), faces.end());
        for (size_t i = 0; i + 1 < faces.size(); ++i) {
            if (faces[i].first != faces[i + 1].first) continue;
            const int8_t a = cut.side[static_cast<size_t>(faces[i].second)], b = cut.side[static_cast<size_t>(faces[i + 1].second)];
            if (a != 0 && b != 0 && a != b) cut_faces.push_back(faces[i].first);
        }
    }

    // split_star's scratch, kept between stars so that each star allocates nothing.
    vec<int32_t> star_parent, star_members, star_number;
    vec<std::pair<Face, int32_t>> star_faces;

    // Copies node (whose star is star[begin, end)) once per extra connected piece of its star.
    void split_star(size_t begin, size_t end) {
        const int32_t node = star[begin].first;
        const int32_t size = static_cast<int32_t>(end - begin);
        star_parent.resize(static_cast<size_t>(size));
        std::iota(star_parent.begin(), star_parent.end(), 0);
        star_faces.clear();
        for (int32_t i = 0; i < size; ++i)
            for (int f = 0; f < 4; ++f) {
                const Face face = sorted_face(tet(static_cast<size_t>(star[begin + static_cast<size_t>(i)].second)), f);
                if (std::find(face.begin(), face.end(), node) != face.end()) star_faces.push_back({face, i});
            }
        std::sort(star_faces.begin(), star_faces.end());
        for (size_t i = 0; i + 1 < star_faces.size(); ++i)
            if (star_faces[i].first == star_faces[i + 1].first && !std::binary_search(cut_faces.begin(), cut_faces.end(), star_faces[i].first))
                star_parent[static_cast<size_t>(root(star_parent, star_faces[i].second))] = root(star_parent, star_faces[i + 1].second);
        // The largest piece keeps the node; every other piece gets a copy.
        star_members.assign(static_cast<size_t>(size), 0);
        for (int32_t i = 0; i < size; ++i) ++star_members[static_cast<size_t>(root(star_parent, i))];
        const int32_t keeper = static_cast<int32_t>(std::max_element(star_members.begin(), star_members.end()) - star_members.begin());
        star_number.assign(static_cast<size_t>(size), -1);
        star_number[static_cast<size_t>(keeper)] = node;
        for (int32_t i = 0; i < size; ++i) {
            int32_t& n = star_number[static_cast<size_t>(root(star_parent, i))];
            if (n < 0) {
                n = node_count + static_cast<int32_t>(cut.origins.size() + copies.size());
                copies.push_back(NodeOrigin{node, node, 0.0});
                copy_of.push_back(node);
            }
            const size_t k = static_cast<size_t>(star[begin + static_cast<size_t>(i)].second);
            for (int a = 0; a < 4; ++a)
                if (tet(k)[a] == node) renumbered[4 * k + static_cast<size_t>(a)] = n;
        }
    }

    void split_stars() {
        copies.clear();
        copy_of.clear();
        renumbered.resize(4 * cut.at_cut.size());
        for (size_t k = 0; k < cut.at_cut.size(); ++k) std::copy(tet(k), tet(k) + 4, &renumbered[4 * k]);
        for (size_t begin = 0; begin < star.size();) {
            size_t end = begin + 1;
            while (end < star.size() && star[end].first == star[begin].first) ++end;
            split_star(begin, end);
            begin = end;
        }
    }

    int32_t original(int32_t node) const {
        const int32_t first_copy = node_count + static_cast<int32_t>(cut.origins.size());
        return node >= first_copy ? copy_of[static_cast<size_t>(node - first_copy)] : node;
    }

    bool touches_cut(const Face& f) const {
        return contains(cut.cut_nodes, original(f[0])) || contains(cut.cut_nodes, original(f[1])) ||
               contains(cut.cut_nodes, original(f[2]));
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
    vec<std::array<int32_t, 2>> pinched_edges(const vec<Face>& surface) const {
        vec<std::array<int32_t, 2>> edges, pinched;
        for (const Face& f : surface) edges.push_back({f[0], f[1]}), edges.push_back({f[0], f[2]}), edges.push_back({f[1], f[2]});
        std::sort(edges.begin(), edges.end());
        for (size_t i = 0; i + 2 < edges.size(); ++i)
            if (edges[i] == edges[i + 2]) {
                std::array<int32_t, 2> e{original(edges[i][0]), original(edges[i][1])};
                std::sort(e.begin(), e.end());
                pinched.push_back(e);
            }
        return pinched;
    }

    // Surface nodes (renumbered) on the cut whose surface faces form more than one fan, as
    // original nodes.
    vec<int32_t> pinched_nodes(const vec<Face>& surface) const {
        vec<std::pair<int32_t, std::array<int32_t, 2>>> links;  // (node, the opposite edge of a face on it)
        for (const Face& f : surface)
            for (int k = 0; k < 3; ++k) links.push_back({f[k], {f[(k + 1) % 3], f[(k + 2) % 3]}});
        std::sort(links.begin(), links.end());
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
                parent[static_cast<size_t>(root(parent, slot(links[i].second[0])))] = root(parent, slot(links[i].second[1]));
            int32_t fans = 0;
            for (size_t i = 0; i < ends.size(); ++i) fans += root(parent, static_cast<int32_t>(i)) == static_cast<int32_t>(i) ? 1 : 0;
            if (fans > 1 && contains(cut.cut_nodes, original(links[begin].first))) pinched.push_back(original(links[begin].first));
            begin = end;
        }
        return pinched;
    }

    // Cut faces along an edge that would join more than two surface faces, or at a node whose
    // surface would be two fans touching at a point, are glued back; true if any was.
    bool glue_pinches() {
        const vec<Face> surface = surface_at_cut();
        const vec<std::array<int32_t, 2>> edges = pinched_edges(surface);
        vec<int32_t> nodes = pinched_nodes(surface);
        if (edges.empty() && nodes.empty()) return false;
        std::sort(nodes.begin(), nodes.end());
        const size_t before = cut_faces.size();
        const auto pinched = [&](const Face& f) {
            for (const int32_t n : f)
                if (std::binary_search(nodes.begin(), nodes.end(), n)) return true;
            for (const auto& e : edges)
                if (std::count(f.begin(), f.end(), e[0]) && std::count(f.begin(), f.end(), e[1])) return true;
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
    Separation s{cut, node_count, {}, {}, {}, {}, {}, {}, {}, {}, {}};
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
