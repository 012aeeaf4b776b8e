/* Backward Euler against its exact discrete solution on a linear oscillator with every linear
 * solver, its order, kept factorisations (exact where the tangent is constant, the backward
 * Euler equations still solved where it is not), and agreement of the backends on a liver.
 * Unconditional stability on stiff bodies is in test_stability.c. */
#include "test_support.h"

#include <math.h>
#include <stdlib.h>

/* The backends the library was built with: LDL^T, CG and, when built in, CHOLMOD. */
static int backends(sh_linear_solver out[3]) {
    out[0] = SH_LINEAR_SOLVER_LDLT;
    out[1] = SH_LINEAR_SOLVER_CG;
    out[2] = SH_LINEAR_SOLVER_CHOLMOD;
    if (sh_build_features() & SH_FEATURE_CHOLMOD) return 3;
    print_message("built without CHOLMOD: its cases are skipped\n");
    return 2;
}

/* For a linear system one linearised step is exact backward Euler, whose amplification on
 * (w x, v) has modulus 1 / sqrt(1 + w^2 h^2): the energy shrinks by exactly 1 / (1 + w^2 h^2)
 * per step, at any h, here 50 x the explicit critical step; with every linear solver. */
static void test_oscillator_exact_decay(void** state) {
    (void)state;
    const double w = sqrt(SH_TEST_OSC_STIFFNESS / SH_TEST_OSC_MASS);
    const double steps[2] = {1e-3, 50 * 2.0 / w};
    sh_linear_solver solvers[3];
    const int solver_count = backends(solvers);
    for (int b = 0; b < solver_count; ++b)
        for (int k = 0; k < 2; ++k) {
            sh_world* world = sh_test_world(0.0);
            const sh_body_id body = sh_test_oscillator(world, SH_INTEGRATOR_IMPLICIT_EULER, solvers[b]);
            const double h = steps[k], e0 = sh_test_oscillator_energy(world, body);
            for (int n = 1; n <= 50 && pow(1.0 + w * w * h * h, -n) > 1e-12; ++n) { /* then x - L underflows */
                sh_step_report report;
                assert_ok(sh_world_step(world, h, &report));
                assert_int_equal(report.substeps, 1);
                assert_int_equal(report.newton_iterations, 1);
                const double expected = pow(1.0 + w * w * h * h, -n), ratio = sh_test_oscillator_energy(world, body) / e0;
                assert_close(ratio, expected, 1e-10);
                assert_true(fabs(ratio / expected - 1.0) <= 1e-6); /* also where expected is tiny */
            }
            assert_ok(sh_world_destroy(world));
        }
}

/* First order against the analytic oscillator. */
static void test_oscillator_order(void** state) {
    (void)state;
    const double w = sqrt(SH_TEST_OSC_STIFFNESS / SH_TEST_OSC_MASS);
    double errors[3];
    for (int k = 0; k < 3; ++k) {
        const double h = 2e-4 / (1 << k);
        sh_world* world = sh_test_world(0.0);
        const sh_body_id body = sh_test_oscillator(world, SH_INTEGRATOR_IMPLICIT_EULER, SH_LINEAR_SOLVER_DEFAULT);
        errors[k] = 0.0;
        for (int n = 1; n * h <= 1.0 + 1e-12; ++n) {
            assert_ok(sh_world_step(world, h, NULL));
            double x[6];
            assert_ok(sh_body_get_positions(world, body, x, 2));
            errors[k] = fmax(errors[k], fabs(x[3] - SH_TEST_OSC_REST - SH_TEST_OSC_AMPLITUDE * cos(w * n * h)));
        }
        assert_ok(sh_world_destroy(world));
    }
    const double order1 = log2(errors[0] / errors[1]), order2 = log2(errors[1] / errors[2]);
    print_message("implicit Euler orders %.3f %.3f\n", order1, order2);
    assert_true(fabs(order1 - 1.0) < 0.15 && fabs(order2 - 1.0) < 0.15);
}

/* Against the hand recursion of backward Euler with node damping
 * (sh_test_oscillator_backward_euler), with every linear solver. The oscillator's axial
 * stiffness is constant, so a kept factorisation is exact for it: every step matches the
 * recursion to round-off, and a direct solver factorises only on the first step and after dt
 * or the damping changed (CG builds its preconditioner every step). */
