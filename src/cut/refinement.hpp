// Refinement ahead of a cut: the tets around where a cut ends are bisected until they are
// small, because a cut parts the material only along whole tet faces: on a coarse mesh a
// blade's front and depth would otherwise stop the opening up to an element short of them.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <cstdint>

namespace sh {

class FemBody;

/// A body's tets after refinement, to hand to FemBody::retopologize.
struct Refinement {
    /// New nodes, each the midpoint of an edge (whose ends may be new nodes listed earlier).
    vec<NodeOrigin> origins;
    /// The element list after (4 nodes per tet, oriented as the tets they come from).
    vec<int32_t> tets;
    /// Per tet of tets: the body tet it is, or -1 - s for a piece of body tet s.
    vec<int32_t> source;
};

/// Bisects the tets of body that one of the segments (segment_count of them, 6 doubles each:
/// two points of its rest shape) passes through until none of those has an edge longer than
/// edge_length. Each round splits, at its midpoint, the longest edge of every
/// such tet and of every tet that has an edge split (longest-edge bisection, which keeps the
/// pieces' shapes within a bounded family, Rivara 1991); every tet around a split edge is
/// split along it in one global order, so the mesh stays conforming. At most max_new_tets
/// tets are added; empty origins if nothing needed refining.
Refinement refine_near(const FemBody& body, const double* segments, int32_t segment_count, double edge_length,
                       int32_t max_new_tets);

}  // namespace sh
