// The balls a shape's contact takes between a body's nodes (Shape::ball_count): balls of one
// radius evenly spaced along a segment, its core. A sphere's is its centre, a capsule's its
// axis; a box's or a convex hull's is its largest inscribed capsule along its longest axis.
#pragma once

#include "collision/pose.hpp"

namespace sh {

struct ShapeGeometry;

/// A kind's point query (ShapeKind::penetrate): true if world point x lies inside the shape
/// at pose, with its depth (m) and outward normal.
using PenetrateFn = bool (*)(const ShapeGeometry& g, const Pose& pose, const double x[3], double& depth,
                             double normal[3]);

/// A segment of balls in a shape's local frame.
struct BallCore {
    double centre[3] = {0.0, 0.0, 0.0};  ///< the segment's midpoint (m)
    double axis[3] = {0.0, 0.0, 1.0};    ///< its unit direction
    double half_length = 0.0;            ///< m
    double radius = 0.0;                 ///< the balls' radius (m)
    int count = 0;                       ///< balls from end to end; 0: none
    bool is_shape = false;               ///< the one ball is the shape itself (a sphere)
};

/// The longest core in radii: its balls (4 per radius) are summed on every evaluation.
constexpr double kMaxCoreHalfLength = 1024.0;

/// Sets core to balls of radius along the segment (centre, unit axis, half_length), at most
/// half a radius apart, both ends included: their union is the capsule the segment and radius
/// make, but for scallops of at most 3 % of the radius between them, which no ball's excess
/// sees (each one's maximiser is at the foot of its own centre). half_length must be at most
/// kMaxCoreHalfLength radii.
void set_ball_core(BallCore& core, const double centre[3], const double axis[3], double half_length, double radius);

/// Sets core to the largest (by volume) capsule inside the convex shape g, along the principal
/// axis of its count points (3 coordinates each, local frame) through their mean; penetrate
/// is its kind's point query (its depth is concave along any line). No balls if the capsule
/// would be longer than kMaxCoreHalfLength radii.
void inscribe_ball_core(BallCore& core, const double* points, int count, PenetrateFn penetrate, const ShapeGeometry& g);

/// The balls (ShapeKind::balls_near) whose centres may lie within reach (m) of local point x:
/// those from first to last (none if first > last).
void core_balls_near(const ShapeGeometry& g, const double x[3], double reach, int& first, int& last);

/// The centre of ball i, in the local frame (ShapeKind::ball_centre).
void core_ball_centre(const ShapeGeometry& g, int i, double centre[3]);

}  // namespace sh
