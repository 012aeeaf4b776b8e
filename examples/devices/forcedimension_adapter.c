/* forcedimension_adapter.c: a Force Dimension omega / sigma / delta (DHD API) pressing the
 * liver. The device reports metres with z up, as the world has them: the mapping only places
 * the device's origin above the liver and halves the force (force_scale 0.5, a softer feel).
 * This thread is the device loop (1 kHz), the sim thread runs the full model at 60 Hz.
 *
 *   built against tests/stubs (a scripted device) by default; against the SDK:
 *   cc -I<sdk>/include ... -ldhd
 *   forcedimension_adapter [liver.msh] */
#include "device_scene.h"

#include <dhdc.h>

#include <stdio.h>
#include <time.h>

int main(int argc, char** argv) {
    sh_device_mapping frame;
    device_scene* scene;
    const long ticks = (long)(DEVICE_RUN_SECONDS * 1000.0);
    struct timespec next;
    long i;

    sh_device_mapping_default(&frame);
    frame.force_scale = 0.5;
    scene = device_scene_create("forcedimension_adapter", argc > 1 ? argv[1] : "../shared/meshes/liver.msh", &frame);
    if (!scene) return 1;
    if (dhdOpen() < 0) {
        fprintf(stderr, "forcedimension_adapter: dhdOpen failed: %s\n", dhdErrorGetLastStr());
        device_scene_finish(scene);
        return 1;
    }
    dhdEnableForce(DHD_ON, -1);
    device_scene_start(scene);
    clock_gettime(CLOCK_MONOTONIC, &next);
    for (i = 0; i < ticks; ++i) {
        double p[3], rotation[3][3], force[3], torque[3];
        const double identity[4] = {1.0, 0.0, 0.0, 0.0};
        dhdGetPosition(&p[0], &p[1], &p[2], -1);
        dhdGetOrientationFrame(rotation, -1); /* for an oriented tool: its quaternion */
        device_scene_tick(scene, p, identity, 1e-3, force, torque);
        dhdSetForceAndTorque(force[0], force[1], force[2], torque[0], torque[1], torque[2], -1);
        next.tv_nsec += 1000000L;
        if (next.tv_nsec >= 1000000000L) next.tv_nsec -= 1000000000L, ++next.tv_sec;
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
    }
    dhdEnableForce(DHD_OFF, -1);
    dhdClose(-1);
    return device_scene_finish(scene);
}
