// The excess of a collider made of several balls (a capsule): the smooth maximum of its balls'
// excesses over a body's surface, its terms and its tangent.
#pragma once

#include "contact/collider.hpp"
#include "contact/contact_point.hpp"
#include "contact/hunt_crossley.hpp"
#include "core/memory.hpp"

#include <cstdint>

namespace sh {

/// The excess of a collider made of several balls (Shape::ball_count: a capsule is the balls
/// along its axis). Each ball i has the excess terms of a sphere over every surface edge and
/// triangle, whose signed sum over the surface is the ball's own excess there, P_i (with its
/// own nodes' depths in their interpolants and fades). The collider's excess is their Lehmer
/// mean of order p = kOrder,
///   X = sum_i P_i^(p+1) / sum_i P_i^p   (over P_i > 0),
/// a smooth maximum: equal to the P_i where they are equal (a capsule lying on a face: the
/// balls along its ridge reach equally deep, and the face's nodes share the ridge's push
/// evenly), equal to the only ball that reaches, otherwise between their mean and their
/// largest, within about 16 % of the largest as a capsule tilts onto one end. The exact
/// maximum would make its maximiser jump from one end of a lying capsule to the other as
/// the face tilts, and the forces on the face's nodes with it. Each feature's term takes
/// sum_i s_i T_i of its balls' terms T_i as its energy, s_i = P_i^p / sum_j P_j^p, and
/// sum_i c_i grad T_i as its gradient, c_i = P_i^(p-1) ((p+1) P_i - p X) / sum_j P_j^p: the
/// terms sum to X and their forces to X's gradient. So a collider of several balls takes
/// two passes over its terms per evaluation: sum() over them all, then term() for each.
class BallMix {
public:
    /// The Lehmer mean's order p: higher follows the largest ball more closely (within 11 %
    /// for 8 as a capsule tilts, 16 % for 4, 25 % for 2) but swings its push between the
    /// balls faster, and Newton's static press of a tilted capsule took 1,567 (8), 228 (4) and
    /// 108 (2) iterations.
    static constexpr int kOrder = 4;

    /// Makes room for count balls (allocates if there is less).
    void reserve(int count);

    /// Sums collider's balls' totals over the surface's edges and triangles and computes the
    /// shares and coefficients (the room reserved must hold its balls): each_term(add) calls
    /// add(law, x, nodes, count, weight) for each edge (count 2) or triangle (count 3) of nodes
    /// at positions x (law, weight: see excess_shape_contact).
    template <class EachTerm>
    void sum(const Collider& collider, EachTerm&& each_term) {
        begin(collider);
        each_term([&](const StepLaw& law, const double* x, const int32_t* nodes, int count, double weight) {
            add(collider, law, x, nodes, count, weight);
        });
        finish();
    }

    /// The mixed excess term of the edge or triangle (excess_shape_contact for a collider of
    /// several balls): mixed, with a bound on each node's stiffness from its balls' law
    /// curvature and the smooth maximum's (stiffness_bound); the full model's tangent takes the
    /// whole mix's (add_tangent_term, tangent).
    /// False if no ball with a share reaches it.
    bool term(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes, int count,
              double weight, ContactPoint& out) const;

    /// Starts the mix's tangent over the terms of the current sum (after finish()). Allocates.
    void begin_tangent();

    /// Adds the edge's or triangle's ball terms to the tangent's sums (as add() does to the
    /// totals). Allocates.
    void add_tangent_term(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes,
                          int count, double weight);

    /// The mix's stiffness over the nodes its terms touch, the full model's tangent of them:
    /// sum over the terms of their balls' law curvature c_i k_i g_i g_i^T, plus the smooth
    /// maximum's curvature G H G^T (G_i the gradient of ball i's total over every node it
    /// reaches, H = d c / d P), projected to positive semi-definite. Across the terms, so that
    /// an edge's subtracted term meets its faces' before the projection (a ball's region
    /// counts once) and the coupling between the terms a ball spans is there. Calls
    /// block(node_a, node_b, B) with B the 3x3 block (row-major, N/m), for every pair of
    /// touched nodes with a <= b in their order of touch. Allocates.
    template <class Block>
    void tangent(Block&& block) const;

    /// Ball i's share s_i of its terms' energy and coefficient c_i of their gradients.
    double share(int i) const { return mix_[kFields * static_cast<size_t>(i) + 1]; }
    double coefficient(int i) const { return mix_[kFields * static_cast<size_t>(i) + 2]; }

    /// The Hessian of X over the totals, d c_i / d P_j = curvature_i delta_ij - (cross_i c_j +
    /// c_i cross_j) (1/J): the smooth maximum's own curvature, which stiffens a lying capsule's
    /// face against tilting (by far more than the law's curvature does).
    double curvature(int i) const { return mix_[kFields * static_cast<size_t>(i) + 3]; }
    double cross(int i) const { return mix_[kFields * static_cast<size_t>(i) + 4]; }

private:
    /// Starts a sum over collider's balls.
    void begin(const Collider& collider);
    /// Adds the ball terms of one edge or triangle to the balls' totals.
    void add(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes, int count,
             double weight);
    /// Computes the shares and coefficients from the totals.
    void finish();
    /// The dense tangent over the touched nodes (3 per node, row-major), from the sums.
    void tangent_matrix(vec<double>& out) const;

    static constexpr size_t kFields = 5;
    vec<double> mix_;  ///< per ball: total P_i, share, coefficient, curvature, cross
    int count_ = 0;
    // The tangent's sums: the touched nodes; per ball with a share its column (columns_ of
    // them); per (column, touched node) entry its gradient.
    vec<int32_t> touched_, column_;
    int32_t columns_ = 0;
    vec<double> gradient_;
    vec<int32_t> gradient_column_, gradient_node_;
    // Per term and pair of its nodes: the touched nodes' indices and the term's law curvature
    // block (its balls' c_i k_i g_i g_i^T, sign included).
    vec<double> law_;
    vec<int32_t> law_node_;
};

template <class Block>
void BallMix::tangent(Block&& block) const {
    vec<double> k;
    tangent_matrix(k);
    const size_t n = touched_.size(), dim = 3 * n;
    for (size_t a = 0; a < n; ++a)
        for (size_t b = a; b < n; ++b) {
            double B[9];
            for (int r = 0; r < 3; ++r)
                for (int s = 0; s < 3; ++s) B[3 * r + s] = k[(3 * a + static_cast<size_t>(r)) * dim + 3 * b + static_cast<size_t>(s)];
            block(touched_[a], touched_[b], static_cast<const double*>(B));
        }
}

}  // namespace sh
