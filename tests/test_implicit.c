/* Backward Euler against its exact discrete solution on a linear oscillator, its order, its
 * unconditional stability on a stiff body, and agreement of the sparse solver backends. */
#include "test_support.h"

#include <math.h>
#include <stdlib.h>

static const double kMass = 1.0, kStiffness = 100.0, kRest = 1.0, kAmplitude = 0.01;

static sh_body_id add_oscillator(sh_world* world, sh_linear_solver solver) {
    sh_spring_body_def def;
    sh_spring_body_def_default(&def);
    const double nodes[6] = {0, 0, 0, kRest, 0, 0};
    const int32_t springs[2] = {0, 1};
    def.nodes = nodes;
    def.node_count = 2;
    def.springs = springs;
    def.spring_count = 1;
    def.params.stiffness = kStiffness;
    def.node_mass = kMass;
    def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    def.implicit.linear_solver = solver;
    sh_body_id body;
    assert_ok(sh_world_add_spring_body(world, &def, &body));
    const int32_t anchor = 0;
    assert_ok(sh_body_fix_nodes(world, body, &anchor, 1));
    const double start[6] = {0, 0, 0, kRest + kAmplitude, 0, 0};
    assert_ok(sh_body_set_positions(world, body, start, 2));
    return body;
}

static double oscillator_energy(sh_world* world, sh_body_id body) {
    double x[6], v[6];
    assert_ok(sh_body_get_positions(world, body, x, 6));
    assert_ok(sh_body_get_velocities(world, body, v, 6));
    const double d = x[3] - kRest;
    return 0.5 * kMass * v[3] * v[3] + 0.5 * kStiffness * d * d;
}

/* For a linear system one linearised step is exact backward Euler, whose amplification on
 * (w x, v) has modulus 1 / sqrt(1 + w^2 h^2): the energy shrinks by exactly 1 / (1 + w^2 h^2)
 * per step, at any h, here 50 x the explicit critical step. */
static void test_oscillator_exact_decay(void** state) {
    (void)state;
    const double w = sqrt(kStiffness / kMass);
    const double steps[2] = {1e-3, 50 * 2.0 / w};
    for (int k = 0; k < 2; ++k) {
        sh_world* world = sh_test_world(0.0);
        const sh_body_id body = add_oscillator(world, SH_LINEAR_SOLVER_DEFAULT);
        const double h = steps[k], e0 = oscillator_energy(world, body);
        for (int n = 1; n <= 50 && pow(1.0 + w * w * h * h, -n) > 1e-12; ++n) { /* then x - L underflows */
            sh_step_report report;
            assert_ok(sh_world_step(world, h, &report));
            assert_int_equal(report.substeps, 1);
            assert_int_equal(report.newton_iterations, 1);
            assert_close(oscillator_energy(world, body) / e0, pow(1.0 + w * w * h * h, -n), 1e-10);
        }
        assert_ok(sh_world_destroy(world));
    }
}

/* First order against the analytic oscillator. */
static void test_oscillator_order(void** state) {
    (void)state;
    const double w = sqrt(kStiffness / kMass);
    double errors[3];
    for (int k = 0; k < 3; ++k) {
        const double h = 2e-4 / (1 << k);
        sh_world* world = sh_test_world(0.0);
        const sh_body_id body = add_oscillator(world, SH_LINEAR_SOLVER_DEFAULT);
        errors[k] = 0.0;
        for (int n = 1; n * h <= 1.0 + 1e-12; ++n) {
            assert_ok(sh_world_step(world, h, NULL));
            double x[6];
            assert_ok(sh_body_get_positions(world, body, x, 6));
            errors[k] = fmax(errors[k], fabs(x[3] - kRest - kAmplitude * cos(w * n * h)));
        }
        assert_ok(sh_world_destroy(world));
    }
    const double order1 = log2(errors[0] / errors[1]), order2 = log2(errors[1] / errors[2]);
    print_message("implicit Euler orders %.3f %.3f\n", order1, order2);
    assert_true(fabs(order1 - 1.0) < 0.15 && fabs(order2 - 1.0) < 0.15);
}

/* E = 1e9 Pa at dt = 1 ms (thousands of explicit critical steps): finite, no sub-steps, and the
 * total energy (kinetic + elastic + gravitational) never grows beyond round-off (1e-10
 * relative), for every material, with Newton iterations converged. */
