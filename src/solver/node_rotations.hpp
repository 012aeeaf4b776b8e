// Each free node's rotation from the rest shape to the current one, for the warped multigrid
// preconditioner of implicit steps (linalg/warped_multigrid.hpp): the rotation of the polar
// decomposition of the node's least-squares deformation gradient F_i = S_i Q_i^-1, with
// S_i = sum (x_j - x_i)(X_j - X_i)^T and Q_i = sum (X_j - X_i)(X_j - X_i)^T over the element
// edges from i (X rest, x current). Each call starts from the last call's rotations, which one
// or two Newton updates carry to the new ones.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"

#include <cstdint>

namespace sh {

/// Free nodes' rotations of one body (see the file comment).
class NodeRotations {
public:
    /// Starts over for a body whose free DOF d stands for body DOF dof_to_global[d] (3 per free
    /// node, x y z in order): identity rotations. Allocates.
    void reset(const Body& body, const vec<int32_t>& dof_to_global);
    /// The rotations at body's current positions (9 per free node, row-major, rest frame to
    /// current), from the last ones.
    const double* update(const Body& body);
    /// Free nodes it holds.
    size_t size() const { return rotation_.size() / 9; }
    /// The largest angle (rad, to second order) any node turned by in the last update.
    double last_turn() const { return last_turn_; }

    /// An element edge with a free end: body nodes a < b, their free nodes (-1 if not free),
    /// and how many elements share it.
    struct Edge {
        int32_t a, b, free_a, free_b;
        double weight;
    };

private:
    vec<Edge> edges_;
    vec<double> shape_;      // 9 per free node: S_i
    vec<double> inverse_rest_;  // 9 per free node: Q_i^-1 (Q_i / tr Q_i^2 where Q_i is singular)
    vec<double> rotation_;   // 9 per free node
    double last_turn_ = 0.0;
};

}  // namespace sh
