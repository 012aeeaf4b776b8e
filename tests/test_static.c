/* Static equilibrium against closed-form solutions: a bar under an end traction (nu = 0, so
 * the stress is exactly uniaxial and the displacement linear in x: exact for linear tets),
 * linear elasticity u = t x / E in one solve, StVK from its uniaxial law (1 + e) E (e + e^2/2)
 * = t by Newton; and a free-floating body refused. */
#include "test_support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double kLength = 0.1, kSide = 0.02, kYoung = 5e4;

typedef struct {
    sh_world* world;
    sh_mesh* mesh;
    sh_body_id body;
    int n;
    double* rest;
} bar;

/* Bar along x with its x = 0 face fixed and a dead traction t (Pa) on its x = L face,
 * distributed as consistent nodal loads: area / 3 of each face triangle to each of its nodes. */
static bar make_bar(sh_material_model model, double traction) {
    bar b;
    b.world = sh_test_world(0.0);
    b.mesh = sh_test_box(kLength, kSide, kSide, 6, 2, 2);
    sh_mesh_info info;
    assert_ok(sh_mesh_get_info(b.mesh, &info));
    b.n = info.node_count;
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = b.mesh;
    def.material.model = model;
    def.material.young = kYoung;
    def.material.poisson = 0.0;
    assert_ok(sh_fem_body_create(b.world, &def, &b.body));
    b.rest = malloc(sizeof(double) * 3 * b.n);
    assert_ok(sh_mesh_get_nodes(b.mesh, b.rest, b.n));
    int32_t* fixed = malloc(sizeof(int32_t) * b.n);
    const int fixed_count = sh_test_nodes_at(b.rest, b.n, 0, 0.0, fixed);
    assert_ok(sh_body_fix_nodes(b.world, b.body, fixed, fixed_count));
    free(fixed);

    double* force = calloc(3 * (size_t)b.n, sizeof(double));
    int32_t* tris = malloc(sizeof(int32_t) * 3 * info.surface_triangle_count);
    assert_ok(sh_mesh_get_surface_triangles(b.mesh, tris, info.surface_triangle_count));
    double area_sum = 0.0;
    for (int t = 0; t < info.surface_triangle_count; ++t) {
        const int32_t* tri = &tris[3 * t];
        if (b.rest[3 * tri[0]] < kLength - 1e-12 || b.rest[3 * tri[1]] < kLength - 1e-12 || b.rest[3 * tri[2]] < kLength - 1e-12)
            continue;
        const double* p0 = &b.rest[3 * tri[0]];
        const double* p1 = &b.rest[3 * tri[1]];
        const double* p2 = &b.rest[3 * tri[2]];
        const double area = 0.5 * fabs((p1[1] - p0[1]) * (p2[2] - p0[2]) - (p1[2] - p0[2]) * (p2[1] - p0[1]));
        area_sum += area;
        for (int a = 0; a < 3; ++a) force[3 * tri[a]] += traction * area / 3.0;
    }
    assert_close(area_sum, kSide * kSide, 1e-12);
    assert_ok(sh_body_set_external_forces(b.world, b.body, force, b.n));
    free(force);
    free(tris);
    return b;
}

static void free_bar(bar* b) {
    free(b->rest);
    assert_ok(sh_world_destroy(b->world));
    assert_ok(sh_mesh_destroy(b->mesh));
}

static void check_uniform_strain(const bar* b, double strain, double tol) {
    double* x = malloc(sizeof(double) * 3 * b->n);
    assert_ok(sh_body_get_positions(b->world, b->body, x, b->n));
    for (int i = 0; i < b->n; ++i) {
        assert_true(fabs(x[3 * i] - (1 + strain) * b->rest[3 * i]) <= tol * kLength * fabs(strain));
        assert_true(fabs(x[3 * i + 1] - b->rest[3 * i + 1]) <= tol * kLength * fabs(strain));
        assert_true(fabs(x[3 * i + 2] - b->rest[3 * i + 2]) <= tol * kLength * fabs(strain));
    }
    free(x);
}

