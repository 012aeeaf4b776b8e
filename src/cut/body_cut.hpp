// Cutting a body along a triangulated surface: the entry point of sh_body_cut.
#pragma once

#include "core/id_pool.hpp"

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
void cut_body_at_rest(World& world, Id id, const double* triangles, int32_t count, sh_cut_report& report);

}  // namespace sh
