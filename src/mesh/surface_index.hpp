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

/// What a local change does to a boundary: the triangles that leave it and those that join it.
struct SurfaceEdit {
    vec<int32_t> removed;  ///< indices of the triangles no longer on the boundary, ascending
    vec<int32_t> added;    ///< the new boundary triangles, 3 nodes each, outward
};

/// The boundary faces of a conforming tet mesh (faces of exactly one tet), by their sorted
/// nodes, with how many boundary triangles touch each node. A local change of the mesh edits
/// the boundary and the index in place, in time in the changed tets' count plus one pass of
/// memory moves over the index (no sort, no renumbering of untouched triangles).
class SurfaceIndex {
public:
    /// Indexes triangles (3 per, the boundary of a tet mesh) over node_count nodes.
    void build(const vec<int32_t>& triangles, size_t node_count);

    /// True if node is a corner of a boundary triangle.
    bool has_node(int32_t node) const {
        return static_cast<size_t>(node) < node_faces_.size() && node_faces_[static_cast<size_t>(node)] > 0;
    }

    /// The edit that change makes to the boundary this index describes (the one it was built
    /// or last edited for). Throws std::bad_alloc, changing nothing.
    SurfaceEdit plan(const TetChange& change) const;

    /// Makes room in triangles and in the index for edit over node_count nodes, so that apply
    /// allocates nothing. Throws std::bad_alloc, changing no contents (only capacities).
    void reserve(vec<int32_t>& triangles, const SurfaceEdit& edit, size_t node_count);

    /// Applies edit (from plan, with reserve done) to triangles and to the index, over
    /// node_count nodes: added triangles fill the removed ones' places, then the last
    /// triangles fill those left, or the rest of the added ones go at the end. Never allocates.
    void apply(vec<int32_t>& triangles, const SurfaceEdit& edit, size_t node_count) noexcept;

    /// Exchanges the contents with other (never allocates).
    void swap(SurfaceIndex& other) noexcept {
        faces_.swap(other.faces_);
        node_faces_.swap(other.node_faces_);
        removed_keys_.swap(other.removed_keys_);
        added_entries_.swap(other.added_entries_);
        added_at_.swap(other.added_at_);
    }

private:
    using Key = std::array<int32_t, 3>;
    using Entry = std::pair<Key, int32_t>;  ///< (sorted nodes, triangle index)
    /// A face of a changed tet, before or after the change.
    struct Touched {
        Key key;           ///< its nodes, sorted
        Key outward;       ///< its nodes, outward from that tet
        bool after;        ///< a face of a tet after the change (else before)
    };
    /// The faces of the changed tets before and after, sorted by key.
    static vec<Touched> touched_faces(const TetChange& change);
    /// The position in faces_ of the entry with key, or faces_.size().
    size_t position(const Key& key) const;
    /// Moves triangles into the places of edit's removed ones (the added first, then the last
    /// ones), appends the added that are left, and repoints the moved triangles' entries;
    /// the added triangles' new indices go to added_at.
    void place_triangles(vec<int32_t>& triangles, const SurfaceEdit& edit, int32_t* added_at) noexcept;
    /// Drops the entries of the removed triangles (keys in removed_keys, sorted) and merges in
    /// the added ones (sorted), in place within faces_'s capacity.
    void edit_entries(const Key* removed_keys, size_t removed_count, const Entry* added, size_t added_count) noexcept;

    vec<Entry> faces_;         ///< by key
    vec<int32_t> node_faces_;  ///< per node: boundary triangles on it
    vec<Key> removed_keys_;    ///< apply's scratch: the removed triangles' keys (reserved)
    vec<Entry> added_entries_; ///< apply's scratch: the added triangles' entries (reserved)
    vec<int32_t> added_at_;    ///< apply's scratch: where each added triangle went (reserved)
};

}  // namespace sh
