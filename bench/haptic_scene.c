/* The haptic studies' scene: a world holding one tissue body and the sphere tool, the full
 * model's step, and the haptic context's def on it. */
#include "haptic_common.h"

/* The tissue: E = 15 kPa, nu = 0.45, rho = 1000 kg/m^3. */
static const double kYoung = 15e3;     /* Pa */
static const double kPoisson = 0.45;
static const double kDensity = 1000.0; /* kg/m^3 */

scene scene_create(const tissue* t, sh_material_model model, sh_integrator integrator, double damping,
                   const double tool_position[3]) {
    const sh_collider_def tool = bench_sphere_def(kToolRadius, tool_position);
    return scene_create_with_tool(t, model, integrator, damping, &tool);
}

scene scene_create_with_tool(const tissue* t, sh_material_model model, sh_integrator integrator, double damping,
                             const sh_collider_def* tool) {
    scene s;
    /* Gravity off: the press is the only load, so the full model's reference is the press
     * force alone. */
    s.world = bench_world_create(0);
    sh_fem_body_def def = bench_fem_body_def(t->mesh, model, kYoung, kPoisson, kDensity);
    def.integrator = integrator;
    def.damping_mass = damping;
    CHECK(sh_fem_body_create(s.world, &def, &s.body));
    CHECK(sh_body_fix_nodes(s.world, s.body, t->fixed, t->fixed_count));
    CHECK(sh_tool_create(s.world, tool, &s.tool));
    return s;
}

void scene_destroy(scene* s) { CHECK(sh_world_destroy(s->world)); }

/* An implicit step whose Newton iteration does not converge leaves the body as it was
 * (SH_ERR_NOT_CONVERGED): the studies count it rather than stop. */
int world_step(sh_world* world) {
    const sh_status st = sh_world_step(world, kSimDt, NULL);
    if (st == SH_ERR_NOT_CONVERGED) return 1;
    CHECK(st);
    return 0;
}

/* capacity_nodes 4 N + 4 never binds, so the tets alone size the buffer; data never goes stale
 * (the studies step the world themselves or not at all). */
sh_haptic_def haptic_def_for(const scene* s, double radius, int32_t capacity_tets, int exact) {
    sh_haptic_def def;
    sh_haptic_def_default(&def);
    def.tool = s->tool;
    def.radius = radius;
    def.capacity_tets = capacity_tets;
    def.capacity_nodes = 4 * capacity_tets + 4;
    def.dt = kHapticDt;
    def.stale_after = 1e3;
    if (exact) {
        def.max_force = 100.0;
        def.max_force_rate = 1e6;
        def.ramp_time = 0.0;
    }
    return def;
}
