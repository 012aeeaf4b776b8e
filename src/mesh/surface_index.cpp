#include "mesh/surface_index.hpp"

#include "mesh/tet_mesh.hpp"

#include <algorithm>

namespace sh {
namespace {

template <class Key>
Key sorted(Key key) {
    std::sort(key.begin(), key.end());
    return key;
}

}  // namespace

void SurfaceIndex::build(const vec<int32_t>& triangles, size_t node_count) {
    const size_t count = triangles.size() / 3;
    vec<std::pair<Key, int32_t>> faces(count);
    vec<int32_t> node_faces(node_count, 0);
    for (size_t i = 0; i < count; ++i) {
        const Key outward{triangles[3 * i], triangles[3 * i + 1], triangles[3 * i + 2]};
        faces[i] = {sorted(outward), static_cast<int32_t>(i)};
        for (const int32_t node : outward) ++node_faces[static_cast<size_t>(node)];
    }
    std::sort(faces.begin(), faces.end());
    faces_.swap(faces);
    node_faces_.swap(node_faces);
}

vec<SurfaceIndex::Touched> SurfaceIndex::touched_faces(const TetChange& change) {
    vec<Touched> faces;
    faces.reserve(8 * change.changed.size());
    const auto add_faces = [&](const int32_t* tet, bool after) {
        for (const auto& f : kTetFaces) {
            const Key outward{tet[f[0]], tet[f[1]], tet[f[2]]};
            faces.push_back(Touched{sorted(outward), outward, after});
        }
    };
    for (const int32_t t : change.changed) {
        const size_t i = static_cast<size_t>(t);
        if (i < change.old_count) add_faces(change.old_tets + 4 * i, false);
        if (i < change.new_count) add_faces(change.new_tets + 4 * i, true);
    }
    std::sort(faces.begin(), faces.end(), [](const Touched& a, const Touched& b) { return a.key < b.key; });
    return faces;
}

size_t SurfaceIndex::position(const Key& key) const {
    const auto it = std::lower_bound(faces_.begin(), faces_.end(), Entry{key, INT32_MIN});
    return it != faces_.end() && it->first == key ? static_cast<size_t>(it - faces_.begin()) : faces_.size();
}

SurfaceEdit SurfaceIndex::plan(const TetChange& change) const {
    const vec<Touched> faces = touched_faces(change);
    SurfaceEdit edit;
    for (size_t i = 0; i < faces.size();) {
        size_t j = i;
        int before = 0, after = 0;
        const Touched *last_before = nullptr, *last_after = nullptr;
        for (; j < faces.size() && faces[j].key == faces[i].key; ++j) {
            if (faces[j].after)
                ++after, last_after = &faces[j];
            else
                ++before, last_before = &faces[j];
        }
        const size_t at = position(faces[i].key);
        const int32_t triangle = at < faces_.size() ? faces_[at].second : -1;
        i = j;
        // The unchanged tets on the face: it had one tet if it was on the boundary, else two
        // (a conforming mesh), of which `before` changed; a face no changed tet had before is
        // new, unless an unchanged tet has it on the boundary.
        const int on_boundary = triangle >= 0 ? 1 : 0;
        const int kept = before > 0 ? std::max(0, (on_boundary ? 1 : 2) - before) : on_boundary;
        bool leaves = triangle >= 0;
        if (kept + after == 1) {
            if (after == 1) {
                edit.added.insert(edit.added.end(), last_after->outward.begin(), last_after->outward.end());
            } else if (triangle >= 0) {
                leaves = false;  // an unchanged tet's face, still outside
            } else {
                // An unchanged tet's face that a changed tet covered: outward from the
                // unchanged tet is inward from the changed one.
                const Key& o = last_before->outward;
                edit.added.insert(edit.added.end(), {o[0], o[2], o[1]});
            }
        }
        if (leaves) edit.removed.push_back(triangle);
    }
    std::sort(edit.removed.begin(), edit.removed.end());
    return edit;
}

void SurfaceIndex::reserve(vec<int32_t>& triangles, const SurfaceEdit& edit, size_t node_count) {
    const size_t added = edit.added.size() / 3;
    reserve_growing(triangles, triangles.size() + 3 * added);
    reserve_growing(faces_, faces_.size() + added);
    reserve_growing(node_faces_, node_count);
    reserve_growing(removed_keys_, edit.removed.size());
    reserve_growing(added_entries_, added);
    reserve_growing(added_at_, added);
}

void SurfaceIndex::apply(vec<int32_t>& triangles, const SurfaceEdit& edit, size_t node_count) noexcept {
    node_faces_.resize(std::max(node_count, node_faces_.size()), 0);  // nodes are only ever added
    removed_keys_.clear();
    for (const int32_t t : edit.removed) {
        const int32_t* corners = &triangles[3 * static_cast<size_t>(t)];
        removed_keys_.push_back(sorted(Key{corners[0], corners[1], corners[2]}));
        for (int c = 0; c < 3; ++c) --node_faces_[static_cast<size_t>(corners[c])];
    }
    std::sort(removed_keys_.begin(), removed_keys_.end());
    for (const int32_t node : edit.added) ++node_faces_[static_cast<size_t>(node)];
    const size_t added = edit.added.size() / 3;
    added_at_.resize(added);
    place_triangles(triangles, edit, added_at_.data());
    added_entries_.clear();
    for (size_t k = 0; k < added; ++k) {
        const int32_t* corners = &edit.added[3 * k];
        added_entries_.push_back({sorted(Key{corners[0], corners[1], corners[2]}), added_at_[k]});
    }
    std::sort(added_entries_.begin(), added_entries_.end());
    edit_entries(removed_keys_.data(), removed_keys_.size(), added_entries_.data(), added);
}

void SurfaceIndex::place_triangles(vec<int32_t>& triangles, const SurfaceEdit& edit, int32_t* added_at) noexcept {
    const vec<int32_t>& holes = edit.removed;
    const size_t added = edit.added.size() / 3, filled = std::min(holes.size(), added);
    for (size_t k = 0; k < filled; ++k) {
        std::copy(&edit.added[3 * k], &edit.added[3 * k] + 3, &triangles[3 * static_cast<size_t>(holes[k])]);
        added_at[k] = holes[k];
    }
    for (size_t k = filled; k < added; ++k) {
        added_at[k] = static_cast<int32_t>(triangles.size() / 3);
        triangles.insert(triangles.end(), &edit.added[3 * k], &edit.added[3 * k] + 3);  // within capacity
    }
    // Holes left: the triangles past the new end that are not holes themselves move into the
    // holes before it, in order.
    const size_t count = triangles.size() / 3, left = holes.size() - filled, new_count = count - left;
    size_t hole = filled, past = filled;
    while (past < holes.size() && static_cast<size_t>(holes[past]) < new_count) ++past;
    for (size_t from = new_count; from < count; ++from) {
        if (past < holes.size() && static_cast<size_t>(holes[past]) == from) {
            ++past;
            continue;
        }
        const size_t to = static_cast<size_t>(holes[hole++]);
        const int32_t* corners = &triangles[3 * from];
        faces_[position(sorted(Key{corners[0], corners[1], corners[2]}))].second = static_cast<int32_t>(to);
        std::copy(corners, corners + 3, &triangles[3 * to]);
    }
    triangles.resize(3 * new_count);
}

void SurfaceIndex::edit_entries(const Key* removed_keys, size_t removed_count, const Entry* added,
                                size_t added_count) noexcept {
    // Drop the removed entries (both lists by key: one pass from the first of them).
    size_t write = removed_count > 0 ? position(removed_keys[0]) : faces_.size(), r = 0;
    for (size_t read = write; read < faces_.size(); ++read) {
        if (r < removed_count && faces_[read].first == removed_keys[r]) {
            ++r;
            continue;
        }
        faces_[write++] = faces_[read];
    }
    // Merge the added ones in from the back.
    size_t kept = write, total = write + added_count, a = added_count;
    faces_.resize(total);  // within capacity
    while (a > 0) {
        if (kept > 0 && added[a - 1].first < faces_[kept - 1].first)
            faces_[--total] = faces_[--kept];
        else
            faces_[--total] = added[--a];
    }
}

}  // namespace sh
