/* The device mapping: a device in mm with y up (OpenHaptics, CHAI3D) in a z-up world in metres.
 * Expected values are worked out by hand from the mapping's definition in the header; the
 * round trips check forward and inverse against each other over many poses. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double kHalf = 0.70710678118654752440; /* cos 45 deg = sin 45 deg */

/* mm, y up -> m, z up: a quarter turn about x takes the device's y to the world's z and its z
 * (towards the user) to the world's -y; the device's origin at (0.1, 0.2, 0.3) m. */
static sh_device_mapping desk_device(void) {
    sh_device_mapping m;
    sh_device_mapping_default(&m);
    m.scale = 0.001;
    m.base_position[0] = 0.1;
    m.base_position[1] = 0.2;
    m.base_position[2] = 0.3;
    m.base_orientation[0] = kHalf;
    m.base_orientation[1] = kHalf;
    m.force_scale = 0.5;
    return m;
}

static void test_default_is_the_identity(void** state) {
    (void)state;
    sh_device_mapping m;
    sh_device_mapping_default(&m);
    assert_ok(sh_device_mapping_check(&m));
    const double p[3] = {1.0, -2.0, 3.0}, q[4] = {0.5, 0.5, -0.5, 0.5};
    double wp[3], wq[4];
    assert_ok(sh_device_to_world(&m, p, q, wp, wq));
    for (int k = 0; k < 3; ++k) assert_true(wp[k] == p[k]);
    for (int k = 0; k < 4; ++k) assert_true(fabs(wq[k] - q[k]) < 1e-15);
}

static void test_mm_y_up_device_in_a_z_up_world(void** state) {
    (void)state;
    sh_device_mapping m = desk_device();
    assert_ok(sh_device_mapping_check(&m));
    /* (10, 20, 30) mm in the device: x stays, y goes up (z), z goes to -y. */
    const double p[3] = {10.0, 20.0, 30.0}, identity[4] = {1.0, 0.0, 0.0, 0.0};
    double wp[3], wq[4];
    assert_ok(sh_device_to_world(&m, p, identity, wp, wq));
    const double expected[3] = {0.1 + 0.010, 0.2 - 0.030, 0.3 + 0.020};
    for (int k = 0; k < 3; ++k) assert_true(fabs(wp[k] - expected[k]) < 1e-15);
    assert_true(fabs(wq[0] - kHalf) < 1e-15 && fabs(wq[1] - kHalf) < 1e-15);
    /* A stylus tip 40 mm along the end-effector's -z; the end-effector turned a quarter about
     * the device's y: its -z points along the device's -x, so the tip is 40 mm further -x. */
    m.tool_offset[2] = -40.0;
    const double turned[4] = {kHalf, 0.0, kHalf, 0.0};
    assert_ok(sh_device_to_world(&m, p, turned, wp, wq));
    const double tip[3] = {0.1 + 0.010 - 0.040, 0.2 - 0.030, 0.3 + 0.020};
    for (int k = 0; k < 3; ++k) assert_true(fabs(wp[k] - tip[k]) < 1e-15);
    /* The world's 2 N up is the device's 2 N along +y, halved; a torque about the world's x
     * stays about the device's x. */
    const double up[3] = {0.0, 0.0, 2.0}, about_x[3] = {0.3, 0.0, 0.0};
    double f[3], t[3];
    assert_ok(sh_device_force(&m, up, about_x, f, t));
    assert_true(fabs(f[0]) < 1e-15 && fabs(f[1] - 1.0) < 1e-15 && fabs(f[2]) < 1e-15);
    assert_true(fabs(t[0] - 0.15) < 1e-15 && fabs(t[1]) < 1e-15 && fabs(t[2]) < 1e-15);
}

