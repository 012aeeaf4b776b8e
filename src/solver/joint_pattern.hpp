// The joint pattern of bodies solved together (a NewtonProblem over bodies in contact): where
// each body's free nodes and value slots sit in the joint matrix, and which node pairs of
// different bodies their fields couple.
#pragma once

#include "core/memory.hpp"
#include "linalg/sparse_system.hpp"
#include "model/body.hpp"
#include "solver/newton_body_state.hpp"
#include "solver/stepped_body.hpp"

#include <cstdint>

namespace sh {

/// A body of a NewtonProblem over bodies solved together, and its place in their joint matrix.
struct CoupledMember {
    SteppedBody* stepped = nullptr;  ///< the body; its NewtonBodyState holds its own matrix,
                                     ///< assembled before it is added into the joint one
    int32_t offset = 0;              ///< its first DOF in the joint matrix
    vec<int32_t> joint_index;        ///< per node: its free-node index in the joint matrix, or -1
    vec<int32_t> slots;              ///< per value slot of its own matrix: the joint value slot
    uint64_t pattern_id = 0;         ///< its own matrix's pattern when the joint one was built

    /// The member's body.
    Body& body() const { return *stepped->body; }
    /// The member's per-body Newton data (its free-node map and own matrix).
    NewtonBodyState& state() const { return *stepped->newton; }
};

/// Fills each member's joint_index from its offset and its free-node map.
void map_joint_nodes(vec<CoupledMember>& members);

/// Fills needed with the sorted, distinct joint node pairs ((i << 32) | j, i < j) that the
/// members' fields couple; pairs is scratch.
void collect_coupled_links(const vec<CoupledMember>& members, vec<int32_t>& pairs, vec<uint64_t>& needed);

/// The joint pattern: every node block of each member's own pattern, at its offset, and a block
/// for every pair in links. Joint free node i is node i.
SparseSystem build_joint_pattern(const vec<CoupledMember>& members, const vec<uint64_t>& links);

/// Fills each member's slots: the value slot in joint of each value slot of its own matrix.
/// Throws SH_ERR_INTERNAL if joint lacks one.
void map_member_slots(vec<CoupledMember>& members, const SparseSystem& joint);

}  // namespace sh