static void test_linear_bar_one_solve(void** state) {
    (void)state;
    const sh_linear_solver solvers[3] = {SH_LINEAR_SOLVER_DEFAULT, SH_LINEAR_SOLVER_LDLT, SH_LINEAR_SOLVER_CG};
    for (int k = 0; k < 3; ++k) {
        const double t = 500.0; /* Pa: strain 1 % */
        bar b = make_bar(SH_MATERIAL_LINEAR, t);
        sh_static_def def;
        sh_static_def_default(&def);
        def.linear_solver = solvers[k];
        if (solvers[k] == SH_LINEAR_SOLVER_CG) def.tolerance = 1e-7;
        sh_static_report report;
        assert_ok(sh_world_solve_static(b.world, &def, &report));
        print_message("linear bar, solver %d: %d iterations, residual %.2e\n", solvers[k], report.iterations, report.residual);
        if (solvers[k] != SH_LINEAR_SOLVER_CG) assert_int_equal(report.iterations, 1);
        assert_true(report.converged == 1 && report.residual <= def.tolerance);
        check_uniform_strain(&b, t / kYoung, solvers[k] == SH_LINEAR_SOLVER_CG ? 1e-5 : 1e-9);
        free_bar(&b);
    }
}

/* StVK with nu = 0 (lambda = 0, mu = E/2) under a dead nominal traction t: F = diag(1+e, 1, 1)
 * with P11 = (1 + e) E (e + e^2 / 2) = t. Solved here by bisection, independently. */
static void test_stvk_bar_newton(void** state) {
    (void)state;
    const double t = 0.2 * kYoung; /* large: the strain is about 17 % */
    double lo = 0.0, hi = 1.0;
    for (int k = 0; k < 200; ++k) {
        const double e = 0.5 * (lo + hi);
        if ((1 + e) * kYoung * (e + 0.5 * e * e) < t) lo = e; else hi = e;
    }
    const double strain = 0.5 * (lo + hi);
    bar b = make_bar(SH_MATERIAL_STVK, t);
    sh_static_def def;
    sh_static_def_default(&def);
    sh_static_report report;
    assert_ok(sh_world_solve_static(b.world, &def, &report));
    print_message("StVK bar: strain %.6f, %d iterations, residual %.2e\n", strain, report.iterations, report.residual);
    /* Stretched, the tangent is the exact Hessian (nothing to project): Newton converges
     * quadratically, in a few iterations (4 here). */
    assert_true(report.iterations > 2 && report.iterations <= 6 && report.residual <= 1e-10);
    for (int k = 1; k < report.history_count && k < 4; ++k)
        assert_true(report.residual_history[k] < report.residual_history[k - 1]);
    check_uniform_strain(&b, strain, 1e-8);
    free_bar(&b);
}

/* No fixed node: K is singular; the call fails with SH_ERR_SOLVER and changes nothing. */
static void test_free_floating_refused(void** state) {
    (void)state;
    sh_world* world = sh_test_world(-9.81);
    sh_mesh* box = sh_test_box(0.1, 0.1, 0.1, 2, 2, 2);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = box;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    double before[3 * 27], after[3 * 27];
    assert_ok(sh_body_get_positions(world, body, before, 27));
    sh_static_def sdef;
    sh_static_def_default(&sdef);
    assert_status(sh_world_solve_static(world, &sdef, NULL), SH_ERR_SOLVER);
    assert_non_null(strstr(sh_last_error_message(), "singular"));
    assert_ok(sh_body_get_positions(world, body, after, 27));
    assert_memory_equal(before, after, sizeof before);
    sdef.internal_init = 0;
    assert_status(sh_world_solve_static(world, &sdef, NULL), SH_ERR_UNINITIALIZED_DEF);
    assert_ok(sh_world_destroy(world));
    assert_ok(sh_mesh_destroy(box));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_linear_bar_one_solve),
        cmocka_unit_test(test_stvk_bar_newton),
        cmocka_unit_test(test_free_floating_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