static void test_stiff_body_stable(void** state) {
    (void)state;
    sh_mesh* box = sh_test_box(0.1, 0.02, 0.02, 5, 1, 1);
    sh_mesh_info info;
    assert_ok(sh_mesh_get_info(box, &info));
    double* x = malloc(sizeof(double) * 3 * info.node_count);
    assert_ok(sh_mesh_get_nodes(box, x, 3 * info.node_count));
    int32_t fixed[8];
    int fixed_count = 0;
    for (int i = 0; i < info.node_count; ++i)
        if (x[3 * i] < 1e-12) fixed[fixed_count++] = i;
    for (int model = 0; model < 4; ++model) {
        sh_world* world = sh_test_world(-9.81);
        sh_fem_body_def def;
        sh_test_stiff_implicit_def(&def, box, (sh_material_model)model);
        sh_body_id body;
        assert_ok(sh_world_add_fem_body(world, &def, &body));
        assert_ok(sh_body_fix_nodes(world, body, fixed, fixed_count));
        double previous = INFINITY;
        for (int s = 0; s < 200; ++s) {
            sh_step_report report;
            assert_ok(sh_world_step(world, 1e-3, &report));
            assert_int_equal(report.substeps, 1);
            const double total = report.kinetic_energy + report.elastic_energy + report.potential_energy;
            assert_true(isfinite(total));
            if (!(total <= previous + 1e-10 * fabs(previous)))
                print_message("model %d step %d: energy %.17g -> %.17g\n", model, s, previous, total);
            assert_true(total <= previous + 1e-10 * fabs(previous)); /* round-off of E = 1e9 forces */
            previous = total;
        }
        assert_ok(sh_world_destroy(world));
    }
    free(x);
    assert_ok(sh_mesh_destroy(box));
}

/* The exact backward Euler step of the oscillator along its axis with
 * node damping c (force -c m v): (m (1 + h c) + h^2 k) v1 = m v0 - h k (x0 - L), x1 = x0 + h v1.
 * The oscillator's axial stiffness is constant, so a kept factorisation is exact for it: every
 * step matches this recursion to round-off, and the report shows a factorisation only on the
 * first step and after dt or the damping changed. */
static void test_factor_reuse_exact_and_invalidated(void** state) {
    (void)state;
    sh_world* world = sh_test_world(0.0);
    const sh_body_id body = add_oscillator(world, SH_LINEAR_SOLVER_DEFAULT);
    double x = kRest + kAmplitude, v = 0.0, c = 0.0;
    const double phases[3][2] = {{1e-2, 0.0}, {3e-3, 0.0}, {3e-3, 5.0}}; /* (h, c) */
    int total = 0;
    for (int phase = 0; phase < 3; ++phase) {
        const double h = phases[phase][0];
        if (phases[phase][1] != c) {
            c = phases[phase][1];
            const double damping[2] = {c, c};
            assert_ok(sh_body_set_node_damping(world, body, damping, 2));
        }
        for (int n = 0; n < 20; ++n) {
            sh_step_report report;
            assert_ok(sh_world_step(world, h, &report));
            v = (kMass * v - h * kStiffness * (x - kRest)) / (kMass * (1.0 + h * c) + h * h * kStiffness);
            x += h * v;
            double xs[6], vs[6];
            assert_ok(sh_body_get_positions(world, body, xs, 6));
            assert_ok(sh_body_get_velocities(world, body, vs, 6));
            assert_true(fabs(xs[3] - x) <= 1e-14 && fabs(vs[3] - v) <= 1e-12);
            assert_int_equal(report.factorizations, n == 0 ? 1 : 0);
            total += report.factorizations;
        }
    }
    assert_int_equal(total, 3);
    assert_ok(sh_world_destroy(world));
}

/* Largest backward Euler residual |m (v1 - v0) - dt (f(x1) + m g)| over the free nodes, and
 * largest |x1 - x0 - dt v1|, from the body's state before (x0, v0) and after the step, with the
 * elastic forces f evaluated apart from the step (sh_body_get_elastic_forces). */
