/* Tools, obstacles and Hunt-Crossley contact: impact restitution against the impact ODE,
 * friction against Coulomb's law, the tool's reaction, degenerate inputs and capacity. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- The Hunt-Crossley impact, independently of the library ------------------------------ */

/* m x'' = -lambda x^n (1 + c x'), c = 3/2 alpha, from x = 0 at speed v_in > 0: integrated with
 * classical RK4 at a step of 1/20000 of the contact time scale until x returns to 0; the exit
 * speed x' < 0 is interpolated at the crossing. Returns -x'(exit) / v_in. */
static double hunt_crossley_ode_ratio(double m, double lambda, double n, double alpha, double v_in) {
    const double c = 1.5 * alpha;
    const double x_max = pow((n + 1.0) * 0.5 * m * v_in * v_in / lambda, 1.0 / (n + 1.0));
    const double h = x_max / v_in / 20000.0;
    double x = 0.0, v = v_in;
#define HC_ACC(X, V) ((X) > 0.0 ? -lambda * pow((X), n) * fmax(0.0, 1.0 + c * (V)) / m : 0.0)
    for (int i = 0; i < 10000000; ++i) {
        const double k1x = v, k1v = HC_ACC(x, v);
        const double k2x = v + 0.5 * h * k1v, k2v = HC_ACC(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
        const double k3x = v + 0.5 * h * k2v, k3v = HC_ACC(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
        const double k4x = v + h * k3v, k4v = HC_ACC(x + h * k3x, v + h * k3v);
        const double xn = x + h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
        const double vn = v + h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
        if (i > 0 && xn <= 0.0) {
            const double s = x / (x - xn); /* linear interpolation to x = 0 */
            return -(v + s * (vn - v)) / v_in;
        }
        x = xn;
        v = vn;
    }
#undef HC_ACC
    return NAN;
}

/* The same ratio from the closed form of the impact: with c = 3/2 alpha, integrating
 * v dv / (1 + c v) = -(lambda/m) x^n dx over the whole contact gives G(v_out) = G(v_in) for
 * G(v) = v / c - ln(1 + c v) / c^2; solved for v_out in (-1/c, 0) by bisection. */
static double hunt_crossley_closed_ratio(double alpha, double v_in) {
    const double c = 1.5 * alpha;
#define HC_G(V) ((V) / c - log1p(c * (V)) / (c * c))
    const double target = HC_G(v_in);
    double lo = -1.0 / c * (1.0 - 1e-15), hi = 0.0;  /* G decreasing on (-1/c, 0) */
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (HC_G(mid) > target) lo = mid;
        else hi = mid;
    }
#undef HC_G
    return -0.5 * (lo + hi) / v_in;
}

/* A particle (one-node spring body) of mass m at height z0 moving down at speed v, and a
 * plane obstacle z = 0 with the given law. */
static sh_body_id particle(sh_world* world, double m, double z0, double v, sh_integrator integrator) {
    sh_spring_body_def def;
    sh_spring_body_def_default(&def);
    const double node[3] = {0.0, 0.0, z0};
    def.nodes = node;
    def.node_count = 1;
    def.node_mass = m;
    def.integrator = integrator;
    sh_body_id body = 0;
    assert_ok(sh_world_add_spring_body(world, &def, &body));
    const double velocity[3] = {0.0, 0.0, -v};
    assert_ok(sh_body_set_velocities(world, body, velocity, 1));
    return body;
}

static sh_obstacle_id floor_plane(sh_world* world, const sh_contact_params* law) {
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_PLANE;
    def.contact = *law;
    sh_obstacle_id id = 0;
    assert_ok(sh_obstacle_create(world, &def, &id));
    return id;
}

/* Drops the particle and returns its rebound speed over its impact speed. */
static double simulated_ratio(const sh_contact_params* law, double m, double v_in, sh_integrator integrator) {
    sh_world* world = sh_test_world(0.0);
    floor_plane(world, law);
    const double x_max = pow((law->exponent + 1.0) * 0.5 * m * v_in * v_in / law->stiffness, 1.0 / (law->exponent + 1.0));
    const double dt = x_max / v_in / 400.0;
    const sh_body_id body = particle(world, m, 0.5 * x_max, v_in, integrator);
    double v[3] = {0};
    int left = 0;
    for (int i = 0; i < 100000 && !left; ++i) {
        assert_ok(sh_world_step(world, dt, NULL));
        double x[3];
        assert_ok(sh_body_get_positions(world, body, x, 3));
        assert_ok(sh_body_get_velocities(world, body, v, 3));
        left = v[2] > 0.0 && x[2] > 0.0;
    }
    assert_true(left);
    assert_ok(sh_world_destroy(world));
    return v[2] / v_in;
}

static void test_impact_restitution_matches_hunt_crossley(void** state) {
    (void)state;
    sh_contact_params law;
    sh_contact_params_default(&law);
    law.stiffness = 1e4;
    law.exponent = 1.5;
    law.damping = 0.3;
    const double m = 1e-3;
    const double speeds[] = {0.05, 0.2, 0.5, 1.0, 2.0};
    for (size_t k = 0; k < sizeof speeds / sizeof speeds[0]; ++k) {
        const double v = speeds[k];
        const double ode = hunt_crossley_ode_ratio(m, law.stiffness, law.exponent, law.damping, v);
        const double closed = hunt_crossley_closed_ratio(law.damping, v);
        assert_close(ode, closed, 1e-4); /* the two references agree */
        const double rk4 = simulated_ratio(&law, m, v, SH_INTEGRATOR_RK4);
        const double symplectic = simulated_ratio(&law, m, v, SH_INTEGRATOR_SYMPLECTIC_EULER);
        printf("v_in %.2f m/s: ODE %.5f, closed form %.5f, 1 - alpha v %.5f; RK4 %.5f, symplectic Euler %.5f\n", v, ode,
               closed, 1.0 - law.damping * v, rk4, symplectic);
        assert_true(fabs(rk4 - ode) <= 0.02 * ode);
        assert_true(fabs(symplectic - ode) <= 0.02 * ode);
        if (law.damping * v <= 0.1) assert_true(fabs(rk4 - (1.0 - law.damping * v)) <= 0.02);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_impact_restitution_matches_hunt_crossley),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
