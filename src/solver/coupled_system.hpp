// CoupledSystem: one sparse system over the free DOFs of several bodies that act on each other
// (bodies in contact), so that one Newton loop solves for all of them: each body's own system
// (elements, field, mass) scattered in, plus the blocks its field couples to the other bodies.
#pragma once

#include "solver/implicit_integrator.hpp"

#include <cmath>
#include <cstdint>

namespace sh {

/// A body of a CoupledSystem.
struct CoupledMember {
    SteppedBody* stepped = nullptr;  ///< the body; its implicit state holds its own system,
                                     ///< filled before it is added in
    int32_t offset = 0;              ///< its first DOF in the joint system
    vec<int32_t> joint_index;        ///< per node: its free-node index in the joint system, or -1
    vec<int32_t> slots;              ///< per value slot of its own system: the joint value slot
    uint64_t pattern_id = 0;         ///< its own system's pattern when the joint one was built

    Body& body() const { return *stepped->body; }
    ImplicitState& state() const { return *stepped->implicit; }
};

/// The joint system of bodies solved together. Its pattern is the union of the members' own
/// patterns (each at its offset) and the blocks their fields couple between members, kept
/// across calls (and grown) while it covers what they need.
class CoupledSystem : public NewtonSystem {
public:
    /// Takes bodies[0..count) (each with its implicit state) as members, in that order:
    /// prepares each state's own pattern (without a solver of its own) and rebuilds the joint
    /// pattern, solver (from settings) and symbolic analysis if the members, their free nodes
    /// or their sizes changed, or if their fields now couple nodes the pattern has no block for.
    void prepare(SteppedBody* const* bodies, int32_t count, const sh_implicit_settings& settings);

    int32_t member_count() const { return static_cast<int32_t>(members_.size()); }
    CoupledMember& member(int32_t m) { return members_[static_cast<size_t>(m)]; }
    const CoupledMember& member(int32_t m) const { return members_[static_cast<size_t>(m)]; }

    /// Sum of the members' matrix versions: changes whenever one of them does.
    uint64_t matrix_version() const;

    /// Clears the joint system; for each member calls assemble_member(member), which fills the
    /// member's own system and returns the round-off of its forces, and adds that system in;
    /// then adds the blocks stiffness_scale K + damping_scale D that the members' fields
    /// couple between them (at rest: without velocities). Returns the members' round-offs
    /// combined (root of the sum of squares).
    template <class AssembleMember>
    double assemble(AssembleMember&& assemble_member, double stiffness_scale, double damping_scale, bool at_rest) {
        system.clear_values();
        double roundoff2 = 0.0;
        for (CoupledMember& m : members_) {
            const double roundoff = assemble_member(m);
            roundoff2 += roundoff * roundoff;
            add_member_values(m);
        }
        add_coupling(stiffness_scale, damping_scale, at_rest);
        return std::sqrt(roundoff2);
    }

private:
    /// Adds the values of m's own system into the joint one.
    void add_member_values(const CoupledMember& m);
    /// Adds the members' coupling blocks into the joint system.
    void add_coupling(double stiffness_scale, double damping_scale, bool at_rest);
    /// Fills needed_ with the sorted, distinct joint node pairs the members' fields couple.
    void collect_links();
    /// Builds the joint pattern from the members' patterns and links (taken as links_), the
    /// slot maps, the solver and its analysis; on failure nothing changes but the slot maps.
    void build(vec<uint64_t>& links, const sh_implicit_settings& settings);

    vec<CoupledMember> members_;
    vec<uint64_t> links_;   ///< coupled joint node pairs in the pattern: (i << 32) | j, i < j, sorted
    vec<uint64_t> needed_;  ///< the pairs the current contacts couple
    vec<int32_t> pairs_;    ///< scratch: node pairs as the fields report them
};

}  // namespace sh
