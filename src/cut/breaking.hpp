// The physical breaking criterion: the blade's edge holds the material just ahead of it and
// drags it along, and the material breaks ahead of the blade once the work the blade has done
// since the last break pays for the new crack (an energy balance).
#pragma once

#include "core/id_pool.hpp"
#include "core/memory.hpp"

#include <cstdint>

namespace sh {

class Body;
class World;
struct Collider;

/// What a tool with the physical criterion keeps of one body between steps.
struct BreakState {
    double work = 0.0;       ///< work (J) the blade did on the body since the last break
    vec<int32_t> held;       ///< the nodes the edge holds, ascending
    vec<double> previous;    ///< their positions (3 each) when the work was last counted
    vec<double> forces;      ///< the material's force on each (3 each) at the last step's end
    double needed = 0.0;     ///< the work (J) a break costs at the blade's last engagement
    uint64_t hold = 0;       ///< counts the holds: each new set of nodes held gets the next
};

/// The blade of tool against body at the tool's pose before this step's motion.
struct Engagement {
    double length = 0.0;     ///< of the blade inside the material (m)
    double toughness = 0.0;  ///< G_c (J/m^2) of the material at the middle of that part
};

/// Where tool's blade (at its start pose) lies in body: samples along the edge whose rest
/// mapping falls inside a tet (or on its faces, within a twentieth of its size: the walls of
/// the blade's own slit meet on the plane the edge runs in) make up the engaged length.
Engagement engage(const Body& body, const Collider& tool);

/// The crack a break opens: the blade's edge at the tool's start pose swept by `advance` (m)
/// along the step's motion (start to target) with its part along the edge removed, as two
/// triangles in the world frame (18 doubles), laid out as a swept blade's. False if the
/// motion runs along the edge or is nil.
bool crack_ahead(const Collider& tool, double advance, double triangles[18]);

/// Measures, after a step, the material's force on each held node (state.forces) and their sum
/// in force (N, world): what the material pushes the blade with.
void measure_held(const Body& body, BreakState& state, double force[3]);

/// The work (J) the blade did holding the nodes against the material since the last count:
/// their displacement against the forces measure_held found at the step's end.
double pending_work(const Body& body, const BreakState& state);

/// Adds pending_work to state.work and takes the held nodes' current positions as the next
/// count's start.
void count_work(const Body& body, BreakState& state);

/// Holds the free nodes of body the blade's edge meets, if it holds none: those not on the cut
/// (cut_nodes, ascending: the crack's walls) within half of `reach` ahead of the edge along the
/// step's motion and of the crack plane, alongside the edge. Then moves every held node with
/// the step's motion across the edge, prescribing their targets through the body's kinematic
/// nodes.
void hold_ahead(Body& body, const Collider& tool, double reach, const vec<int32_t>& cut_nodes, BreakState& state);

/// The crack a break opens, in body's rest shape (18 doubles, laid out as a swept blade's):
/// from the blade's edge at the tool's start pose to `advance` (m of rest length) beyond the
/// crack's front (the farthest of cut_nodes, ascending, near the crack plane alongside the
/// edge), and at least through the held nodes, along the motion across the edge as the rest
/// shape sees it. The crack then grows by about the engaged length times `advance`, the area
/// the work paid for. False if the motion runs along the edge or is nil.
bool break_at_rest(const Body& body, const Collider& tool, const BreakState& state, const vec<int32_t>& cut_nodes, double advance,
                   double rest[18]);

/// Lets the held nodes go (the material broke, or the blade left it).
void release(Body& body, BreakState& state);

}  // namespace sh
