// Cutting a body along a triangulated surface: the entry point of sh_body_cut.
#pragma once

#include "core/id_pool.hpp"
#include "core/memory.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

class World;

/// Cuts body id of world along triangles[0..9 count) (three corners each, world frame, the
/// body's current configuration), as sh_body_cut describes; fills report. Throws
/// SH_ERR_INVALID_ARGUMENT for bad triangles and SH_ERR_INVALID_HANDLE for a bad id; a
/// failure leaves the body as it was.
void cut_body(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report);

/// cut_body with triangles given in body id's rest shape (the material frame) instead of its
/// current configuration: a surface recorded there stays with the material as it moves.
/// on_nodes (ascending, may be null) lists the nodes an earlier cut along part of the same
/// surface went through: they stay on it, so cutting again along a grown surface parts the
/// same faces; the nodes this cut goes through (and their copies) are added to it.
void cut_body_at_rest(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report,
                      vec<int32_t>* on_nodes = nullptr);

/// Refines FEM body id of world around the segments (segment_count of them, 6 doubles each:
/// two points of its rest shape) to edges of at most edge_length, as refine_near describes,
/// as one topology change; mass-spring bodies are left alone. A new node between two nodes of
/// on_nodes (ascending, may be null: the nodes a cut went through) is added to it. Throws
/// std::bad_alloc leaving the body as it was.
void refine_body_near(World& world, Id id, const double* segments, int32_t segment_count, double edge_length,
                      vec<int32_t>* on_nodes = nullptr);

}  // namespace sh
