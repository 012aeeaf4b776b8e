// Separation: the tets on the two sides of a cut stop sharing nodes. Every node on the cut is
// copied once per extra piece of its star, so that parts joined only through a node come
// apart too and the surface stays a 2-manifold.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <array>
#include <cstdint>

namespace sh {

class TetCut;

/// Separates the material along cut (a TetCut of a body of node_count nodes before the cut):
/// appends to cut.origins a copy of each node on the cut for every extra face-connected piece
/// of its star (cut faces, between tets on opposite sides, do not connect), and renumbers
/// cut.tets to use them. A cut face whose edge would join more than two surface faces (a
/// slit narrower than an element) is glued back. Returns the number of faces that parted.
int32_t separate(TetCut& cut, int32_t node_count);

}  // namespace sh
