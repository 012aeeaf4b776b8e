#include "solver/joint_pattern.hpp"

#include "core/error.hpp"
#include "model/external_field.hpp"
#include "solver/node_links.hpp"

#include <algorithm>
#include <utility>

namespace sh {

void map_joint_nodes(vec<CoupledMember>& members) {
    for (CoupledMember& member : members) {
        const int32_t n = member.body().node_count();
        member.joint_index.assign(static_cast<size_t>(n), -1);
        for (int32_t i = 0; i < n; ++i) {
            const int32_t f = member.state().free_index[static_cast<size_t>(i)];
            if (f >= 0) member.joint_index[static_cast<size_t>(i)] = member.offset / 3 + f;
        }
    }
}

void collect_coupled_links(const vec<CoupledMember>& members, vec<int32_t>& pairs, vec<uint64_t>& needed) {
    pairs.clear();
    for (const CoupledMember& a : members) {
        if (!a.body().field) continue;
        for (const CoupledMember& b : members)
            if (&a != &b)
                a.body().field->add_coupling_pattern(b.body(), a.joint_index.data(), b.joint_index.data(), pairs);
    }
    collect_link_keys(pairs, needed);
}

SparseSystem build_joint_pattern(const vec<CoupledMember>& members, const vec<uint64_t>& links) {
    // The joint pattern from two-node "elements": every block a member's pattern has, at its
    // offset, and every coupled pair.
    int32_t nodes = 0;
    vec<int32_t> elements;
    for (const CoupledMember& m : members) {
        const SparseSystem& own = m.state().matrix.system;
        const vec<int32_t>& starts = own.column_starts();
        const vec<int32_t>& rows = own.row_indices();
        const int32_t base = m.offset / 3;
        for (int32_t column = 0; column < own.dof_count(); column += 3)
            for (int32_t p = starts[static_cast<size_t>(column)]; p < starts[static_cast<size_t>(column) + 1]; ++p) {
                const int32_t row = rows[static_cast<size_t>(p)];
                if (row % 3 != 0 || row / 3 == column / 3) continue;
                elements.push_back(base + row / 3);
                elements.push_back(base + column / 3);
            }
        nodes += own.dof_count() / 3;
    }
    vec<int32_t> link_pairs;
    link_key_pairs(links, link_pairs);
    vec<int32_t> identity(static_cast<size_t>(nodes));
    for (int32_t i = 0; i < nodes; ++i) identity[static_cast<size_t>(i)] = i;
    SparseSystem joint;
    joint.build_pattern(elements.data(), elements.size() / 2, 2, identity.data(), nodes, nodes, link_pairs.data(),
                        link_pairs.size() / 2);
    return joint;
}

void map_member_slots(vec<CoupledMember>& members, const SparseSystem& joint) {
    // Each member value slot's place in the joint matrix: same column and row, shifted.
    const vec<int32_t>& starts = joint.column_starts();
    const vec<int32_t>& rows = joint.row_indices();
    for (CoupledMember& m : members) {
        const SparseSystem& own = m.state().matrix.system;
        m.slots.resize(own.row_indices().size());
        for (int32_t column = 0; column < own.dof_count(); ++column)
            for (int32_t p = own.column_starts()[static_cast<size_t>(column)];
                 p < own.column_starts()[static_cast<size_t>(column) + 1]; ++p) {
                const int32_t row = m.offset + own.row_indices()[static_cast<size_t>(p)];
                const int32_t* first = rows.data() + starts[static_cast<size_t>(m.offset + column)];
                const int32_t* last = rows.data() + starts[static_cast<size_t>(m.offset + column) + 1];
                const int32_t* slot = std::lower_bound(first, last, row);
                SH_REQUIRE(slot != last && *slot == row, SH_ERR_INTERNAL, "coupled system: no joint slot for row %d", row);
                m.slots[static_cast<size_t>(p)] = static_cast<int32_t>(slot - rows.data());
            }
    }
}

}  // namespace sh
