// C API: worlds, body creation and stepping.
#include "capi/guard.hpp"
#include "capi/handles.hpp"
#include "capi/world_handle.hpp"
#include "core/enum_value.hpp"
#include "cut/tearing.hpp"
#include "material/material_params.hpp"
#include "mesh/tet_mesh.hpp"
#include "model/fem_body.hpp"
#include "model/spring_body.hpp"
#include "solver/integrator_table.hpp"

using namespace sh;
using capi::HandleKind;

namespace sh::capi {
const TetMesh& mesh_of(const sh_mesh* mesh);

World& world_of(const sh_world* world) { return object_of<World>(HandleKind::World, world, "world"); }
}  // namespace sh::capi

namespace {

// Checks the implicit integrator's settings.
sh_implicit_settings checked_implicit_settings(const sh_implicit_settings& in) {
    const int solver = enum_value(in.linear_solver);
    SH_REQUIRE(solver >= 0 && solver < SH_LINEAR_SOLVER_COUNT, SH_ERR_INVALID_ARGUMENT,
               "def->implicit.linear_solver = %d is not a sh_linear_solver", solver);
    require(solver != SH_LINEAR_SOLVER_CHOLMOD || (sh_build_features() & SH_FEATURE_CHOLMOD), SH_ERR_UNSUPPORTED,
            "def->implicit.linear_solver is SH_LINEAR_SOLVER_CHOLMOD but this library was built without CHOLMOD");
    SH_REQUIRE(in.newton_max_iterations >= 1, SH_ERR_INVALID_ARGUMENT,
               "def->implicit.newton_max_iterations = %d, must be >= 1", in.newton_max_iterations);
    SH_REQUIRE(std::isfinite(in.newton_tolerance) && in.newton_tolerance > 0.0, SH_ERR_INVALID_ARGUMENT,
               "def->implicit.newton_tolerance = %g, must be finite and > 0", in.newton_tolerance);
    SH_REQUIRE(std::isfinite(in.cg_tolerance) && in.cg_tolerance > 0.0, SH_ERR_INVALID_ARGUMENT,
               "def->implicit.cg_tolerance = %g, must be finite and > 0", in.cg_tolerance);
    SH_REQUIRE(in.cg_max_iterations >= 1, SH_ERR_INVALID_ARGUMENT,
               "def->implicit.cg_max_iterations = %d, must be >= 1", in.cg_max_iterations);
    SH_REQUIRE(std::isfinite(in.factor_reuse) && in.factor_reuse >= 0.0 && in.factor_reuse < 1.0,
               SH_ERR_INVALID_ARGUMENT, "def->implicit.factor_reuse = %g, must be in [0, 1)", in.factor_reuse);
    SH_REQUIRE(in.max_substeps >= 1, SH_ERR_INVALID_ARGUMENT, "def->implicit.max_substeps = %d, must be >= 1",
               in.max_substeps);
    sh_implicit_settings out = in;
    out.linear_solver = static_cast<sh_linear_solver>(solver);
    return out;
}

sh_implicit_settings default_implicit_settings() {
    sh_implicit_settings s{};
    s.linear_solver = SH_LINEAR_SOLVER_DEFAULT;
    s.newton_max_iterations = 1;
    s.newton_tolerance = 1e-6;
    s.cg_tolerance = 1e-8;
    s.cg_max_iterations = 2000;
    s.factor_reuse = 0.25;
    s.max_substeps = 16;
    return s;
}

// Checks and copies the step fields that FEM and spring defs share.
template <class Def>
StepSettings step_settings(const Def& def) {
    const int integrator = enum_value(def.integrator), policy = enum_value(def.on_unstable);
    const double runaway_speed = def.runaway_speed;
    SH_REQUIRE(is_integrator(integrator), SH_ERR_INVALID_ARGUMENT, "def->integrator = %d is not a sh_integrator", integrator);
    SH_REQUIRE(policy >= 0 && policy < SH_UNSTABLE_POLICY_COUNT, SH_ERR_INVALID_ARGUMENT, "def->on_unstable = %d is not a sh_unstable_policy", policy);
    SH_REQUIRE(runaway_speed > 0.0, SH_ERR_INVALID_ARGUMENT, "def->runaway_speed = %g m/s, must be > 0", runaway_speed);
    StepSettings s;
    if (integrator == SH_INTEGRATOR_IMPLICIT_EULER) s.implicit = checked_implicit_settings(def.implicit);
    s.integrator = static_cast<sh_integrator>(integrator);
    s.on_unstable = static_cast<sh_unstable_policy>(policy);
    s.runaway_speed = runaway_speed;
    return s;
}

// Checks a def's Rayleigh mass damping (1/s).
template <class Def>
double checked_damping_mass(const Def& def) {
    SH_REQUIRE(std::isfinite(def.damping_mass) && def.damping_mass >= 0.0, SH_ERR_INVALID_ARGUMENT, "def->damping_mass = %g 1/s, must be finite and >= 0", def.damping_mass);
    return def.damping_mass;
}

}  // namespace

