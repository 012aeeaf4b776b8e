/* A stand-in for the part of Force Dimension's DHD SDK that examples/devices uses (see
 * tests/stubs/HD/hd.h for why). Units as the SDK's: m, N, N m; the device frame's z is up. */
#ifndef SOFTHAP_STUB_DHDC_H
#define SOFTHAP_STUB_DHDC_H

#ifdef __cplusplus
extern "C" {
#endif

#define DHD_ON 1
#define DHD_OFF 0

int dhdOpen(void);
int dhdClose(char id);
int dhdEnableForce(unsigned char value, char id);
int dhdGetPosition(double* px, double* py, double* pz, char id);
int dhdGetOrientationFrame(double matrix[3][3], char id);
int dhdSetForceAndTorque(double fx, double fy, double fz, double tx, double ty, double tz, char id);
const char* dhdErrorGetLastStr(void);

#ifdef __cplusplus
}
#endif

#endif