static void backward_euler_residual(sh_world* world, sh_body_id body, int n, const double* x0, const double* v0,
                                    const double* mass, const uint8_t* fixed, double dt, double g_z,
                                    double* momentum, double* position) {
    double* x1 = malloc(sizeof(double) * 3 * n);
    double* v1 = malloc(sizeof(double) * 3 * n);
    double* f = malloc(sizeof(double) * 3 * n);
    assert_ok(sh_body_get_positions(world, body, x1, 3 * n));
    assert_ok(sh_body_get_velocities(world, body, v1, 3 * n));
    assert_ok(sh_body_get_elastic_forces(world, body, f, 3 * n));
    *momentum = *position = 0.0;
    for (int i = 0; i < n; ++i) {
        if (fixed[i]) continue;
        for (int c = 0; c < 3; ++c) {
            const int j = 3 * i + c;
            const double r = mass[i] * (v1[j] - v0[j]) - dt * (f[j] + (c == 2 ? mass[i] * g_z : 0.0));
            *momentum = fmax(*momentum, fabs(r));
            *position = fmax(*position, fabs(x1[j] - x0[j] - dt * v1[j]));
        }
    }
    free(x1);
    free(v1);
    free(f);
}

/* A StVK bar clamped at one end swings down under gravity (a tip drop over half its length).
 * With Newton iterated to 1e-10 and a kept factorisation, every step still solves the backward
 * Euler equations (checked from outside with the elastic forces at the end of the step: the
 * momentum residual below 1e-8 of the weight's impulse on one node), and the positions match
 * exact Newton (a factorisation per iteration) to 1e-9 of the bar's length, with fewer
 * factorisations than iterations; the linearised step with reuse refactorises when the
 * rotation makes the kept tangent stale (more than once over the swing). */
static void test_factor_reuse_nonlinear(void** state) {
    (void)state;
    const double length = 0.1;
    sh_mesh* bar = sh_test_box(length, 0.01, 0.01, 10, 1, 1);
    sh_mesh_info info;
    assert_ok(sh_mesh_get_info(bar, &info));
    const int n = info.node_count;
    double* rest = malloc(sizeof(double) * 3 * n);
    double* x[2] = {malloc(sizeof(double) * 3 * n), malloc(sizeof(double) * 3 * n)};
    assert_ok(sh_mesh_get_nodes(bar, rest, 3 * n));
    int32_t fixed[8];
    int fixed_count = 0;
    for (int i = 0; i < n; ++i)
        if (rest[3 * i] < 1e-12) fixed[fixed_count++] = i;
    uint8_t* is_fixed = calloc((size_t)n, 1);
    for (int k = 0; k < fixed_count; ++k) is_fixed[fixed[k]] = 1;
    double* mass = malloc(sizeof(double) * n);
    double* x0 = malloc(sizeof(double) * 3 * n);
    double* v0 = malloc(sizeof(double) * 3 * n);
    const double dt = 5e-3, g_z = -9.81;
    int factorizations[3] = {0, 0, 0}, iterations[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) { /* 0: exact Newton, 1: Newton with reuse, 2: linearised with reuse */
        sh_world* world = sh_test_world(g_z);
        sh_fem_body_def def;
        sh_fem_body_def_default(&def);
        def.mesh = bar;
        def.material.model = SH_MATERIAL_STVK;
        def.material.young = 1e4;
        def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
        def.implicit.newton_max_iterations = k < 2 ? 30 : 1;
        def.implicit.newton_tolerance = 1e-10;
        def.implicit.factor_reuse = k == 0 ? 0.0 : 0.25;
        sh_body_id body;
        assert_ok(sh_world_add_fem_body(world, &def, &body));
        assert_ok(sh_body_fix_nodes(world, body, fixed, fixed_count));
        assert_ok(sh_body_get_masses(world, body, mass, n));
        double largest_mass = 0.0;
        for (int i = 0; i < n; ++i) largest_mass = fmax(largest_mass, mass[i]);
        for (int s = 0; s < 60; ++s) {
            assert_ok(sh_body_get_positions(world, body, x0, 3 * n));
            assert_ok(sh_body_get_velocities(world, body, v0, 3 * n));
            sh_step_report report;
            assert_ok(sh_world_step(world, dt, &report));
            factorizations[k] += report.factorizations;
            iterations[k] += report.newton_iterations;
            if (k == 1) {
                double momentum, position;
                backward_euler_residual(world, body, n, x0, v0, mass, is_fixed, dt, g_z, &momentum, &position);
                assert_true(momentum <= 1e-8 * dt * largest_mass * fabs(g_z));
                assert_true(position <= 1e-15);
            }
        }
        assert_ok(sh_body_get_positions(world, body, x[k < 2 ? k : 0], 3 * n));
        if (k == 1) {
            double tip_drop = 0.0;
            for (int j = 0; j < 3 * n; ++j) assert_true(fabs(x[1][j] - x[0][j]) <= 1e-9 * length);
            for (int i = 0; i < n; ++i) tip_drop = fmax(tip_drop, -x[1][3 * i + 2]);
            assert_true(tip_drop > 0.5 * length); /* a large rotation, not a small sag */
        }
        assert_ok(sh_world_destroy(world));
    }
    print_message("factorisations / Newton iterations over 60 steps: exact Newton %d / %d, reuse %d / %d, "
                  "linearised with reuse %d / %d\n",
                  factorizations[0], iterations[0], factorizations[1], iterations[1], factorizations[2], iterations[2]);
    assert_int_equal(factorizations[0], iterations[0]);
    assert_true(factorizations[1] < iterations[1]);
    assert_true(factorizations[2] > 1 && factorizations[2] < 60);
    free(rest);
    free(x[0]);
    free(x[1]);
    free(is_fixed);
    free(mass);
    free(x0);
    free(v0);
    assert_ok(sh_mesh_destroy(bar));
}

