/* A stand-in for the part of 3D Systems' OpenHaptics HD API that examples/devices uses, so that
 * the adapter compiles and runs in CI without the SDK (tests/stubs/fake_devices.c implements it
 * as a scripted device). The names and signatures follow the SDK's documentation; build the
 * adapter against the real SDK to drive a Touch or Phantom. Units as the SDK's: mm, N. */
#ifndef SOFTHAP_STUB_HD_H
#define SOFTHAP_STUB_HD_H

#ifdef __cplusplus
extern "C" {
#endif

typedef unsigned int HHD;
typedef unsigned int HDenum;
typedef unsigned int HDCallbackCode;
typedef unsigned long HDSchedulerHandle;
typedef unsigned short HDushort;
typedef double HDdouble;
typedef HDCallbackCode (*HDSchedulerCallback)(void* data);

typedef struct HDErrorInfo {
    HDenum errorCode;
    int internalErrorCode;
    HHD hHD;
} HDErrorInfo;

#define HD_DEFAULT_DEVICE 0
#define HD_SUCCESS 0
#define HD_CALLBACK_DONE 0
#define HD_CALLBACK_CONTINUE 1
#define HD_MAX_SCHEDULER_PRIORITY 0xffff
#define HD_FORCE_OUTPUT 0x4000
#define HD_CURRENT_POSITION 0x2050
#define HD_CURRENT_TRANSFORM 0x2052
#define HD_CURRENT_FORCE 0x2700
#define HD_INSTANTANEOUS_UPDATE_RATE 0x2601

#define HD_DEVICE_ERROR(info) ((info).errorCode != HD_SUCCESS)

HHD hdInitDevice(const char* name);
void hdDisableDevice(HHD device);
void hdEnable(HDenum capability);
HDErrorInfo hdGetError(void);
void hdStartScheduler(void);
void hdStopScheduler(void);
HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback callback, void* data, HDushort priority);
void hdUnschedule(HDSchedulerHandle handle);
HHD hdGetCurrentDevice(void);
void hdBeginFrame(HHD device);
void hdEndFrame(HHD device);
void hdGetDoublev(HDenum name, HDdouble* value);
void hdSetDoublev(HDenum name, const HDdouble* value);

#ifdef __cplusplus
}
#endif

#endif