static void test_factor_reuse_exact_and_invalidated(void** state) {
    (void)state;
    sh_linear_solver solvers[3];
    const int solver_count = backends(solvers);
    for (int b = 0; b < solver_count; ++b) {
        const int direct = solvers[b] != SH_LINEAR_SOLVER_CG;
        sh_world* world = sh_test_world(0.0);
        const sh_body_id body = sh_test_oscillator(world, SH_INTEGRATOR_IMPLICIT_EULER, solvers[b]);
        double stretch = SH_TEST_OSC_AMPLITUDE, v = 0.0, c = 0.0;
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
                sh_test_oscillator_backward_euler(&stretch, &v, h, c);
                double xs[6], vs[6];
                assert_ok(sh_body_get_positions(world, body, xs, 2));
                assert_ok(sh_body_get_velocities(world, body, vs, 2));
                assert_true(fabs(xs[3] - SH_TEST_OSC_REST - stretch) <= 1e-14 && fabs(vs[3] - v) <= 1e-12);
                assert_int_equal(report.factorizations, direct ? (n == 0) : 1);
                total += report.factorizations;
            }
        }
        assert_int_equal(total, direct ? 3 : 60);
        assert_ok(sh_world_destroy(world));
    }
}

/* The defaults with mesh, model and E = 10 kPa, stepped by implicit Euler. */
static sh_fem_body_def soft_implicit_def(const sh_mesh* mesh, sh_material_model model) {
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = model;
    def.material.young = 1e4;
    def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    return def;
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
    assert_ok(sh_body_get_positions(world, body, x1, n));
    assert_ok(sh_body_get_velocities(world, body, v1, n));
    assert_ok(sh_body_get_elastic_forces(world, body, f, n));
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
    sh_test_mesh_arrays m = sh_test_mesh_arrays_of(bar);
    const int n = m.node_count;
    double* x[2] = {malloc(sizeof(double) * 3 * n), malloc(sizeof(double) * 3 * n)};
    int32_t fixed[8];
    const int fixed_count = sh_test_nodes_at(m.nodes, n, 0, 0.0, fixed);
    uint8_t* is_fixed = calloc((size_t)n, 1);
    for (int k = 0; k < fixed_count; ++k) is_fixed[fixed[k]] = 1;
    double* mass = malloc(sizeof(double) * n);
    double* x0 = malloc(sizeof(double) * 3 * n);
    double* v0 = malloc(sizeof(double) * 3 * n);
    const double dt = 5e-3, g_z = -9.81;
    int factorizations[3] = {0, 0, 0}, iterations[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) { /* 0: exact Newton, 1: Newton with reuse, 2: linearised with reuse */
        sh_world* world = sh_test_world(g_z);
        sh_fem_body_def def = soft_implicit_def(bar, SH_MATERIAL_STVK);
        def.implicit.newton_max_iterations = k < 2 ? 30 : 1;
        def.implicit.newton_tolerance = 1e-10;
        def.implicit.factor_reuse = k == 0 ? 0.0 : 0.25;
        sh_body_id body;
        assert_ok(sh_fem_body_create(world, &def, &body));
        assert_ok(sh_body_fix_nodes(world, body, fixed, fixed_count));
        assert_ok(sh_body_get_masses(world, body, mass, n));
        double largest_mass = 0.0;
        for (int i = 0; i < n; ++i) largest_mass = fmax(largest_mass, mass[i]);
        for (int s = 0; s < 60; ++s) {
            assert_ok(sh_body_get_positions(world, body, x0, n));
            assert_ok(sh_body_get_velocities(world, body, v0, n));
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
        assert_ok(sh_body_get_positions(world, body, x[k < 2 ? k : 0], n));
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
    sh_test_mesh_arrays_free(&m);
    free(x[0]);
    free(x[1]);
    free(is_fixed);
    free(mass);
    free(x0);
    free(v0);
    assert_ok(sh_mesh_destroy(bar));
}

/* A step's reported elastic energy and sh_body_get_elastic_energy are the energy of the body's
 * state now, however it came about: against the same positions on a body never stepped (computed
 * afresh), at its rest shape (zero), and after its Young's modulus doubles (every law's energy is
 * linear in (lambda, mu): it doubles). */
static void test_energy_follows_state(void** state) {
    (void)state;
    sh_mesh* bar = sh_test_box(0.1, 0.01, 0.01, 10, 1, 1);
    sh_test_mesh_arrays m = sh_test_mesh_arrays_of(bar);
    const int n = m.node_count;
    int32_t fixed[8];
    const int fixed_count = sh_test_nodes_at(m.nodes, n, 0, 0.0, fixed);
    double* x = malloc(sizeof(double) * 3 * n);
    sh_world* world = sh_test_world(-9.81);
    sh_fem_body_def def = soft_implicit_def(bar, SH_MATERIAL_NEOHOOKEAN);
    sh_body_id body, fresh;
    assert_ok(sh_fem_body_create(world, &def, &body));
    assert_ok(sh_body_fix_nodes(world, body, fixed, fixed_count));
    assert_ok(sh_fem_body_create(world, &def, &fresh));
    assert_ok(sh_body_fix_nodes(world, fresh, fixed, fixed_count));
    sh_step_report report;
    for (int s = 0; s < 10; ++s) assert_ok(sh_world_step(world, 5e-3, &report));
    /* Both bodies took the same steps: put the fresh one where the stepped one is. */
    assert_ok(sh_body_get_positions(world, body, x, n));
    double energy, reference;
    assert_ok(sh_body_get_elastic_energy(world, body, &energy));
    assert_true(energy > 0.0);
    sh_world* other = sh_test_world(0.0);
    sh_body_id alone;
    assert_ok(sh_fem_body_create(other, &def, &alone));
    assert_ok(sh_body_set_positions(other, alone, x, n));
    assert_ok(sh_body_get_elastic_energy(other, alone, &reference));
    assert_close(energy, reference, 1e-12 * reference);
    assert_close(report.elastic_energy, 2.0 * reference, 2e-12 * reference); /* both bodies */
    assert_ok(sh_body_set_positions(world, body, m.nodes, n));
    assert_ok(sh_body_get_elastic_energy(world, body, &energy));
    assert_true(fabs(energy) <= 1e-12 * reference);
    assert_ok(sh_body_set_positions(world, body, x, n));
    sh_material stiffer = def.material;
    stiffer.young *= 2.0;
    int32_t* all = malloc(sizeof(int32_t) * (size_t)m.tet_count);
    for (int32_t t = 0; t < m.tet_count; ++t) all[t] = t;
    assert_ok(sh_body_set_material(world, body, all, m.tet_count, &stiffer));
    free(all);
    assert_ok(sh_body_get_elastic_energy(world, body, &energy));
    assert_close(energy, 2.0 * reference, 2e-12 * reference);
    assert_ok(sh_world_destroy(other));
    assert_ok(sh_world_destroy(world));
    sh_test_mesh_arrays_free(&m);
    free(x);
    assert_ok(sh_mesh_destroy(bar));
}

/* On a deforming liver (a large nonlinear system, where no closed form exists) CHOLMOD, LDLT and
 * CG solve the same linearised systems, so they give the same steps. */
static void test_backends_agree(void** state) {
    (void)state;
    sh_mesh* file = NULL;
    sh_mesh* liver = NULL;
    assert_ok(sh_mesh_load(SH_TEST_MESH("liver.msh"), &file));
    assert_ok(sh_mesh_transform(file, 0.01, NULL, &liver));
    sh_mesh_info info;
    assert_ok(sh_mesh_get_info(liver, &info));
    const int n = info.node_count;
    sh_linear_solver solvers[3];
    const int solver_count = backends(solvers);
    double* reference = malloc(sizeof(double) * 3 * n);
    double* x = malloc(sizeof(double) * 3 * n);
    for (int k = 0; k < solver_count; ++k) {
        sh_world* world = sh_test_world(-9.81);
        sh_fem_body_def def = soft_implicit_def(liver, SH_MATERIAL_NEOHOOKEAN);
        def.implicit.linear_solver = solvers[k];
        def.implicit.cg_tolerance = 1e-12;
        def.implicit.factor_reuse = 0.0; /* every backend solves the same linearised systems */
        sh_body_id body;
        assert_ok(sh_fem_body_create(world, &def, &body));
        const int32_t clamp[6] = {0, 1, 2, 3, 4, 5};
        assert_ok(sh_body_fix_nodes(world, body, clamp, 6));
        for (int s = 0; s < 10; ++s) assert_ok(sh_world_step(world, 1e-2, NULL));
        assert_ok(sh_body_get_positions(world, body, k == 0 ? reference : x, n));
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
        cmocka_unit_test(test_factor_reuse_exact_and_invalidated),
        cmocka_unit_test(test_factor_reuse_nonlinear),
        cmocka_unit_test(test_energy_follows_state),
        cmocka_unit_test(test_backends_agree),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