/* CHOLMOD, LDLT and CG give the same step on a deforming liver. */
static void test_backends_agree(void** state) {
    (void)state;
    sh_mesh* file = NULL;
    sh_mesh* liver = NULL;
    assert_ok(sh_mesh_load(SH_TEST_MESH("liver.msh"), &file));
    assert_ok(sh_mesh_transform(file, 0.01, NULL, &liver));
    sh_mesh_info info;
    assert_ok(sh_mesh_get_info(liver, &info));
    const int n = info.node_count;
    sh_linear_solver solvers[3] = {SH_LINEAR_SOLVER_LDLT, SH_LINEAR_SOLVER_CG, SH_LINEAR_SOLVER_CHOLMOD};
    const int solver_count = (sh_build_features() & SH_FEATURE_CHOLMOD) ? 3 : 2;
    if (solver_count == 2) print_message("built without CHOLMOD: its comparison is skipped\n");
    double* reference = malloc(sizeof(double) * 3 * n);
    double* x = malloc(sizeof(double) * 3 * n);
    for (int k = 0; k < solver_count; ++k) {
        sh_world* world = sh_test_world(-9.81);
        sh_fem_body_def def;
        sh_fem_body_def_default(&def);
        def.mesh = liver;
        def.material.model = SH_MATERIAL_NEOHOOKEAN;
        def.material.young = 1e4;
        def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
        def.implicit.linear_solver = solvers[k];
        def.implicit.cg_tolerance = 1e-12;
        def.implicit.factor_reuse = 0.0; /* every backend solves the same linearised systems */
        sh_body_id body;
        assert_ok(sh_world_add_fem_body(world, &def, &body));
        const int32_t clamp[6] = {0, 1, 2, 3, 4, 5};
        assert_ok(sh_body_fix_nodes(world, body, clamp, 6));
        for (int s = 0; s < 10; ++s) assert_ok(sh_world_step(world, 1e-2, NULL));
        assert_ok(sh_body_get_positions(world, body, k == 0 ? reference : x, 3 * n));
        if (k > 0)
            for (int j = 0; j < 3 * n; ++j) assert_true(fabs(x[j] - reference[j]) <= 1e-8);
        assert_ok(sh_world_destroy(world));
    }
    free(reference);
    free(x);
    assert_ok(sh_mesh_destroy(liver));
    assert_ok(sh_mesh_destroy(file));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_oscillator_exact_decay),
        cmocka_unit_test(test_oscillator_order),
        cmocka_unit_test(test_stiff_body_stable),
        cmocka_unit_test(test_factor_reuse_exact_and_invalidated),
        cmocka_unit_test(test_factor_reuse_nonlinear),
        cmocka_unit_test(test_backends_agree),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
