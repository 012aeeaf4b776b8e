/* Time integrators on a 1-DOF spring (node 0 fixed, node 1 of mass m, stiffness k) against
 * the analytic oscillator x(t) = L + A cos(w t), w = sqrt(k/m); and a free particle. */
#include "test_support.h"

#include <math.h>

static const double kMass = SH_TEST_OSC_MASS, kStiffness = SH_TEST_OSC_STIFFNESS, kRest = SH_TEST_OSC_REST,
                    kAmplitude = SH_TEST_OSC_AMPLITUDE;

typedef struct {
    sh_world* world;
    sh_body_id body;
} oscillator;

static oscillator make_oscillator(sh_integrator integrator) {
    oscillator o;
    o.world = sh_test_world(0.0);
    o.body = sh_test_oscillator(o.world, integrator, SH_LINEAR_SOLVER_DEFAULT);
    return o;
}

/* Largest |x_numeric - x_exact| over [0, T] with step dt. */
static double trajectory_error(sh_integrator integrator, double dt, double duration) {
    oscillator o = make_oscillator(integrator);
    const double w = sqrt(kStiffness / kMass);
    const int steps = (int)lround(duration / dt);
    double worst = 0.0;
    for (int n = 1; n <= steps; ++n) {
        assert_ok(sh_world_step(o.world, dt, NULL));
        double x[6];
        assert_ok(sh_body_get_positions(o.world, o.body, x, 2));
        const double exact = kRest + kAmplitude * cos(w * n * dt);
        worst = fmax(worst, fabs(x[3] - exact));
    }
    assert_ok(sh_world_destroy(o.world));
    return worst;
}

static void check_order(sh_integrator integrator, double dt, double expected_order) {
    const double e1 = trajectory_error(integrator, dt, 1.0);
    const double e2 = trajectory_error(integrator, dt / 2, 1.0);
    const double e3 = trajectory_error(integrator, dt / 4, 1.0);
    const double order1 = log2(e1 / e2), order2 = log2(e2 / e3);
    print_message("integrator %d: errors %.3e %.3e %.3e, orders %.3f %.3f (expected %.0f)\n", integrator, e1, e2, e3,
                  order1, order2, expected_order);
    assert_true(fabs(order1 - expected_order) < 0.15);
    assert_true(fabs(order2 - expected_order) < 0.15);
}

static void test_order_forward_euler(void** s) { (void)s; check_order(SH_INTEGRATOR_FORWARD_EULER, 2e-4, 1.0); }
static void test_order_symplectic_euler(void** s) { (void)s; check_order(SH_INTEGRATOR_SYMPLECTIC_EULER, 2e-4, 1.0); }
static void test_order_rk2(void** s) { (void)s; check_order(SH_INTEGRATOR_RK2, 2e-3, 2.0); }
static void test_order_rk4(void** s) { (void)s; check_order(SH_INTEGRATOR_RK4, 2e-2, 4.0); }

static double oscillator_energy(const oscillator* o) { return sh_test_oscillator_energy(o->world, o->body); }

/* Symplectic Euler conserves a modified energy: the true energy oscillates within
 * O(w dt) of E0 and does not drift, over 1e5 steps. */
static void test_symplectic_energy_bounded(void** s) {
    (void)s;
    oscillator o = make_oscillator(SH_INTEGRATOR_SYMPLECTIC_EULER);
    const double dt = 0.01, w = sqrt(kStiffness / kMass), e0 = oscillator_energy(&o);
    double lo = e0, hi = e0;
    for (int n = 0; n < 100000; ++n) {
        sh_step_report report;
        assert_ok(sh_world_step(o.world, dt, &report));
        const double e = oscillator_energy(&o);
        assert_close(report.kinetic_energy + report.elastic_energy, e, 1e-12);
        lo = fmin(lo, e);
        hi = fmax(hi, e);
    }
    /* The modified energy is E(1 - w dt sin-terms): the band is within w dt of E0. */
    assert_true(hi <= e0 * (1 + w * dt));
    assert_true(lo >= e0 * (1 - w * dt));
    assert_ok(sh_world_destroy(o.world));
}

