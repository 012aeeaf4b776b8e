// Tool cutting: a tool with a blade cuts the bodies its blade edge sweeps through at every
// full step (a step hook the world owns).
#pragma once

#include "core/id_pool.hpp"

#include <softhap/softhap.h>

namespace sh {

class World;

/// Makes tool id of world a cutting tool with def (validated), or an ordinary tool for null;
/// the first cutting tool of a world gives it the hook that cuts. Throws
/// SH_ERR_INVALID_HANDLE, SH_ERR_INVALID_ARGUMENT or std::bad_alloc, changing nothing.
void set_tool_cutting(World& world, Id id, const sh_cut_def* def);

}  // namespace sh
