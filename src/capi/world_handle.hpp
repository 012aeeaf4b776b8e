// The opaque sh_world of the C API and its checked access.
#pragma once

#include "world/world.hpp"

struct sh_world {
    explicit sh_world(const sh_world_def& def) : world(def) {}
    sh::World world;
};

namespace sh::capi {

/// The World behind a live sh_world; throws SH_ERR_INVALID_HANDLE otherwise.
World& world_of(const sh_world* world);

}  // namespace sh::capi