/* Forward Euler multiplies m v^2 + k x^2 by exactly (1 + w^2 dt^2) per step. */
static void test_forward_euler_energy_growth(void** s) {
    (void)s;
    oscillator o = make_oscillator(SH_INTEGRATOR_FORWARD_EULER);
    const double dt = 0.01, w = sqrt(kStiffness / kMass), e0 = oscillator_energy(&o);
    const int steps = 100; /* amplitude stays below the rest length: the spring stays linear */
    for (int n = 0; n < steps; ++n) assert_ok(sh_world_step(o.world, dt, NULL));
    const double predicted = e0 * pow(1 + w * w * dt * dt, steps);
    assert_true(predicted > 2.0 * e0);
    assert_close(oscillator_energy(&o) / e0, predicted / e0, 1e-9);
    assert_ok(sh_world_destroy(o.world));
}

/* The critical step of an undamped spring on a fixed anchor is 2/w (leapfrog); RK4's is
 * 2 sqrt(2)/w; symplectic Euler is stable just below it and blows up just above it. */
static void test_critical_step(void** s) {
    (void)s;
    const double w = sqrt(kStiffness / kMass);
    oscillator o = make_oscillator(SH_INTEGRATOR_SYMPLECTIC_EULER);
    sh_body_info info;
    assert_ok(sh_body_get_info(o.world, o.body, &info));
    assert_close(info.dt_critical, 2.0 / w, 1e-12);
    sh_step_report report;
    assert_status(sh_world_step(o.world, 1.01 * 2.0 / w, &report), SH_ERR_UNSTABLE);
    assert_int_equal(report.unstable_body_count, 1);
    for (int n = 0; n < 1000; ++n) assert_ok(sh_world_step(o.world, 0.99 * 2.0 / w, NULL));
    assert_true(oscillator_energy(&o) < 2.0 * 0.5 * kStiffness * kAmplitude * kAmplitude * 100);
    assert_ok(sh_world_destroy(o.world));
    o = make_oscillator(SH_INTEGRATOR_RK4);
    assert_ok(sh_body_get_info(o.world, o.body, &info));
    assert_close(info.dt_critical, 2.0 * sqrt(2.0) / w, 1e-12);
    assert_ok(sh_world_destroy(o.world));
}

/* A spring body of one node and no spring is a particle: under gravity RK2 and RK4 are exact
 * for constant acceleration; symplectic Euler gives z_n = z0 - g dt^2 n (n + 1) / 2. */
static void test_free_particle(void** s) {
    (void)s;
    const sh_integrator integrators[3] = {SH_INTEGRATOR_SYMPLECTIC_EULER, SH_INTEGRATOR_RK2, SH_INTEGRATOR_RK4};
    for (int k = 0; k < 3; ++k) {
        sh_world* world = sh_test_world(-9.81);
        const double node[3] = {1.0, 2.0, 3.0};
        sh_spring_body_def def;
        sh_spring_body_def_default(&def);
        def.nodes = node;
        def.node_count = 1;
        def.node_mass = 0.2;
        def.integrator = integrators[k];
        sh_body_id body;
        assert_ok(sh_spring_body_create(world, &def, &body));
        const double v0[3] = {0.5, 0.0, 1.0};
        assert_ok(sh_body_set_velocities(world, body, v0, 1));
        const double dt = 0.01, g = 9.81;
        const int steps = 100;
        for (int n = 0; n < steps; ++n) assert_ok(sh_world_step(world, dt, NULL));
        double x[3];
        assert_ok(sh_body_get_positions(world, body, x, 1));
        const double t = steps * dt;
        const double z = k == 0 ? 3.0 + v0[2] * t - g * dt * dt * steps * (steps + 1) / 2.0 : 3.0 + v0[2] * t - 0.5 * g * t * t;
        assert_close(x[0], 1.0 + v0[0] * t, 1e-12);
        assert_close(x[1], 2.0, 1e-12);
        assert_close(x[2], z, 1e-12);
        assert_ok(sh_world_destroy(world));
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_order_forward_euler),     cmocka_unit_test(test_order_symplectic_euler),
        cmocka_unit_test(test_order_rk2),               cmocka_unit_test(test_order_rk4),
        cmocka_unit_test(test_symplectic_energy_bounded), cmocka_unit_test(test_forward_euler_energy_growth),
        cmocka_unit_test(test_critical_step),           cmocka_unit_test(test_free_particle),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
