// The shape table: one row per sh_shape_kind, in the enum's order. Each kind's file defines
// its row; adding a kind is its file plus its row here.
#include "collision/shape_kind.hpp"

#include "core/error.hpp"

namespace sh {

extern const ShapeKind kSphereShape, kCapsuleShape, kBoxShape, kConvexShape, kPlaneShape;

namespace {

const ShapeKind* const kShapeKinds[] = {
    &kSphereShape,   // SH_SHAPE_SPHERE
    &kCapsuleShape,  // SH_SHAPE_CAPSULE
    &kBoxShape,      // SH_SHAPE_BOX
    &kConvexShape,   // SH_SHAPE_CONVEX
    &kPlaneShape,    // SH_SHAPE_PLANE
};
static_assert(sizeof(kShapeKinds) / sizeof(kShapeKinds[0]) == SH_SHAPE_COUNT, "one row per sh_shape_kind");

}  // namespace

const ShapeKind& shape_kind(int kind) {
    SH_REQUIRE(kind >= 0 && kind < SH_SHAPE_COUNT, SH_ERR_INVALID_ARGUMENT, "shape.kind = %d is not a sh_shape_kind",
               kind);
    const ShapeKind& row = *kShapeKinds[kind];
    // The rows live in their kinds' files, out of the compiler's sight here: a row in the wrong
    // place shows at its kind's first shape.
    SH_REQUIRE(row.kind == kind, SH_ERR_INTERNAL, "shape table: row %d holds the %s (kind %d)", kind, row.name,
               static_cast<int>(row.kind));
    return row;
}

}  // namespace sh
