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

int32_t SurfaceIndex::find(const Key& key) const {
    const auto it = std::lower_bound(faces_.begin(), faces_.end(), std::make_pair(key, INT32_MIN));
    return it != faces_.end() && it->first == key ? it->second : -1;
}

void SurfaceIndex::update(const vec<int32_t>& triangles, const TetChange& change, size_t node_count,
                          vec<int32_t>& out_triangles, SurfaceIndex& out) const {
    const vec<Touched> faces = touched_faces(change);
    vec<uint8_t> removed(triangles.size() / 3, 0);
    vec<int32_t> added;
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
        const int32_t triangle = find(faces[i].key);
        i = j;
        // The unchanged tets on the face: it had one tet if it was on the boundary, else two
        // (a conforming mesh), of which `before` changed; a face no changed tet had before is
        // new, unless an unchanged tet has it on the boundary.
        const int on_boundary = triangle >= 0 ? 1 : 0;
        const int kept = before > 0 ? std::max(0, (on_boundary ? 1 : 2) - before) : on_boundary;
        if (triangle >= 0) removed[static_cast<size_t>(triangle)] = 1;
        if (kept + after != 1) continue;
        if (after == 1) {
            added.insert(added.end(), last_after->outward.begin(), last_after->outward.end());
        } else if (triangle >= 0) {
            removed[static_cast<size_t>(triangle)] = 0;  // an unchanged tet's face, still outside
        } else {
            // An unchanged tet's face that a changed tet covered: outward from the unchanged
            // tet is inward from the changed one.
            const Key& o = last_before->outward;
            added.insert(added.end(), {o[0], o[2], o[1]});
        }
    }
    vec<int32_t> result;
    result.reserve(triangles.size() + added.size());
    for (size_t t = 0; t < removed.size(); ++t)
        if (!removed[t]) result.insert(result.end(), &triangles[3 * t], &triangles[3 * t] + 3);
    const size_t first_added = result.size() / 3;
    result.insert(result.end(), added.begin(), added.end());
    SurfaceIndex index;
    rebuild_into(triangles, removed, result, first_added, node_count, index);
    out_triangles.swap(result);
    out.swap(index);
}

void SurfaceIndex::rebuild_into(const vec<int32_t>& triangles, const vec<uint8_t>& removed, const vec<int32_t>& out_triangles,
                                size_t first_added, size_t node_count, SurfaceIndex& out) const {
    vec<int32_t> renumbered(removed.size(), -1);
    int32_t next = 0;
    for (size_t t = 0; t < removed.size(); ++t)
        if (!removed[t]) renumbered[t] = next++;
    const size_t total = out_triangles.size() / 3;
    vec<std::pair<Key, int32_t>> kept, added, merged;
    kept.reserve(first_added);
    for (const auto& face : faces_)
        if (!removed[static_cast<size_t>(face.second)]) kept.push_back({face.first, renumbered[static_cast<size_t>(face.second)]});
    added.reserve(total - first_added);
    for (size_t t = first_added; t < total; ++t)
        added.push_back({sorted(Key{out_triangles[3 * t], out_triangles[3 * t + 1], out_triangles[3 * t + 2]}), static_cast<int32_t>(t)});
    std::sort(added.begin(), added.end());
    merged.resize(kept.size() + added.size());
    std::merge(kept.begin(), kept.end(), added.begin(), added.end(), merged.begin());
    vec<int32_t> node_faces(node_count, 0);
    std::copy(node_faces_.begin(), node_faces_.begin() + static_cast<ptrdiff_t>(std::min(node_count, node_faces_.size())),
              node_faces.begin());
    for (size_t t = 0; t < removed.size(); ++t)
        if (removed[t])
            for (int c = 0; c < 3; ++c) --node_faces[static_cast<size_t>(triangles[3 * t + static_cast<size_t>(c)])];
    for (size_t t = first_added; t < total; ++t)
        for (int c = 0; c < 3; ++c) ++node_faces[static_cast<size_t>(out_triangles[3 * t + static_cast<size_t>(c)])];
    out.faces_.swap(merged);
    out.node_faces_.swap(node_faces);
}

}  // namespace sh
