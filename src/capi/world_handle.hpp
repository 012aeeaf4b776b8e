// Checked access to the World behind the C API's opaque sh_world handle.
#pragma once

#include "world/world.hpp"

#include <softhap/softhap.h>

namespace sh::capi {

/// The World behind a live sh_world handle; throws SH_ERR_INVALID_HANDLE otherwise.
World& world_of(const sh_world* world);

}  // namespace sh::capi
