/* The step-doubling error estimate of sh_step_report (sh_world_def.error_estimate) on a linear
 * oscillator: a mass on a spring of stiffness k whose other end is fixed, moving along the
 * spring. Its exact motion and its backward Euler steps are known in closed form. */
#include "test_support.h"

#include <math.h>
#include <string.h>

static sh_world* oscillator_world(int error_estimate, sh_integrator integrator, sh_body_id* body) {
    sh_world_def wd;
    sh_world_def_default(&wd);
    wd.gravity[2] = 0.0;
    wd.error_estimate = error_estimate;
    sh_world* world = NULL;
    assert_ok(sh_world_create(&wd, &world));
    *body = sh_test_oscillator(world, integrator, SH_LINEAR_SOLVER_DEFAULT);
    return world;
}

/* The estimate is exactly |x(one step) - x(two half steps)| of the hand-computed recursion,
 * the state kept is the full step's (bit-identical to a world without the estimate), and the
 * estimate is -1 when off. */
static void test_estimate_is_the_half_step_difference(void** state) {
    (void)state;
    sh_body_id with, without;
    sh_world* w1 = oscillator_world(1, SH_INTEGRATOR_IMPLICIT_EULER, &with);
    sh_world* w0 = oscillator_world(0, SH_INTEGRATOR_IMPLICIT_EULER, &without);
    double x = SH_TEST_OSC_AMPLITUDE, v = 0.0; /* stretch */
    const double h = 0.02;
    for (int n = 0; n < 10; ++n) {
        double xf = x, vf = v, xh = x, vh = v;
        sh_test_oscillator_backward_euler(&xf, &vf, h, 0.0);
        sh_test_oscillator_backward_euler(&xh, &vh, 0.5 * h, 0.0);
        sh_test_oscillator_backward_euler(&xh, &vh, 0.5 * h, 0.0);
        sh_step_report r1, r0;
        assert_ok(sh_world_step(w1, h, &r1));
        assert_ok(sh_world_step(w0, h, &r0));
        assert_close(r1.error_estimate, fabs(xf - xh), 1e-9);
        assert_true(fabs(r1.error_estimate / fabs(xf - xh) - 1.0) <= 1e-9);
        assert_true(r1.error_estimate_seconds > 0.0);
        assert_true(r0.error_estimate == -1.0 && r0.error_estimate_seconds == 0.0);
        double p1[6], p0[6], v1[6], v0[6];
        assert_ok(sh_body_get_positions(w1, with, p1, 2));
        assert_ok(sh_body_get_positions(w0, without, p0, 2));
        assert_ok(sh_body_get_velocities(w1, with, v1, 2));
        assert_ok(sh_body_get_velocities(w0, without, v0, 2));
        assert_memory_equal(p1, p0, sizeof p1);
        assert_memory_equal(v1, v0, sizeof v1);
        assert_true(fabs(p1[3] - SH_TEST_OSC_REST - xf) <= 1e-14);
        x = xf;
        v = vf;
    }
    assert_ok(sh_world_destroy(w1));
    assert_ok(sh_world_destroy(w0));
}

/* Against the exact motion x = L + A cos(w t): over one step from the exact state at t = 0.3 s
 * the full step's true error is 2^p / (2^p - 1) times the estimate for a method of order p, in
 * the limit of small h (here within 10 %): p = 1 for backward Euler, 4 for RK4. */
static void test_estimate_predicts_the_true_local_error(void** state) {
    (void)state;
    const double w = sqrt(SH_TEST_OSC_STIFFNESS / SH_TEST_OSC_MASS), t = 0.3, L = SH_TEST_OSC_REST,
                 A = SH_TEST_OSC_AMPLITUDE;
    const struct {
        sh_integrator integrator;
        int order;
        double h;
    } cases[] = {{SH_INTEGRATOR_IMPLICIT_EULER, 1, 1e-3}, {SH_INTEGRATOR_RK4, 4, 5e-3}};
    for (int c = 0; c < 2; ++c) {
        sh_body_id body;
        sh_world* world = oscillator_world(1, cases[c].integrator, &body);
        const double h = cases[c].h;
        const double start[6] = {0, 0, 0, L + A * cos(w * t), 0, 0};
        const double speed[6] = {0, 0, 0, -A * w * sin(w * t), 0, 0};
        assert_ok(sh_body_set_positions(world, body, start, 2));
        assert_ok(sh_body_set_velocities(world, body, speed, 2));
        sh_step_report report;
        assert_ok(sh_world_step(world, h, &report));
        double x[6];
        assert_ok(sh_body_get_positions(world, body, x, 2));
        const double true_error = fabs(x[3] - (L + A * cos(w * (t + h))));
        const double factor = pow(2.0, cases[c].order) / (pow(2.0, cases[c].order) - 1.0);
        print_message("order %d: true local error %.4g, estimate %.4g x %.4f = %.4g\n", cases[c].order, true_error,
                      report.error_estimate, factor, factor * report.error_estimate);
        assert_true(fabs(factor * report.error_estimate / true_error - 1.0) < 0.1);
        assert_ok(sh_world_destroy(world));
    }
}

/* A world def with error_estimate other than 0 or 1 is refused, naming the field. */
static void test_bad_flag_is_invalid_argument(void** state) {
    (void)state;
    sh_world_def wd;
    sh_world_def_default(&wd);
    wd.error_estimate = 2;
    sh_world* world = (sh_world*)1;
    assert_status(sh_world_create(&wd, &world), SH_ERR_INVALID_ARGUMENT);
    assert_null(world);
    assert_non_null(strstr(sh_last_error_message(), "error_estimate"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_estimate_is_the_half_step_difference),
        cmocka_unit_test(test_estimate_predicts_the_true_local_error),
        cmocka_unit_test(test_bad_flag_is_invalid_argument),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