/* Forward then inverse (and inverse then forward) is the identity for random poses. */
static void test_round_trips_are_the_identity(void** state) {
    (void)state;
    sh_device_mapping m = desk_device();
    m.tool_offset[0] = 3.0, m.tool_offset[1] = -7.0, m.tool_offset[2] = 11.0;
    srand(7);
    double worst = 0.0;
    for (int i = 0; i < 1000; ++i) {
        double p[3], q[4], norm = 0.0;
        for (int k = 0; k < 3; ++k) p[k] = 200.0 * rand() / RAND_MAX - 100.0;
        for (int k = 0; k < 4; ++k) q[k] = 2.0 * rand() / RAND_MAX - 1.0, norm += q[k] * q[k];
        for (int k = 0; k < 4; ++k) q[k] /= sqrt(norm);
        if (q[0] < 0.0)
            for (int k = 0; k < 4; ++k) q[k] = -q[k];
        double wp[3], wq[4], dp[3], dq[4];
        assert_ok(sh_device_to_world(&m, p, q, wp, wq));
        assert_ok(sh_world_to_device(&m, wp, wq, dp, dq));
        const double sign = dq[0] * q[0] + dq[1] * q[1] + dq[2] * q[2] + dq[3] * q[3] < 0.0 ? -1.0 : 1.0;
        for (int k = 0; k < 3; ++k) worst = fmax(worst, fabs(dp[k] - p[k]) / 100.0);
        for (int k = 0; k < 4; ++k) worst = fmax(worst, fabs(sign * dq[k] - q[k]));
        double back_p[3], back_q[4];
        assert_ok(sh_device_to_world(&m, dp, dq, back_p, back_q));
        for (int k = 0; k < 3; ++k) worst = fmax(worst, fabs(back_p[k] - wp[k]));
    }
    printf("device mapping round trips: worst relative difference %.2e\n", worst);
    assert_true(worst < 1e-13);
}

/* Bad input: a status, the outputs untouched; the check names the field. */
static void test_bad_mapping_and_poses_are_refused(void** state) {
    (void)state;
    sh_device_mapping m = desk_device();
    const double p[3] = {1.0, 2.0, 3.0}, q[4] = {1.0, 0.0, 0.0, 0.0}, zero_q[4] = {0.0, 0.0, 0.0, 0.0};
    const double nan_p[3] = {NAN, 0.0, 0.0};
    double wp[3] = {7.0, 7.0, 7.0}, wq[4] = {7.0, 7.0, 7.0, 7.0};
    assert_int_equal(sh_device_to_world(&m, nan_p, q, wp, wq), SH_ERR_INVALID_ARGUMENT);
    assert_int_equal(sh_device_to_world(&m, p, zero_q, wp, wq), SH_ERR_INVALID_ARGUMENT);
    assert_int_equal(sh_device_to_world(NULL, p, q, wp, wq), SH_ERR_INVALID_ARGUMENT);
    for (int k = 0; k < 3; ++k) assert_true(wp[k] == 7.0);
    m.scale = 0.0;
    assert_int_equal(sh_device_mapping_check(&m), SH_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(sh_last_error_message(), "mapping->scale"));
    assert_int_equal(sh_world_to_device(&m, p, q, wp, wq), SH_ERR_INVALID_ARGUMENT);
    m = desk_device();
    m.base_orientation[0] = m.base_orientation[1] = 0.0;
    assert_int_equal(sh_device_mapping_check(&m), SH_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(sh_last_error_message(), "base_orientation"));
    sh_device_mapping raw;
    memset(&raw, 0, sizeof raw);
    assert_int_equal(sh_device_mapping_check(&raw), SH_ERR_UNINITIALIZED_DEF);
    assert_int_equal(sh_device_force(&raw, p, p, wp, wp), SH_ERR_INVALID_ARGUMENT);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_default_is_the_identity),
        cmocka_unit_test(test_mm_y_up_device_in_a_z_up_world),
        cmocka_unit_test(test_round_trips_are_the_identity),
        cmocka_unit_test(test_bad_mapping_and_poses_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
