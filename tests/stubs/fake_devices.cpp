// Scripted stand-ins for the device SDKs declared in tests/stubs (OpenHaptics HD, Force
// Dimension DHD, CHAI3D): one device whose end-effector goes down along its frame's "up" axis by
// device_script_depth_mm(t) of wall time since it was opened, and which keeps the last force
// it was given. OpenHaptics' scheduler calls its callbacks at 1 kHz from its own thread, as the
// SDK's does. Only for the adapters to compile and run in CI: no real device is driven.
#include "HD/hd.h"
#include "chai3d.h"
#include "dhdc.h"

extern "C" {
#include "device_scene.h"
}

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

Clock::time_point g_opened = Clock::now();
double g_force[3] = {0.0, 0.0, 0.0};

double seconds_open() { return std::chrono::duration<double>(Clock::now() - g_opened).count(); }

// Depth below the device's origin (mm).
double depth_mm() { return device_script_depth_mm(seconds_open()); }

struct Scheduled {
    HDSchedulerCallback callback;
    void* data;
    bool done;
};
std::vector<Scheduled> g_scheduled;
std::thread g_scheduler;
std::atomic<bool> g_running{false};

void scheduler_loop() {
    auto next = Clock::now();
    while (g_running.load()) {
        bool any = false;
        for (Scheduled& s : g_scheduled) {
            if (s.done) continue;
            s.done = s.callback(s.data) == HD_CALLBACK_DONE;
            any = any || !s.done;
        }
        if (!any) break;
        next += std::chrono::microseconds(1000);
        std::this_thread::sleep_until(next);
    }
}

}  // namespace

// --- OpenHaptics HD: mm, y up ---------------------------------------------------------------

extern "C" {

HHD hdInitDevice(const char*) {
    g_opened = Clock::now();
    return 1;
}
void hdDisableDevice(HHD) {}
void hdEnable(HDenum) {}
HDErrorInfo hdGetError(void) { return HDErrorInfo{HD_SUCCESS, 0, 1}; }
void hdStartScheduler(void) {
    g_running = true;
    g_scheduler = std::thread(scheduler_loop);
}
void hdStopScheduler(void) {
    g_running = false;
    if (g_scheduler.joinable()) g_scheduler.join();
}
HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback callback, void* data, HDushort) {
    g_scheduled.push_back(Scheduled{callback, data, false});
    return g_scheduled.size();
}
void hdUnschedule(HDSchedulerHandle) {}
HHD hdGetCurrentDevice(void) { return 1; }
void hdBeginFrame(HHD) {}
void hdEndFrame(HHD) {}
void hdGetDoublev(HDenum name, HDdouble* value) {
    const double position[3] = {0.0, -depth_mm(), 0.0};
    if (name == HD_CURRENT_POSITION) {
        for (int k = 0; k < 3; ++k) value[k] = position[k];
    } else if (name == HD_CURRENT_TRANSFORM) {  // column-major 4x4: no rotation, the position
        for (int k = 0; k < 16; ++k) value[k] = k % 5 == 0 ? 1.0 : 0.0;
        for (int k = 0; k < 3; ++k) value[12 + k] = position[k];
    } else if (name == HD_INSTANTANEOUS_UPDATE_RATE) {
        value[0] = 1000.0;
    }
}
void hdSetDoublev(HDenum name, const HDdouble* value) {
    if (name == HD_CURRENT_FORCE)
        for (int k = 0; k < 3; ++k) g_force[k] = value[k];
}

// --- Force Dimension DHD: m, z up -------------------------------------------------------------

int dhdOpen(void) {
    g_opened = Clock::now();
    return 0;
}
int dhdClose(char) { return 0; }
int dhdEnableForce(unsigned char, char) { return 0; }
int dhdGetPosition(double* px, double* py, double* pz, char) {
    *px = 0.0, *py = 0.0, *pz = -0.001 * depth_mm();
    return 0;
}
int dhdGetOrientationFrame(double matrix[3][3], char) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) matrix[i][j] = i == j ? 1.0 : 0.0;
    return 0;
}
int dhdSetForceAndTorque(double fx, double fy, double fz, double, double, double, char) {
    g_force[0] = fx, g_force[1] = fy, g_force[2] = fz;
    return 0;
}
const char* dhdErrorGetLastStr(void) { return "no error"; }

}  // extern "C"

// --- CHAI3D: m, z up --------------------------------------------------------------------------

namespace chai3d {

bool cGenericHapticDevice::open() {
    g_opened = Clock::now();
    return true;
}
bool cGenericHapticDevice::close() { return true; }
bool cGenericHapticDevice::getPosition(cVector3d& position) {
    position = cVector3d(0.0, 0.0, -0.001 * depth_mm());
    return true;
}
bool cGenericHapticDevice::getRotation(cMatrix3d& rotation) {
    rotation = cMatrix3d();
    return true;
}
bool cGenericHapticDevice::setForceAndTorqueAndGripperForce(const cVector3d& force, const cVector3d&, double) {
    g_force[0] = force.x(), g_force[1] = force.y(), g_force[2] = force.z();
    return true;
}
unsigned int cHapticDeviceHandler::getNumDevices() const { return 1; }
bool cHapticDeviceHandler::getDevice(cGenericHapticDevicePtr& device, unsigned int) {
    device = std::make_shared<cGenericHapticDevice>();
    return true;
}

}  // namespace chai3d
