// FemBody's local topology change: a cut or a refinement that changes a few tets updates the
// body in place (emptied lanes and new blocks, moved lumped masses, the surface from the
// changed tets' faces) instead of rebuilding it (FemBody::adopt).
#include "model/fem_body.hpp"

#include <algorithm>

namespace sh {

vec<int32_t> FemBody::changed_tets(const vec<int32_t>& tets, const vec<int32_t>& source) const {
    vec<int32_t> changed;
    const size_t old_count = volume_.size();
    for (size_t t = 0; t < tets.size() / 4; ++t)
        if (t >= old_count || source[t] != static_cast<int32_t>(t) || !std::equal(&tets[4 * t], &tets[4 * t] + 4, &tets_[4 * t]))
            changed.push_back(static_cast<int32_t>(t));
    return changed;
}

bool FemBody::changes_locally(size_t changed, size_t old) const {
    size_t lanes = 0;
    for (const vec<TetBlock>& blocks : blocks_) lanes += blocks.size() * kLanes;
    // Emptied lanes cost force passes their time: past a quarter, every block is rebuilt.
    return 4 * changed <= volume_.size() && 4 * (vacant_lanes_ + old) <= lanes;
}

FemBody::ElementSet FemBody::fresh_elements(const GrownNodes& grown, const vec<int32_t>& tets, const vec<int32_t>& source,
                                            const vec<int32_t>& changed) const {
    const size_t count = changed.size();
    ElementSet fresh;
    fresh.tets.resize(4 * count), fresh.inverse_rest.resize(9 * count), fresh.volume.resize(count);
    fresh.materials.resize(count), fresh.omega2.resize(count);
    for (size_t k = 0; k < count; ++k) {
        const size_t t = static_cast<size_t>(changed[k]);
        std::copy(&tets[4 * t], &tets[4 * t] + 4, &fresh.tets[4 * k]);
        element_from_source(grown, &tets[4 * t], source[t], fresh, k);  // a piece's frequency: when asked for
    }
    return fresh;
}

void FemBody::fill_new_blocks(const ElementSet& fresh, vec<TetBlock> (&added)[SH_MATERIAL_COUNT], vec<int32_t>& lanes) const {
    const size_t count = fresh.volume.size();
    lanes.assign(count, -1);
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model) {
        vec<uint32_t> members;
        for (size_t k = 0; k < count; ++k)
            if (fresh.materials[k].model == model) members.push_back(static_cast<uint32_t>(k));
        added[model].assign(block_count(members.size()), TetBlock{});
        const size_t first = blocks_[model].size();
        spread_over_lanes(members.data(), members.size(), [&](uint32_t k, bool used, size_t block, int lane) {
            fill_lane(fresh, k, used, added[model][block], lane);
            if (used) lanes[k] = static_cast<int32_t>((first + block) * kLanes + static_cast<size_t>(lane));
        });
    }
}

void FemBody::move_masses(const vec<int32_t>& changed, const ElementSet& fresh) noexcept {
    // The changed tets' shares move from their old nodes to their new ones; only those nodes'
    // inverse masses change (appended nodes with no tet keep the zero adopt_nodes gave them).
    for (size_t k = 0; k < changed.size(); ++k) {
        const size_t t = static_cast<size_t>(changed[k]);
        if (t < volume_.size())
            for (int a = 0; a < 4; ++a) mass[static_cast<size_t>(tets_[4 * t + a])] -= materials_[t].density * volume_[t] / 4.0;
        for (int a = 0; a < 4; ++a) mass[static_cast<size_t>(fresh.tets[4 * k + a])] += fresh.materials[k].density * fresh.volume[k] / 4.0;
    }
    for (size_t k = 0; k < changed.size(); ++k) {
        const size_t t = static_cast<size_t>(changed[k]);
        if (t < volume_.size())
            for (int a = 0; a < 4; ++a) update_inverse_mass_of(static_cast<size_t>(tets_[4 * t + a]));
        for (int a = 0; a < 4; ++a) update_inverse_mass_of(static_cast<size_t>(fresh.tets[4 * k + a]));
    }
}

void FemBody::change_locally(GrownNodes& grown, const vec<int32_t>& tets, const vec<int32_t>& source, const vec<int32_t>& changed) {
    const size_t old_count = volume_.size(), new_count = tets.size() / 4;
    const ElementSet fresh = fresh_elements(grown, tets, source, changed);  // in changed's order
    const SurfaceEdit surface = surface_index_.plan(TetChange{tets_.data(), old_count, tets.data(), new_count, changed});
    vec<TetBlock> added[SH_MATERIAL_COUNT];  // after each model's own blocks
    vec<int32_t> lanes;
    fill_new_blocks(fresh, added, lanes);
    // Capacity first, so that nothing below allocates (amortised: a body cut again and again
    // does not copy its elements at every cut).
    reserve_growing(tets_, 4 * new_count), reserve_growing(inverse_rest_, 9 * new_count), reserve_growing(volume_, new_count);
    reserve_growing(materials_, new_count), reserve_growing(element_omega2_, new_count), reserve_growing(lane_of_, new_count);
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model)
        reserve_growing(blocks_[model], blocks_[model].size() + added[model].size());
    RotatingBlocks rotating;
    reserve_rotations(blocks_, added, rotating);
    surface_index_.reserve(surface_triangles, surface, grown.node_count());

    // Commit: nothing below allocates.
    adopt_nodes(grown);
    move_masses(changed, fresh);
    surface_index_.apply(surface_triangles, surface, grown.node_count());
    ++topology_version;
    for (const int32_t t : changed)
        if (static_cast<size_t>(t) < old_count) vacate_lane(static_cast<size_t>(t));
    tets_.resize(4 * new_count), inverse_rest_.resize(9 * new_count), volume_.resize(new_count), materials_.resize(new_count);
    element_omega2_.resize(new_count), lane_of_.resize(new_count);
    for (size_t k = 0; k < changed.size(); ++k) {
        const size_t t = static_cast<size_t>(changed[k]);
        std::copy(&fresh.tets[4 * k], &fresh.tets[4 * k] + 4, &tets_[4 * t]);
        std::copy(&fresh.inverse_rest[9 * k], &fresh.inverse_rest[9 * k] + 9, &inverse_rest_[9 * t]);
        volume_[t] = fresh.volume[k], materials_[t] = fresh.materials[k], element_omega2_[t] = fresh.omega2[k];
        lane_of_[t] = lanes[k];
    }
    for (int model = 0; model < SH_MATERIAL_COUNT; ++model)
        blocks_[model].insert(blocks_[model].end(), added[model].begin(), added[model].end());
    stable_step_known_ = false;  // new pieces' frequencies are found when the step is asked for
    rotations_.fit(rotating, true);
    ++matrix_version;
}

void FemBody::vacate_lane(size_t t) {
    TetBlock& b = blocks_[materials_[t].model][static_cast<size_t>(lane_of_[t]) / kLanes];
    const int lane = lane_of_[t] % kLanes;
    b.lambda_w[lane] = 0.0;
    b.mu_w[lane] = 0.0;
    // Like an unused lane, it repeats a live tet of its block (its old nodes may have parted).
    for (int l = 0; l < kLanes; ++l) {
        if (l == lane || b.mu_w[l] == 0.0) continue;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) b.Bm.m[i][j][lane] = b.Bm.m[i][j][l];
        for (int a = 0; a < 4; ++a) b.node[a][lane] = b.node[a][l];
        break;
    }
    ++vacant_lanes_;
}

}  // namespace sh