extern "C" {

SH_API void sh_world_def_default(sh_world_def* def) {
    if (!def) return;
    *def = sh_world_def{};
    def->internal_init = capi::kDefInitialised;
    def->gravity[2] = -9.81;
}

SH_API sh_status sh_world_create(const sh_world_def* def, sh_world** out_world) {
    return capi::guard([&] {
        capi::require_pointer(out_world, "out_world");
        *out_world = nullptr;
        capi::require_initialised(def, "def");
        for (int k = 0; k < 3; ++k) capi::require_finite(def->gravity[k], "def->gravity");
        SH_REQUIRE(def->error_estimate == 0 || def->error_estimate == 1, SH_ERR_INVALID_ARGUMENT,
                   "def->error_estimate = %d, must be 0 or 1", def->error_estimate);
        World* world = sh::create<World>(*def);
        try {
            *out_world = static_cast<sh_world*>(const_cast<void*>(capi::register_handle(HandleKind::World, world)));
        } catch (...) {
            sh::destroy(world);
            throw;
        }
    });
}

SH_API sh_status sh_world_destroy(sh_world* world) {
    return capi::guard([&] {
        if (!world) return;
        World* object = static_cast<World*>(capi::unregister_handle(HandleKind::World, world));
        require(object != nullptr, SH_ERR_INVALID_HANDLE, "world is not a live object (destroyed twice or never created)");
        sh::destroy(object);
    });
}

SH_API sh_status sh_world_set_gravity(sh_world* world, const double gravity[3]) {
    return capi::guard([&] {
        World& w = capi::world_of(world);
        capi::require_pointer(gravity, "gravity");
        for (int k = 0; k < 3; ++k) capi::require_finite(gravity[k], "gravity");
        for (int k = 0; k < 3; ++k) w.gravity[k] = gravity[k];
    });
}

SH_API sh_status sh_world_get_warnings(const sh_world* world, uint64_t out_counts[SH_WARN_COUNT]) {
    return capi::guard([&] {
        const World& w = capi::world_of(world);
        capi::require_pointer(out_counts, "out_counts");
        for (int k = 0; k < SH_WARN_COUNT; ++k) out_counts[k] = w.warnings[k];
    });
}

SH_API sh_status sh_world_step(sh_world* world, double dt, sh_step_report* report) {
    return capi::guard([&] { capi::world_of(world).step(dt, report); });
}

SH_API void sh_static_def_default(sh_static_def* def) {
    if (!def) return;
    *def = sh_static_def{};
    def->internal_init = capi::kDefInitialised;
    def->tolerance = 1e-10;
    def->max_iterations = 50;
    def->load_steps = 1;
    def->linear_solver = SH_LINEAR_SOLVER_DEFAULT;
}

SH_API sh_status sh_world_solve_static(sh_world* world, const sh_static_def* def, sh_static_report* report) {
    return capi::guard([&] {
        World& w = capi::world_of(world);
        capi::require_initialised(def, "def");
        SH_REQUIRE(std::isfinite(def->tolerance) && def->tolerance > 0.0, SH_ERR_INVALID_ARGUMENT,
                   "def->tolerance = %g, must be finite and > 0", def->tolerance);
        SH_REQUIRE(def->max_iterations >= 1, SH_ERR_INVALID_ARGUMENT, "def->max_iterations = %d, must be >= 1",
                   def->max_iterations);
        SH_REQUIRE(def->load_steps >= 1, SH_ERR_INVALID_ARGUMENT, "def->load_steps = %d, must be >= 1", def->load_steps);
        sh_static_def checked = *def;
        sh_implicit_settings solver = default_implicit_settings();
        solver.linear_solver = def->linear_solver;
        checked.linear_solver = checked_implicit_settings(solver).linear_solver;
        w.solve_static(checked, report);
    });
}

SH_API void sh_material_default(sh_material* material) {
    if (!material) return;
    *material = sh_material{};
    material->internal_init = capi::kDefInitialised;
    material->model = SH_MATERIAL_STVK;
    material->young = 3000.0;
    material->poisson = 0.45;
    material->density = 1000.0;
    material->toughness = 200.0;
}

SH_API void sh_fem_body_def_default(sh_fem_body_def* def) {
    if (!def) return;
    *def = sh_fem_body_def{};
    def->internal_init = capi::kDefInitialised;
    sh_material_default(&def->material);
    def->integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
    def->on_unstable = SH_UNSTABLE_SUBSTEP;
    def->runaway_speed = 1e4;
    def->implicit = default_implicit_settings();
}

SH_API sh_status sh_fem_body_create(sh_world* world, const sh_fem_body_def* def, sh_body_id* out_body) {
    return capi::guard([&] {
        World& w = capi::world_of(world);
        capi::require_pointer(out_body, "out_body");
        *out_body = sh_body_id{0};
        capi::require_initialised(def, "def");
        capi::require_initialised(&def->material, "def->material");
        if (!def->mesh) throw Error(SH_ERR_INVALID_ARGUMENT, "def->mesh is NULL");
        const TetMesh& mesh = capi::mesh_of(def->mesh);
        validate_material(def->material, "def");
        SH_REQUIRE(std::isfinite(def->damping_stiffness) && def->damping_stiffness >= 0.0, SH_ERR_INVALID_ARGUMENT, "def->damping_stiffness = %g s, must be finite and >= 0", def->damping_stiffness);
        const StepSettings settings = step_settings(*def);
        const double damping_mass = checked_damping_mass(*def);
        out_body->value = w.add_fem_body(mesh, def->material, damping_mass, def->damping_stiffness, settings);
    });
}

SH_API void sh_spring_body_def_default(sh_spring_body_def* def) {
    if (!def) return;
    *def = sh_spring_body_def{};
    def->internal_init = capi::kDefInitialised;
    def->params.law = SH_SPRING_LINEAR;
    def->params.stiffness = 100.0;
    def->node_mass = 1e-3;
    def->integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
    def->on_unstable = SH_UNSTABLE_SUBSTEP;
    def->runaway_speed = 1e4;
    def->implicit = default_implicit_settings();
}

SH_API sh_status sh_spring_body_create(sh_world* world, const sh_spring_body_def* def, sh_body_id* out_body) {
    return capi::guard([&] {
        World& w = capi::world_of(world);
        capi::require_pointer(out_body, "out_body");
        *out_body = sh_body_id{0};
        capi::require_initialised(def, "def");
        const TetMesh* mesh = def->mesh ? &capi::mesh_of(def->mesh) : nullptr;
        vec<double> nodes;
        if (def->nodes) {
            SH_REQUIRE(def->node_count > 0, SH_ERR_INVALID_ARGUMENT, "def->node_count = %d, must be > 0", def->node_count);
            nodes.assign(def->nodes, def->nodes + 3 * static_cast<size_t>(def->node_count));
        } else {
            require(mesh != nullptr, SH_ERR_INVALID_ARGUMENT, "def->nodes and def->mesh are both NULL");
            nodes = mesh->nodes;
        }
        const size_t node_count = nodes.size() / 3;
        vec<int32_t> springs;
        if (def->springs) {
            SH_REQUIRE(def->spring_count >= 0, SH_ERR_INVALID_ARGUMENT, "def->spring_count = %d, must be >= 0", def->spring_count);
            springs.assign(def->springs, def->springs + 2 * static_cast<size_t>(def->spring_count));
        } else if (mesh) {
            require(mesh->node_count() == static_cast<int32_t>(node_count), SH_ERR_INVALID_ARGUMENT,
                    "springs from def->mesh need the mesh's nodes (def->nodes NULL or the same count)");
            springs = mesh->edges;
        }
        vec<double> masses(node_count, def->node_mass);
        if (def->node_masses) masses.assign(def->node_masses, def->node_masses + node_count);
        else if (mesh && !def->nodes)
            for (size_t i = 0; i < node_count; ++i)
                if (!mesh->node_used[i]) masses[i] = 0.0;  // orphans stay out of the dynamics
        const StepSettings settings = step_settings(*def);
        const double damping_mass = checked_damping_mass(*def);
        if (def->params.break_strain > 0.0) enable_tearing(w);  // before the body: it can fail alone
        out_body->value = w.add_body(
            sh::create<SpringBody>(std::move(nodes), std::move(springs), def->params, masses, damping_mass), settings);
    });
}

}  // extern "C"
