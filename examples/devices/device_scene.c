#include "device_scene.h"

#include "liver_scene.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct device_scene {
    liver_scene liver;
    sh_tool_id tool;
    sh_haptic* haptic;
    sh_device_mapping mapping;  /* the device's frame, units and force scale */
    pthread_t sim;
    atomic_int stop;            /* set to end the sim thread */
    int sim_running;
    long ticks, contact_ticks, sim_steps, sim_failures;
    double largest_force;       /* N, in the device's frame (times force_scale) */
};

static const double kToolRadius = 0.01; /* m */
static const double kSimDt = 1.0 / 60.0;

double device_script_depth_mm(double t) { return 10.0 * liver_ease(liver_progress(t, 0.0, 1.0)); }

/* The tool and the haptic context, the tool where the device's origin maps. */
static int create_tool(device_scene* s, const char* program) {
    sh_collider_def tool;
    sh_haptic_def haptic;
    sh_collider_def_default(&tool);
    tool.shape.kind = SH_SHAPE_SPHERE;
    tool.shape.radius = kToolRadius;
    memcpy(tool.position, s->mapping.base_position, sizeof tool.position);
    tool.contact.stiffness = 2e5; /* N/m^1.5: a rigid instrument */
    tool.contact.damping = 1.5;
    EXAMPLE_CHECK(program, sh_tool_create(s->liver.world, &tool, &s->tool));
    sh_haptic_def_default(&haptic);
    haptic.tool = s->tool;
    EXAMPLE_CHECK(program, sh_haptic_create(s->liver.world, &haptic, &s->haptic));
    return 0;
done:
    return 1;
}

device_scene* device_scene_create(const char* program, const char* mesh_path, const sh_device_mapping* device_frame) {
    liver_scene_def def;
    liver_path path;
    device_scene* s = (device_scene*)calloc(1, sizeof *s);
    if (!s) return NULL;
    def.program = program;
    def.mesh_path = mesh_path;
    def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    def.dt = kSimDt;
    def.table_friction = 0.5;
    def.base_height = 0.01;
    if (liver_scene_create(&def, &s->liver) != 0) {
        free(s);
        return NULL;
    }
    if (liver_scene_find_path(&s->liver, kToolRadius, 0.01, &path) != 0) goto fail;
    s->mapping = *device_frame;
    liver_path_point(&path, 0.0, -0.002, s->mapping.base_position);
    if (example_failed(program, "sh_device_mapping_check", sh_device_mapping_check(&s->mapping))) goto fail;
    if (create_tool(s, program) != 0) goto fail;
    return s;
fail:
    sh_haptic_destroy(s->haptic);
    liver_scene_destroy(&s->liver);
    free(s);
    return NULL;
}

/* Steps the full model every kSimDt of wall time until told to stop. */
static void* sim_main(void* arg) {
    device_scene* s = (device_scene*)arg;
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    while (!atomic_load(&s->stop)) {
        const sh_status status = sh_world_step(s->liver.world, kSimDt, NULL);
        s->sim_failures += status != SH_OK;
        ++s->sim_steps;
        next.tv_nsec += (long)(kSimDt * 1e9);
        while (next.tv_nsec >= 1000000000L) next.tv_nsec -= 1000000000L, ++next.tv_sec;
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
    }
    return NULL;
}

int device_scene_start(device_scene* s) {
    atomic_store(&s->stop, 0);
    if (pthread_create(&s->sim, NULL, sim_main, s) != 0) return 1;
    s->sim_running = 1;
    return 0;
}

void device_scene_tick(device_scene* s, const double device_position[3], const double device_orientation[4],
                       double dt, double out_force[3], double out_torque[3]) {
    double p[3], q[4];
    sh_haptic_output out;
    int k;
    memset(out_force, 0, 3 * sizeof(double));
    memset(out_torque, 0, 3 * sizeof(double));
    if (sh_device_to_world(&s->mapping, device_position, device_orientation, p, q) != SH_OK) return;
    sh_haptic_step(s->haptic, p, q, dt, &out); /* the output is valid (finite, clamped) whatever it returns */
    if (sh_device_force(&s->mapping, out.force, out.torque, out_force, out_torque) != SH_OK) return;
    ++s->ticks;
    s->contact_ticks += out.contact;
    for (k = 0; k < 3; ++k) s->largest_force = fmax(s->largest_force, fabs(out_force[k]));
}

int device_scene_finish(device_scene* s) {
    if (s->sim_running) {
        atomic_store(&s->stop, 1);
        pthread_join(s->sim, NULL);
    }
    fprintf(stderr, "%s: %ld device ticks (%ld in contact), %ld full-model steps (%ld failed); largest force "
            "component on the device %.3f N\n", s->liver.program, s->ticks, s->contact_ticks, s->sim_steps,
            s->sim_failures, s->largest_force);
    const int ok = s->sim_failures == 0 && s->contact_ticks > 0;
    sh_haptic_destroy(s->haptic);
    liver_scene_destroy(&s->liver);
    free(s);
    return ok ? 0 : 1;
}
