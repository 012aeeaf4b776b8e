// Each free node's rotation from the rest shape to the current one, for the warped multigrid
// preconditioner of implicit steps (linalg/warped_multigrid.hpp): the rotation of the polar
// decomposition of the node's least-squares deformation gradient F_i = S_i Q_i^-1, with
// S_i = sum (x_j - x_i)(X_j - X_i)^T and Q_i = sum (X_j - X_i)(X_j - X_i)^T over the element
// edges from i (X rest, x current). Q_i is the rest shape's, so F_i = sum (x_j - x_i) c_ij^T
// with c_ij = Q_i^-1 (X_j - X_i) kept per edge end: each node gathers its F from its
// neighbours' positions, where summing the edges' products into both ends would write every
// node's sums once per edge. Each call starts from the last call's rotations, which one or two
// Newton updates carry to the new ones.
#pragma once

#include "core/memory.hpp"
#include "material/lanes.hpp"
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
    /// and how many elements share it (its weight in the sums).
    struct Edge {
        int32_t a, b, free_a, free_b;
        double weight;
    };

private:
    /// F_k of free node k at positions x (its lane of f): the sum over its neighbours j of
    /// (x_j - x_k) c_kj^T.
    void gather_gradient(size_t k, const double* x, Mat3L& f, int lane) const;

    vec<int32_t> node_;          // per free node: its body node
    vec<int32_t> entry_start_;   // per free node + 1: where its neighbours start in the entries
    vec<int32_t> neighbour_;     // per entry: the body node at the edge's other end
    // 3 per entry: c_kj = w Q_k^-1 (X_j - X_k), w the edge's elements. In single precision:
    // F to 1e-7, where the preconditioner needs the rotations to 1e-3, and half the data the
    // update streams.
    vec<float> coefficient_;
    vec<double> rotation_;       // 9 per free node
    double last_turn_ = 0.0;
};

}  // namespace sh
