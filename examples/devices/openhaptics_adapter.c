/* openhaptics_adapter.c: a 3D Systems Touch / Phantom (OpenHaptics HD API) pressing the liver.
 * The device reports millimetres with y up; a device mapping turns that into the world's metres
 * with z up, and the rendered force back. The HD scheduler calls device_tick at 1 kHz on its
 * own thread (hdScheduleAsynchronous), the main thread runs the full model at 60 Hz.
 *
 *   built against tests/stubs (a scripted device) by default; against the SDK:
 *   cc -I<OpenHaptics>/include ... -lHD
 *   openhaptics_adapter [liver.msh] */
#include "device_scene.h"

#include <HD/hd.h>

#include <math.h>
#include <stdio.h>
#include <time.h>

/* One servo tick: read the end-effector's pose, render the force. */
static HDCallbackCode device_tick(void* data) {
    device_scene* scene = (device_scene*)data;
    double transform[16], position[3], force[3], torque[3];
    const double identity[4] = {1.0, 0.0, 0.0, 0.0};
    hdBeginFrame(hdGetCurrentDevice());
    hdGetDoublev(HD_CURRENT_TRANSFORM, transform); /* column-major; the position is column 3 */
    position[0] = transform[12], position[1] = transform[13], position[2] = transform[14];
    /* This example keeps the tool's orientation fixed (a sphere); a host with an oriented tool
     * passes the quaternion of the transform's rotation instead of identity. */
    device_scene_tick(scene, position, identity, 1e-3, force, torque);
    hdSetDoublev(HD_CURRENT_FORCE, force);
    hdEndFrame(hdGetCurrentDevice());
    return HD_CALLBACK_CONTINUE;
}

int main(int argc, char** argv) {
    const double half = sqrt(0.5);
    sh_device_mapping frame;
    device_scene* scene;
    struct timespec run = {(time_t)DEVICE_RUN_SECONDS, 0};
    HHD device;
    HDErrorInfo error;
    int exit_code;

    sh_device_mapping_default(&frame);
    frame.scale = 0.001;                          /* mm -> m */
    frame.base_orientation[0] = half;             /* y up -> z up: a quarter turn about x */
    frame.base_orientation[1] = half;
    scene = device_scene_create("openhaptics_adapter", argc > 1 ? argv[1] : "../shared/meshes/liver.msh", &frame);
    if (!scene) return 1;
    device = hdInitDevice(HD_DEFAULT_DEVICE);
    error = hdGetError();
    if (HD_DEVICE_ERROR(error)) {
        fprintf(stderr, "openhaptics_adapter: hdInitDevice failed (%u)\n", error.errorCode);
        device_scene_finish(scene);
        return 1;
    }
    hdEnable(HD_FORCE_OUTPUT);
    hdScheduleAsynchronous(device_tick, scene, HD_MAX_SCHEDULER_PRIORITY);
    device_scene_start(scene);
    hdStartScheduler();
    nanosleep(&run, NULL);
    hdStopScheduler();
    hdDisableDevice(device);
    exit_code = device_scene_finish(scene);
    return exit_code;
}
