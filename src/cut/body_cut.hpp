// Cutting a body along a triangulated surface: the entry point of sh_body_cut.
#pragma once

#include "core/id_pool.hpp"
#include "core/memory.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

class World;

/// Most triangles of a cut surface kept to be cut with again (a cutting tool's sweep, a body's
/// programmatic cuts), per body: a blade advancing by at least 1/256 of an element per step
/// still crosses whole elements with what is kept.
constexpr size_t kKeptCutTriangles = 512;

/// Drops the oldest triangles of kept (9 doubles each) beyond kKeptCutTriangles.
void keep_recent(vec<double>& kept);

/// Cuts body id of world along triangles[0..9 count) (three corners each, world frame, the
/// body's current configuration), as sh_body_cut describes; fills report. An FEM body's
/// earlier programmatic cuts are kept in its rest shape (the most recent kKeptCutTriangles
/// triangles) and cut with again, so that cuts that each cross only part of an element (a
/// scripted blade advancing by less than an element per cut) add up as a cutting tool's sweep
/// does; the first cut of a body is exact in its current configuration, later ones map the
/// new triangles to the rest shape by their corners. Throws SH_ERR_INVALID_ARGUMENT for bad
/// triangles and SH_ERR_INVALID_HANDLE for a bad id; a failure leaves the body, and what is
/// kept of it, as it was.
void cut_body(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report);

/// cut_body with triangles given in body id's rest shape (the material frame) instead of its
/// current configuration: a surface recorded there stays with the material as it moves.
/// on_nodes (ascending, may be null) lists the nodes an earlier cut along part of the same
/// surface went through: they stay on it, so cutting again along a grown surface parts the
/// same faces; the nodes this cut goes through (and their copies) are added to it. With
/// focus_count > 0, only tets near the last focus_count triangles (the new part of a grown
/// surface) are cut: away from them, cutting again along the rest parts nothing new.
void cut_body_at_rest(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report,
                      vec<int32_t>* on_nodes = nullptr, int32_t focus_count = 0);

/// Refines FEM body id of world around the segments (segment_count of them, 6 doubles each:
/// two points of its rest shape) to edges of at most edge_length, as refine_near describes,
/// as one topology change; mass-spring bodies are left alone. A new node between two nodes of
/// on_nodes (ascending, may be null: the nodes a cut went through) is added to it. Throws
/// std::bad_alloc leaving the body as it was.
void refine_body_near(World& world, Id id, const double* segments, int32_t segment_count, double edge_length,
                      vec<int32_t>* on_nodes = nullptr);

}  // namespace sh
