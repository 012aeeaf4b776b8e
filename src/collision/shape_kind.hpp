// The shape table's rows: what each kind of rigid shape implements. A kind is one file
// (sphere_shape.cpp, ...) defining its functions and its row; shape_table.cpp lists the rows
// in sh_shape_kind order, and Shape calls its kind's functions through its row.
#pragma once

#include "collision/pose.hpp"
#include "collision/shape.hpp"
#include "collision/shape_geometry.hpp"

#include <softhap/softhap.h>

#include <cmath>

namespace sh {

/// A surface edge or triangle in a shape's local frame: count (2 or 3) points and their
/// nodes' own contact energies (J).
struct LocalSimplex {
    double p[3][3];
    double energy[3];
    int count;
};

/// A candidate maximiser of a ball's excess over a LocalSimplex (ball_excess.hpp).
struct LocalExcess {
    double value = -INFINITY;  ///< J; -INFINITY: none
    double depth = 0.0;        ///< m
    double w[3] = {0.0, 0.0, 0.0};
    double x[3] = {0.0, 0.0, 0.0};
    double n[3] = {0.0, 0.0, 1.0};     ///< unit push
    double push[3] = {0.0, 0.0, 0.0};  ///< N
};

/// One row of the shape table: a kind's functions over its geometry.
struct ShapeKind {
    sh_shape_kind kind;  ///< the row's index in the table
    const char* name;    ///< as the Python bindings spell it
    /// An unbounded half-space (a plane): obstacles only, posed from a point and a normal, its
    /// depth linear (its nodes carry all of its contact), nothing to sub-step its motion by.
    bool half_space;
    /// Validates the kind's fields of def (SH_ERR_INVALID_ARGUMENT naming the field) and fills
    /// its fields of g, inner_radius included.
    void (*init)(const sh_shape& def, ShapeGeometry& g);
    /// World-frame bounds at pose, grown by margin (m) (Shape::bounds).
    void (*bounds)(const ShapeGeometry& g, const Pose& pose, double margin, double lo[3], double hi[3]);
    /// The farthest point in world direction dir (Shape::support).
    void (*support)(const ShapeGeometry& g, const Pose& pose, const double dir[3], double out[3]);
    /// True if world point x lies inside at pose: then its depth (m, > 0) and the outward
    /// normal (world) at the nearest surface point, which Shape::penetrate_point normalises.
    PenetrateFn penetrate;
    /// The balls (g.balls) whose centres may lie within reach (m) of local point x: those
    /// from first to last (none if first > last). Null for a kind without balls
    /// (Shape::ball_count).
    void (*balls_near)(const ShapeGeometry& g, const double x[3], double reach, int& first, int& last);
    /// The centre of ball i, in the local frame.
    void (*ball_centre)(const ShapeGeometry& g, int i, double centre[3]);
};

/// The row of kind: SH_ERR_INVALID_ARGUMENT if kind is not a sh_shape_kind.
const ShapeKind& shape_kind(int kind);

/// Bounds of a shape symmetric about the pose's position: reach[k] (m) on either side along
/// world axis k, grown by margin.
inline void centred_bounds(const Pose& pose, const double reach[3], double margin, double lo[3], double hi[3]) {
    for (int k = 0; k < 3; ++k) {
        lo[k] = pose.p[k] - reach[k];
        hi[k] = pose.p[k] + reach[k];
        lo[k] -= margin;
        hi[k] += margin;
    }
}

/// def.radius, checked finite and > 0 (SH_ERR_INVALID_ARGUMENT): the sphere's and the capsule's.
double checked_radius(const sh_shape& def);

}  // namespace sh
