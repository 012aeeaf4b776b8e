// A ball's excess terms over a body's surface (shape_contact.hpp): a sphere's, or each of the
// balls a capsule, box or convex hull takes between nodes (Shape::ball_count), for the excess
// of one ball (excess_shape_contact) and the mix of several (BallMix).
#pragma once

#include "collision/closest_point.hpp"
#include "collision/shape.hpp"
#include "contact/collider.hpp"
#include "contact/contact_point.hpp"
#include "contact/hunt_crossley.hpp"
#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>

#include <cstdint>

namespace sh {

/// The step's Hunt-Crossley law as the potential a ball's excess maximises.
class StepLawPotential final : public DepthPotential {
public:
    StepLawPotential(const sh_contact_params& params, const StepLaw& law) : params_(params), law_(law) {}
    double energy(double depth) const override { return hunt_crossley_step_energy(params_, law_, depth); }
    double force(double depth) const override { return hunt_crossley_step(params_, law_, depth).force; }
    double stiffness(double depth) const override { return hunt_crossley_step(params_, law_, depth).stiffness; }
    void force_and_stiffness(double depth, double& force, double& stiffness) const override {
        const NormalForce fn = hunt_crossley_step(params_, law_, depth);
        force = fn.force;
        stiffness = fn.stiffness;
    }

private:
    const sh_contact_params& params_;
    const StepLaw& law_;
};

/// The axis-aligned box (world, m) around a feature's count points. Inline: a contact pass
/// builds one for every surface edge and triangle near the tool, most only to cull them.
struct FeatureBox {
    double lo[3], hi[3];
    FeatureBox(const double* const points[3], int count) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = hi[k] = points[0][k];
            for (int a = 1; a < count; ++a) {
                lo[k] = std::min(lo[k], points[a][k]);
                hi[k] = std::max(hi[k], points[a][k]);
            }
        }
    }
    /// The centre of the box (out) and the radius (m) of the sphere around it that holds it.
    double bounding_sphere(double centre[3]) const {
        double half[3];
        for (int k = 0; k < 3; ++k) {
            centre[k] = 0.5 * (lo[k] + hi[k]);
            half[k] = 0.5 * (hi[k] - lo[k]);
        }
        return norm3(half);
    }
    /// The squared distance (m^2) from p to the box (0 inside): no square root, so that a
    /// ball that cannot reach the feature is told apart at the price of a few comparisons.
    double distance2(const double p[3]) const {
        double sum = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double gap = std::max(std::max(lo[k] - p[k], p[k] - hi[k]), 0.0);
            sum += gap * gap;
        }
        return sum;
    }
};

/// The unit normal of the triangle of points; false (and zero) if it is a sliver or
/// degenerate.
bool feature_normal(const double* const points[3], double normal[3]);

/// The distance (m) from p to the edge (count 2) or triangle (count 3) of points, flat as
/// feature_normal says (0, which culls nothing, for a sliver).
double feature_distance(const double* p, const double* const points[3], int count, bool flat);

/// A surface edge's or triangle's nodes: their positions and, for a collider of several
/// balls, their depths (m, 0 outside) and push directions in it (a sphere's are its ball's).
struct FeatureNodes {
    const double* points[3];
    int count;
    bool own_depths;  ///< depth and normal belong to the collider (it is not its one ball)
    bool measured;    ///< depth and normal are set
    double depth[3];
    double normal[3][3];
    /// Takes the count nodes' positions from x, against collider.
    FeatureNodes(const Collider& collider, const double* x, const int32_t* nodes, int count);
    /// Sets depth and normal, once: the point queries are left until a ball reaches the
    /// feature (most features near a tool have none).
    void measure(const Collider& collider);
};

/// The excess term of the ball at centre (world; the collider's ball radius) over the edge
/// (count 2) or triangle (count 3) of feature's nodes, as excess_shape_contact describes it
/// for a sphere: the interpolant takes the nodes' depths in the ball, and the fade (the mesh
/// resolving the contact) their depths in the collider, so that a capsule's balls leave a
/// feature whose nodes are all in the capsule to its node terms, as a sphere's does. False
/// if it has none. Measures feature first (FeatureNodes::measure).
bool ball_term(const Collider& collider, const DepthPotential& psi, FeatureNodes& feature, const int32_t* nodes,
               int count, double weight, const double centre[3], ContactPoint& out);

/// Calls visit(i, term) for each ball i of the collider with an excess term over the edge or
/// triangle of nodes at positions x (law, weight: see excess_shape_contact).
template <class Visit>
void for_each_ball_term(const Collider& collider, const StepLaw& law, const double* x, const int32_t* nodes, int count,
                        double weight, Visit&& visit) {
    const BallRow& row = collider.balls();
    if (row.count == 0 || !(weight > 0.0)) return;
    const StepLawPotential psi(collider.params, law);
    FeatureNodes feature(collider, x, nodes, count);
    const double* const* points = feature.points;
    const FeatureBox box(points, count);
    const double radius = collider.shape.ball_radius();
    int first = 0, last = row.count - 1;
    if (last > 0) {  // one ball needs no search: the box test below culls it
        double centre[3];
        const double reach = box.bounding_sphere(centre) + radius;
        collider.shape.balls_near(collider.pose, centre, reach, first, last);
        if (first > last) return;
    }
    double ball[3], normal[3] = {0.0, 0.0, 0.0};
    // A sliver's plane and closest point are round-off: only its bounds cull balls. The plane
    // is found for the first ball that reaches the box.
    bool flat = false, plane_known = count < 3;
    for (int i = first; i <= last; ++i) {
        // A ball that does not reach the feature has no term there (most of those near it):
        // first its box, then its plane, then the feature itself.
        row.centre(i, ball);
        if (!(box.distance2(ball) < radius * radius)) continue;
        if (!plane_known) flat = feature_normal(points, normal), plane_known = true;
        double offset[3];
        sub3(ball, points[0], offset);
        if (flat && !(std::fabs(dot3(offset, normal)) < radius)) continue;
        if (!(feature_distance(ball, points, count, flat) < radius)) continue;
        ContactPoint term;
        if (ball_term(collider, psi, feature, nodes, count, weight, ball, term)) visit(i, term);
    }
}

}  // namespace sh
