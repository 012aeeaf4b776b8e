// SurfaceIndex: a tet mesh's boundary triangles looked up by their nodes, so that when a few
// tets change (a cut, a refinement) the new boundary follows from those tets alone instead of
// from sorting every face of the mesh again.
#pragma once

#include "core/memory.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>

namespace sh {

/// A local change of a tet mesh: its tets before (old_count) and after (new_count), 4 node
/// indices each and positively oriented, and the indices of the tets that differ (ascending;
/// those from old_count on are new). A tet not listed is the same before and after.
struct TetChange {
    const int32_t* old_tets;
    size_t old_count;
    const int32_t* new_tets;
    size_t new_count;
    const vec<int32_t>& changed;
};

/// The boundary faces of a conforming tet mesh (faces of exactly one tet), by their sorted
/// nodes, with how many boundary triangles touch each node.
class SurfaceIndex {
public:
    /// Indexes triangles (3 per, the boundary of a tet mesh) over node_count nodes.
    void build(const vec<int32_t>& triangles, size_t node_count);

    /// True if node is a corner of a boundary triangle.
    bool has_node(int32_t node) const {
        return static_cast<size_t>(node) < node_faces_.size() && node_faces_[static_cast<size_t>(node)] > 0;
    }

    /// The boundary after change, for triangles (the boundary this index was built or updated
    /// for), over node_count nodes: the triangles the change does not touch keep their order,
    /// the faces of changed tets that are now on the boundary (outward) follow. Writes it to
    /// out_triangles and its index to out; costs a linear copy of the index plus time in the
    /// changed tets' count. Throws std::bad_alloc, changing nothing.
    void update(const vec<int32_t>& triangles, const TetChange& change, size_t node_count, vec<int32_t>& out_triangles,
                SurfaceIndex& out) const;

    /// Exchanges the contents with other (never allocates).
    void swap(SurfaceIndex& other) noexcept {
        faces_.swap(other.faces_);
        node_faces_.swap(other.node_faces_);
    }

private:
    using Key = std::array<int32_t, 3>;
    /// A face of a changed tet, before or after the change.
    struct Touched {
        Key key;           ///< its nodes, sorted
        Key outward;       ///< its nodes, outward from that tet
        bool after;        ///< a face of a tet after the change (else before)
    };
    /// The faces of the changed tets before and after, sorted by key.
    static vec<Touched> touched_faces(const TetChange& change);
    /// The index of the boundary triangle with key, or -1.
    int32_t find(const Key& key) const;
    /// Fills out's faces_ and node_faces_ for out_triangles: this index without the removed
    /// triangles, renumbered, merged with the added ones (those from first_added on).
    void rebuild_into(const vec<int32_t>& triangles, const vec<uint8_t>& removed, const vec<int32_t>& out_triangles,
                      size_t first_added, size_t node_count, SurfaceIndex& out) const;

    vec<std::pair<Key, int32_t>> faces_;  ///< (sorted nodes, triangle index), by key
    vec<int32_t> node_faces_;             ///< per node: boundary triangles on it
};

}  // namespace sh
