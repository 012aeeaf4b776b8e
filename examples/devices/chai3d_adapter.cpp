// chai3d_adapter.cpp: any device CHAI3D drives (cGenericHapticDevice) pressing the liver. CHAI3D
// reports metres with z up; the mapping places the device's origin above the liver. This thread
// is the device loop (1 kHz), the sim thread runs the full model at 60 Hz.
//
//   built against tests/stubs (a scripted device) by default; against CHAI3D:
//   c++ -I<chai3d>/src ... -lchai3d
//   chai3d_adapter [liver.msh]
extern "C" {
#include "device_scene.h"
}

#include <chai3d.h>

#include <chrono>
#include <cstdio>
#include <thread>

int main(int argc, char** argv) {
    sh_device_mapping frame;
    sh_device_mapping_default(&frame);
    device_scene* scene = device_scene_create("chai3d_adapter", argc > 1 ? argv[1] : "../shared/meshes/liver.msh", &frame);
    if (!scene) return 1;
    chai3d::cHapticDeviceHandler handler;
    chai3d::cGenericHapticDevicePtr device;
    if (handler.getNumDevices() == 0 || !handler.getDevice(device, 0) || !device->open()) {
        std::fprintf(stderr, "chai3d_adapter: no haptic device\n");
        device_scene_finish(scene);
        return 1;
    }
    device_scene_start(scene);
    auto next = std::chrono::steady_clock::now();
    const long ticks = static_cast<long>(DEVICE_RUN_SECONDS * 1000.0);
    for (long i = 0; i < ticks; ++i) {
        chai3d::cVector3d p;
        device->getPosition(p);
        const double position[3] = {p.x(), p.y(), p.z()}, identity[4] = {1.0, 0.0, 0.0, 0.0};
        double force[3], torque[3];
        device_scene_tick(scene, position, identity, 1e-3, force, torque);
        device->setForceAndTorqueAndGripperForce(chai3d::cVector3d(force[0], force[1], force[2]),
                                                 chai3d::cVector3d(torque[0], torque[1], torque[2]), 0.0);
        next += std::chrono::microseconds(1000);
        std::this_thread::sleep_until(next);
    }
    device->close();
    return device_scene_finish(scene);
}
