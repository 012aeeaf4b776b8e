// A stand-in for the part of CHAI3D that examples/devices uses (see tests/stubs/HD/hd.h for
// why): a generic haptic device opened through the device handler. Units as CHAI3D's: m, N,
// N m; z up.
#ifndef SOFTHAP_STUB_CHAI3D_H
#define SOFTHAP_STUB_CHAI3D_H

#include <memory>

namespace chai3d {

struct cVector3d {
    double x_ = 0.0, y_ = 0.0, z_ = 0.0;
    cVector3d() = default;
    cVector3d(double x, double y, double z) : x_(x), y_(y), z_(z) {}
    double x() const { return x_; }
    double y() const { return y_; }
    double z() const { return z_; }
};

struct cMatrix3d {
    double m[3][3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
    double getCol0x() const { return m[0][0]; }
};

class cGenericHapticDevice {
public:
    virtual ~cGenericHapticDevice() = default;
    virtual bool open();
    virtual bool close();
    virtual bool getPosition(cVector3d& position);
    virtual bool getRotation(cMatrix3d& rotation);
    virtual bool setForceAndTorqueAndGripperForce(const cVector3d& force, const cVector3d& torque, double gripper);
};

typedef std::shared_ptr<cGenericHapticDevice> cGenericHapticDevicePtr;

class cHapticDeviceHandler {
public:
    unsigned int getNumDevices() const;
    bool getDevice(cGenericHapticDevicePtr& device, unsigned int index = 0);
};

}  // namespace chai3d

#endif
