// C API: tools, obstacles and contact between bodies.
#include "capi/guard.hpp"
#include "capi/world_handle.hpp"
#include "contact/collider.hpp"
#include "core/enum_value.hpp"

using namespace sh;

namespace {

// Copies a collider's contact state into out_state.
void read_contact(const Collider& c, sh_contact_state* out_state) {
    capi::require_pointer(out_state, "out_state");
    *out_state = c.state;
}

// A copy of def, checked for its cookies and its shape kind (the rest is checked by the
// collider it makes).
sh_collider_def checked_def(const sh_collider_def* def) {
    capi::require_initialised(def, "def");
    capi::require_initialised(&def->contact, "def->contact");
    sh_collider_def out = *def;
    const int kind = enum_value(def->shape.kind);
    SH_REQUIRE(kind >= 0 && kind < SH_SHAPE_COUNT, SH_ERR_INVALID_ARGUMENT,
               "def->shape.kind = %d is not a sh_shape_kind", kind);
    out.shape.kind = static_cast<sh_shape_kind>(kind);
    return out;
}

}  // namespace

extern "C" {

SH_API void sh_contact_params_default(sh_contact_params* params) {
    if (!params) return;
    *params = sh_contact_params{};
    params->internal_init = capi::kDefInitialised;
    params->stiffness = 1e4;
    params->exponent = 1.5;
    params->damping = 0.2;
    params->static_friction = 0.0;
    params->dynamic_friction = 0.0;
    params->slip_velocity = 1e-3;
    params->capacity = 4096;
}

SH_API void sh_collider_def_default(sh_collider_def* def) {
    if (!def) return;
    *def = sh_collider_def{};
    def->internal_init = capi::kDefInitialised;
    def->shape.kind = SH_SHAPE_SPHERE;
    def->shape.radius = 5e-3;
    def->shape.normal[2] = 1.0;
    def->orientation[0] = 1.0;
    sh_contact_params_default(&def->contact);
}

SH_API sh_status sh_tool_create(sh_world* world, const sh_collider_def* def, sh_tool_id* out_tool) {
    return capi::guard([&] {
        capi::require_pointer(out_tool, "out_tool");
        *out_tool = sh_tool_id{0};
        World& w = capi::world_of(world);
        out_tool->value = w.add_collider(checked_def(def), true);
    });
}

SH_API sh_status sh_tool_destroy(sh_world* world, sh_tool_id tool) {
    return capi::guard([&] { capi::world_of(world).remove_collider(tool.value, true); });
}

SH_API int32_t sh_tool_is_valid(const sh_world* world, sh_tool_id tool) {
    int32_t valid = 0;
    capi::guard([&] { valid = capi::world_of(world).is_valid_collider(tool.value, true) ? 1 : 0; });
    return valid;
}

SH_API sh_status sh_tool_set_pose(sh_world* world, sh_tool_id tool, const double position[3],
                                  const double orientation[4]) {
    return capi::guard([&] {
        Collider& c = capi::world_of(world).collider(tool.value, true);
        c.target = checked_pose(position, orientation, "sh_tool_set_pose");
    });
}

SH_API sh_status sh_tool_get_pose(const sh_world* world, sh_tool_id tool, double out_position[3],
                                  double out_orientation[4]) {
    return capi::guard([&] {
        const Collider& c = capi::world_of(world).collider(tool.value, true);
        capi::require_pointer(out_position, "out_position");
        capi::require_pointer(out_orientation, "out_orientation");
        for (int k = 0; k < 3; ++k) out_position[k] = c.target.p[k];
        for (int k = 0; k < 4; ++k) out_orientation[k] = c.target.q[k];
    });
}

SH_API sh_status sh_tool_set_velocity(sh_world* world, sh_tool_id tool, const double linear[3],
                                      const double angular[3]) {
    return capi::guard([&] {
        Collider& c = capi::world_of(world).collider(tool.value, true);
        capi::require_pointer(linear, "linear");
        capi::require_pointer(angular, "angular");
        for (int k = 0; k < 3; ++k) {
            capi::require_finite(linear[k], "linear");
            capi::require_finite(angular[k], "angular");
        }
        for (int k = 0; k < 3; ++k) {
            c.given_velocity[k] = linear[k];
            c.given_angular[k] = angular[k];
        }
        c.velocity_given = true;
    });
}

SH_API sh_status sh_tool_get_contact(const sh_world* world, sh_tool_id tool, sh_contact_state* out_state) {
    return capi::guard([&] { read_contact(capi::world_of(world).collider(tool.value, true), out_state); });
}

SH_API sh_status sh_tool_get_wrench(const sh_world* world, sh_tool_id tool, double out_force[3],
                                    double out_torque[3]) {
    return capi::guard([&] {
        const Collider& c = capi::world_of(world).collider(tool.value, true);
        capi::require_pointer(out_force, "out_force");
        capi::require_pointer(out_torque, "out_torque");
        for (int k = 0; k < 3; ++k) {
            out_force[k] = c.state.force[k];
            out_torque[k] = c.state.torque[k];
        }
    });
}

SH_API sh_status sh_obstacle_create(sh_world* world, const sh_collider_def* def, sh_obstacle_id* out_obstacle) {
    return capi::guard([&] {
        capi::require_pointer(out_obstacle, "out_obstacle");
        *out_obstacle = sh_obstacle_id{0};
        World& w = capi::world_of(world);
        out_obstacle->value = w.add_collider(checked_def(def), false);
    });
}

SH_API sh_status sh_obstacle_destroy(sh_world* world, sh_obstacle_id obstacle) {
    return capi::guard([&] { capi::world_of(world).remove_collider(obstacle.value, false); });
}

SH_API int32_t sh_obstacle_is_valid(const sh_world* world, sh_obstacle_id obstacle) {
    int32_t valid = 0;
    capi::guard([&] { valid = capi::world_of(world).is_valid_collider(obstacle.value, false) ? 1 : 0; });
    return valid;
}

SH_API sh_status sh_obstacle_get_contact(const sh_world* world, sh_obstacle_id obstacle,
                                         sh_contact_state* out_state) {
    return capi::guard([&] { read_contact(capi::world_of(world).collider(obstacle.value, false), out_state); });
}

SH_API sh_status sh_world_set_body_contact(sh_world* world, sh_body_id a, sh_body_id b,
                                           const sh_contact_params* params) {
    return capi::guard([&] {
        World& w = capi::world_of(world);
        if (params) capi::require_initialised(params, "params");
        w.set_body_contact(a.value, b.value, params);
    });
}

}  // extern "C"
