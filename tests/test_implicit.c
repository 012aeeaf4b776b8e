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
        cmocka_unit_test(test_backends_agree),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
