/* What the device adapters (openhaptics_adapter.c, forcedimension_adapter.c,
 * chai3d_adapter.cpp) share: the settled liver of liver_scene.h with its base fixed, a 1 cm
 * sphere tool and a haptic context on it, a sim thread stepping the full model at 60 Hz, and
 * one device tick through a device mapping: the device's pose in its own units and frame in,
 * the force to render in them out. Each adapter only reads its device and writes the force. */
#ifndef SOFTHAP_EXAMPLES_DEVICE_SCENE_H
#define SOFTHAP_EXAMPLES_DEVICE_SCENE_H

#include <softhap/softhap.h>

/* The scene (opaque: its sim thread's state stays in device_scene.c). */
typedef struct device_scene device_scene;

/* Builds the scene for a device whose frame and units device_frame gives (scale,
 * base_orientation, tool_offset, force_scale; its base_position is set here so that the
 * device's origin is 2 mm above the top of the liver, where the path of liver_scene.h starts).
 * mesh_path: the liver mesh. NULL, with a message on stderr, on failure. */
device_scene* device_scene_create(const char* program, const char* mesh_path, const sh_device_mapping* device_frame);

/* Starts the 60 Hz sim thread (the full model's steps, which refresh the haptic buffer). */
int device_scene_start(device_scene* scene);

/* One device tick of dt (s): the device's pose (its units and frame) to the world, the haptic
 * step, and the force and torque to render back in the device's frame. Allocation-free. */
void device_scene_tick(device_scene* scene, const double device_position[3], const double device_orientation[4],
                       double dt, double out_force[3], double out_torque[3]);

/* Stops the sim thread, prints a summary on stderr, frees the scene; returns 0 if every full-model
 * step went well and the tool touched the liver. */
int device_scene_finish(device_scene* scene);

/* The scripted hand the stub devices follow (tests/stubs/fake_devices.cpp): the device's
 * depth below its origin (device units of 1 mm) at time t (s): down 10 mm over the first
 * second, held for the next. */
double device_script_depth_mm(double t);

/* How long the adapters run (s). */
#define DEVICE_RUN_SECONDS 2.0

#endif
