#include "solver/coupled_system.hpp"

#include "core/error.hpp"
#include "model/external_field.hpp"

#include <algorithm>
#include <iterator>

namespace sh {
namespace {

uint64_t link_key(int32_t i, int32_t j) {
    if (i > j) std::swap(i, j);
    return (static_cast<uint64_t>(static_cast<uint32_t>(i)) << 32) | static_cast<uint32_t>(j);
}

}  // namespace

void CoupledSystem::prepare(SteppedBody* const* bodies, int32_t count, const sh_implicit_settings& settings) {
    bool rebuild = !solver || member_count() != count;
    if (member_count() != count) members_.resize(static_cast<size_t>(count));
    int32_t offset = 0;
    for (int32_t m = 0; m < count; ++m) {
        CoupledMember& member = members_[static_cast<size_t>(m)];
        ImplicitState& state = *bodies[m]->implicit;
        const int32_t dofs = prepare_implicit_state(*bodies[m]->body, state, bodies[m]->settings.implicit, false);
        rebuild |= member.stepped != bodies[m] || member.offset != offset || member.pattern_id != state.system.pattern_id();
        member.stepped = bodies[m];
        member.offset = offset;
        state.factor_valid = false;  // its system holds this solve's values from now on
        offset += dofs;
    }
    if (rebuild)
        for (CoupledMember& member : members_) {
            const int32_t n = member.body().node_count();
            member.joint_index.assign(static_cast<size_t>(n), -1);
            for (int32_t i = 0; i < n; ++i) {
                const int32_t f = member.state().free_index[static_cast<size_t>(i)];
                if (f >= 0) member.joint_index[static_cast<size_t>(i)] = member.offset / 3 + f;
            }
        }
    collect_links();
    if (!rebuild && std::includes(links_.begin(), links_.end(), needed_.begin(), needed_.end())) return;
    // Keep the blocks of earlier contacts too (contacts come and go from step to step), unless
    // they have grown well beyond what the current ones need.
    vec<uint64_t> links;
    if (!rebuild) std::set_union(links_.begin(), links_.end(), needed_.begin(), needed_.end(), std::back_inserter(links));
    if (rebuild || links.size() > 2 * needed_.size() + 64) links = needed_;
    build(links, settings);
}

uint64_t CoupledSystem::matrix_version() const {
    uint64_t version = 0;
    for (const CoupledMember& m : members_) version += m.body().matrix_version;
    return version;
}

void CoupledSystem::collect_links() {
    needed_.clear();
    for (const CoupledMember& a : members_) {
        if (!a.body().field) continue;
        for (const CoupledMember& b : members_) {
            if (&a == &b) continue;
            pairs_.clear();
            a.body().field->add_coupling_pattern(b.body(), a.joint_index.data(), b.joint_index.data(), pairs_);
            for (size_t p = 0; p < pairs_.size(); p += 2) needed_.push_back(link_key(pairs_[p], pairs_[p + 1]));
        }
    }
    std::sort(needed_.begin(), needed_.end());
    needed_.erase(std::unique(needed_.begin(), needed_.end()), needed_.end());
}

void CoupledSystem::build(vec<uint64_t>& links, const sh_implicit_settings& settings) {
    // The joint pattern from two-node "elements": every block a member's pattern has, at its
    // offset, and every coupled pair. Joint free node i is node i.
    int32_t nodes = 0;
    vec<int32_t> elements;
    for (const CoupledMember& m : members_) {
        const SparseSystem& own = m.state().system;
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
    for (const uint64_t key : links) {
        elements.push_back(static_cast<int32_t>(key >> 32));
        elements.push_back(static_cast<int32_t>(key & 0xffffffffu));
    }
    vec<int32_t> identity(static_cast<size_t>(nodes));
    for (int32_t i = 0; i < nodes; ++i) identity[static_cast<size_t>(i)] = i;
    SparseSystem joint;
    joint.build_pattern(elements.data(), elements.size() / 2, 2, identity.data(), nodes, nodes);

    // Each member value slot's place in the joint system: same column and row, shifted.
    const vec<int32_t>& starts = joint.column_starts();
    const vec<int32_t>& rows = joint.row_indices();
    for (CoupledMember& m : members_) {
        const SparseSystem& own = m.state().system;
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
    LinearSolverPtr joint_solver = make_analysed_solver(joint, settings);
    const size_t dofs = static_cast<size_t>(joint.dof_count());
    vec<double> r(dofs), d(dofs, 0.0), p(dofs);
    system = std::move(joint);
    solver = std::move(joint_solver);
    links_.swap(links);
    residual.swap(r);
    delta.swap(d);
    previous_v.swap(p);
    factor_valid = false;
    for (CoupledMember& m : members_) m.pattern_id = m.state().system.pattern_id();
}

void CoupledSystem::add_member_values(const CoupledMember& m) {
    const vec<double>& own = m.state().system.values();
    double* joint = system.values().data();
    for (size_t p = 0; p < own.size(); ++p) joint[m.slots[p]] += own[p];
}

void CoupledSystem::add_coupling(double stiffness_scale, double damping_scale, bool at_rest) {
    for (const CoupledMember& a : members_) {
        if (!a.body().field) continue;
        for (const CoupledMember& b : members_)
            if (&a != &b)
                a.body().field->add_coupling_tangent(a.body().x.data(), at_rest ? nullptr : a.body().v.data(), stiffness_scale,
                                                    damping_scale, a.joint_index.data(), b.body(), b.joint_index.data(),
                                                    system);
    }
}

}  // namespace sh
