/* Deformable bodies: lumped mass, momentum, the patch test, boundary conditions, spring laws,
 * heterogeneous materials, and the stability policies on a stiff body. */
#include "test_support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static sh_body_id add_fem(sh_world* world, const sh_mesh* mesh, sh_material_model model, double young, double density,
                          sh_integrator integrator, sh_unstable_policy policy) {
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = model;
    def.material.young = young;
    def.material.poisson = 0.3;
    def.material.density = density;
    def.integrator = integrator;
    def.on_unstable = policy;
    sh_body_id body = SH_NULL_ID;
    assert_ok(sh_fem_body_create(world, &def, &body));
    return body;
}

/* Lumped masses sum to density x volume, for a box and for the liver (volume from the mesh). */
static void test_lumped_mass(void** state) {
    (void)state;
    sh_world* world = sh_test_world(-9.81);
    sh_mesh* box = sh_test_box(0.3, 0.2, 0.1, 3, 2, 2);
    sh_body_id body = add_fem(world, box, SH_MATERIAL_STVK, 1e4, 1070.0, SH_INTEGRATOR_SYMPLECTIC_EULER, SH_UNSTABLE_SUBSTEP);
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    assert_close(info.total_mass, 1070.0 * 0.3 * 0.2 * 0.1, 1e-12);
    /* Corner node 0 belongs to the cube's tets that contain it; every node gets rho V/4 per tet. */
    double masses[3 * 4 * 4];
    assert_ok(sh_body_get_masses(world, body, masses, info.node_count));
    double sum = 0.0;
    for (int i = 0; i < info.node_count; ++i) sum += masses[i];
    assert_close(sum, info.total_mass, 1e-12);

    /* A region of another density changes the total by (rho2 - rho1) x region volume: the
     * first 6 tets are the first cube (0.1 x 0.1 x 0.05). */
    const int32_t region[6] = {0, 1, 2, 3, 4, 5};
    sh_material dense = sh_test_material(SH_MATERIAL_NEOHOOKEAN, 5e4, 0.45, 2000.0);
    assert_ok(sh_body_set_material(world, body, region, 6, &dense));
    assert_ok(sh_body_get_info(world, body, &info));
    assert_close(info.total_mass, 1070.0 * 0.006 + (2000.0 - 1070.0) * 0.1 * 0.1 * 0.05, 1e-12);
    assert_ok(sh_world_destroy(world));
    assert_ok(sh_mesh_destroy(box));
}

static void test_lumped_mass_liver(void** state) {
    (void)state;
    sh_mesh* liver = NULL;
    assert_ok(sh_mesh_load(SH_TEST_MESH("liver.msh"), &liver));
    sh_mesh_info mi;
    assert_ok(sh_mesh_get_info(liver, &mi));
    sh_world* world = sh_test_world(-9.81);
    sh_body_id body = add_fem(world, liver, SH_MATERIAL_STVK, 1e4, 1000.0, SH_INTEGRATOR_SYMPLECTIC_EULER, SH_UNSTABLE_SUBSTEP);
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    assert_close(info.total_mass / (1000.0 * mi.volume), 1.0, 1e-12);
    assert_ok(sh_world_destroy(world));
    assert_ok(sh_mesh_destroy(liver));
}

/* A free body without gravity: internal forces sum to zero, so linear momentum is conserved
 * (exactly up to rounding) whatever the deformation, for every model and integrator. */
static void test_momentum_conserved(void** state) {
    (void)state;
    sh_mesh* box = sh_test_box(0.2, 0.1, 0.1, 2, 1, 1);
    sh_mesh_info mi;
    assert_ok(sh_mesh_get_info(box, &mi));
    const int n = mi.node_count;
    for (int model = 0; model < 4; ++model)
        for (int integrator = 0; integrator < 4; ++integrator) {
            sh_world* world = sh_test_world(0.0);
            sh_body_id body = add_fem(world, box, (sh_material_model)model, 1e4, 1000.0, (sh_integrator)integrator, SH_UNSTABLE_SUBSTEP);
            double v[3 * 64], m[64], x[3 * 64];
            srand(7);
            for (int k = 0; k < 3 * n; ++k) v[k] = 0.2 * ((double)rand() / RAND_MAX - 0.5);
            assert_ok(sh_body_set_velocities(world, body, v, n));
            assert_ok(sh_body_get_masses(world, body, m, n));
            double p0[3] = {0, 0, 0};
            for (int i = 0; i < n; ++i)
                for (int c = 0; c < 3; ++c) p0[c] += m[i] * v[3 * i + c];
            for (int s = 0; s < 50; ++s) assert_ok(sh_world_step(world, 1e-4, NULL));
            assert_ok(sh_body_get_velocities(world, body, v, n));
            assert_ok(sh_body_get_positions(world, body, x, n));
            double p[3] = {0, 0, 0}, scale = 0.0;
            for (int i = 0; i < n; ++i)
                for (int c = 0; c < 3; ++c) {
                    p[c] += m[i] * v[3 * i + c];
                    scale += m[i] * fabs(v[3 * i + c]);
                }
            for (int c = 0; c < 3; ++c) assert_true(fabs(p[c] - p0[c]) <= 1e-12 * scale);
            assert_ok(sh_world_destroy(world));
        }
    assert_ok(sh_mesh_destroy(box));
}

/* Patch test: boundary nodes prescribed to an affine field x = A X + b on an irregular mesh;
 * damped dynamics settle the interior onto the same affine field (a homogeneous deformation is
 * an equilibrium of every material). */
static void test_patch(void** state) {
    (void)state;
    const int cells = 3;
    sh_mesh* regular = sh_test_box(1.0, 1.0, 1.0, cells, cells, cells);
    sh_mesh_info mi;
    assert_ok(sh_mesh_get_info(regular, &mi));
    const int n = mi.node_count;
    double* X = malloc(sizeof(double) * 3 * n);
    int32_t* tets = malloc(sizeof(int32_t) * 4 * mi.tet_count);
    assert_ok(sh_mesh_get_nodes(regular, X, n));
    assert_ok(sh_mesh_get_tets(regular, tets, mi.tet_count));
    int32_t* boundary = malloc(sizeof(int32_t) * n);
    int boundary_count = 0;
    srand(11);
    for (int i = 0; i < n; ++i) {
        int on_boundary = 0;
        for (int c = 0; c < 3; ++c) on_boundary |= X[3 * i + c] < 1e-9 || X[3 * i + c] > 1 - 1e-9;
        if (on_boundary)
            boundary[boundary_count++] = i;
        else
            for (int c = 0; c < 3; ++c) X[3 * i + c] += 0.12 * ((double)rand() / RAND_MAX - 0.5); /* irregular */
    }
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_create(X, n, tets, mi.tet_count, &mesh));
    const double A[3][3] = {{1.01, 0.004, -0.002}, {0.003, 0.995, 0.006}, {-0.005, 0.002, 1.008}};
    const double b[3] = {0.01, -0.02, 0.005};
    double* target = malloc(sizeof(double) * 3 * n);
    for (int i = 0; i < n; ++i)
        for (int r = 0; r < 3; ++r)
            target[3 * i + r] = A[r][0] * X[3 * i] + A[r][1] * X[3 * i + 1] + A[r][2] * X[3 * i + 2] + b[r];
    double* bt = malloc(sizeof(double) * 3 * boundary_count);
    for (int k = 0; k < boundary_count; ++k) memcpy(&bt[3 * k], &target[3 * boundary[k]], sizeof(double) * 3);

    const sh_material_model models[2] = {SH_MATERIAL_LINEAR, SH_MATERIAL_STVK};
    for (int m = 0; m < 2; ++m) {
        sh_world* world = sh_test_world(0.0);
        sh_fem_body_def def;
        sh_fem_body_def_default(&def);
        def.mesh = mesh;
        def.material.model = models[m];
        def.material.young = 1e4;
        def.material.poisson = 0.3;
        def.damping_mass = 20.0;
        sh_body_id body;
        assert_ok(sh_fem_body_create(world, &def, &body));
        assert_ok(sh_body_prescribe_positions(world, body, boundary, bt, boundary_count));
        sh_body_info info;
        assert_ok(sh_body_get_info(world, body, &info));
        for (int s = 0; s < 6000; ++s) assert_ok(sh_world_step(world, 0.9 * info.dt_critical, NULL));
        double* x = malloc(sizeof(double) * 3 * n);
        assert_ok(sh_body_get_positions(world, body, x, n));
        double worst = 0.0;
        for (int k = 0; k < 3 * n; ++k) worst = fmax(worst, fabs(x[k] - target[k]));
        print_message("patch test (model %d): max deviation from the affine field %.3e m\n", models[m], worst);
        assert_true(worst < 1e-9);
        free(x);
        assert_ok(sh_world_destroy(world));
    }
    free(X), free(tets), free(boundary), free(target), free(bt);
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_mesh_destroy(regular));
}

/* Fixed nodes never move; external forces are held; gravity pulls the rest down. */
static void test_fixed_nodes_and_loads(void** state) {
    (void)state;
    sh_world* world = sh_test_world(-9.81);
    sh_mesh* box = sh_test_box(0.2, 0.05, 0.05, 4, 1, 1);
    sh_body_id body = add_fem(world, box, SH_MATERIAL_COROTATIONAL, 1e5, 1000.0, SH_INTEGRATOR_SYMPLECTIC_EULER, SH_UNSTABLE_SUBSTEP);
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    const int n = info.node_count;
    double x0[3 * 64], x[3 * 64];
    assert_ok(sh_body_get_positions(world, body, x0, n));
    int32_t fixed[16];
    int fixed_count = 0;
    for (int i = 0; i < n; ++i)
        if (x0[3 * i] < 1e-9) fixed[fixed_count++] = i;
    assert_ok(sh_body_fix_nodes(world, body, fixed, fixed_count));
    assert_ok(sh_body_get_info(world, body, &info));
    assert_int_equal(info.fixed_node_count, fixed_count);
    for (int s = 0; s < 200; ++s) assert_ok(sh_world_step(world, 1e-3, NULL));
    assert_ok(sh_body_get_positions(world, body, x, n));
    for (int k = 0; k < fixed_count; ++k)
        for (int c = 0; c < 3; ++c) assert_true(x[3 * fixed[k] + c] == x0[3 * fixed[k] + c]);
    double tip_drop = 0.0;
    for (int i = 0; i < n; ++i)
        if (x0[3 * i] > 0.2 - 1e-9) tip_drop = fmax(tip_drop, x0[3 * i + 2] - x[3 * i + 2]);
    assert_true(tip_drop > 0.0);
    assert_ok(sh_world_destroy(world));
    assert_ok(sh_mesh_destroy(box));
}

/* A prescribed node moves linearly to its target within one step and stays there. */
static void test_prescribed_positions(void** state) {
    (void)state;
    sh_world* world = sh_test_world(0.0);
    sh_spring_body_def defaults;
    sh_spring_body_def_default(&defaults);
    const sh_body_id body = sh_test_spring_pair(world, 1.0, &defaults.params, 1.0, SH_INTEGRATOR_SYMPLECTIC_EULER, SH_UNSTABLE_SUBSTEP);
    const int32_t node = 0;
    const double target[3] = {0.01, 0.02, -0.03};
    assert_ok(sh_body_prescribe_positions(world, body, &node, target, 1));
    sh_step_report report;
    assert_ok(sh_world_step(world, 0.01, &report));
    double x[6], v[6];
    assert_ok(sh_body_get_positions(world, body, x, 2));
    assert_ok(sh_body_get_velocities(world, body, v, 2));
    for (int c = 0; c < 3; ++c) {
        assert_true(x[c] == target[c]);
        assert_true(v[c] == 0.0);
    }
    /* The spring pulled node 1 toward the moving node: the spring shrank by the first step. */
    assert_ok(sh_world_step(world, 0.01, NULL));
    assert_ok(sh_body_get_positions(world, body, x, 2));
    for (int c = 0; c < 3; ++c) assert_true(x[c] == target[c]);
    assert_ok(sh_world_destroy(world));
}

/* Each spring law's tension against its formula, read back through the elastic forces of a
 * two-node body stretched along x; energies against the law's integral. */
static double spring_force(const sh_spring_params* params, double stretch, double* energy) {
    sh_world* world = sh_test_world(0.0);
    const double l0 = 0.5;
    const sh_body_id body = sh_test_spring_pair(world, l0, params, 1e-3, SH_INTEGRATOR_SYMPLECTIC_EULER, SH_UNSTABLE_SUBSTEP);
    const double x[6] = {0, 0, 0, l0 + stretch, 0, 0};
    assert_ok(sh_body_set_positions(world, body, x, 2));
    double f[6];
    assert_ok(sh_body_get_elastic_forces(world, body, f, 2));
    assert_true(f[0] == -f[3]);
    assert_ok(sh_body_get_elastic_energy(world, body, energy));
    assert_ok(sh_world_destroy(world));
    return f[0]; /* tension pulls node 0 toward +x */
}

static void test_spring_laws(void** state) {
    (void)state;
    const double l0 = 0.5, dx = 0.1, d = dx / l0;
    double energy;
    sh_spring_params p;
    memset(&p, 0, sizeof p);
    p.law = SH_SPRING_LINEAR;
    p.stiffness = 80.0;
    assert_close(spring_force(&p, dx, &energy), 80.0 * dx, 1e-12);
    assert_close(energy, 0.5 * 80.0 * dx * dx, 1e-12);

    p.law = SH_SPRING_CUBIC;
    p.lambda1 = 30.0;
    p.lambda2 = 12.0;
    assert_close(spring_force(&p, dx, &energy), 30.0 * d * d * d + 12.0 * d, 1e-12);
    assert_close(energy, l0 * (30.0 * pow(d, 4) / 4 + 12.0 * d * d / 2), 1e-12);
    assert_close(spring_force(&p, -dx, &energy), -(30.0 * d * d * d + 12.0 * d), 1e-12);

    p.law = SH_SPRING_HYPERBOLIC;
    p.a = 0.5;   /* saturates at 2 N */
    p.b = 0.01;  /* 100 N/m at small strain */
    assert_close(spring_force(&p, dx, &energy), dx / (0.5 * dx + 0.01), 1e-12);
    assert_close(energy, dx / 0.5 - 0.01 / 0.25 * log(1 + 0.5 * dx / 0.01), 1e-12);
    assert_close(spring_force(&p, -dx, &energy), -dx / (0.5 * dx + 0.01), 1e-12);
    assert_close(spring_force(&p, 100.0, &energy), 100.0 / (50.0 + 0.01), 1e-12);

    /* A table sampled from a linear law is reproduced exactly (monotone cubic keeps lines). */
    const double line[4][2] = {{-0.5, -10.0}, {0.0, 0.0}, {0.5, 10.0}, {1.0, 20.0}};
    p.law = SH_SPRING_TABLE;
    p.table = &line[0][0];
    p.table_rows = 4;
    assert_close(spring_force(&p, dx, &energy), 20.0 * d, 1e-12);
    assert_close(energy, l0 * 20.0 * d * d / 2, 1e-12);
    assert_close(spring_force(&p, 1.5 * l0, &energy), 20.0 * 1.5, 1e-12); /* linear beyond the end */
    /* A measured, strongly nonlinear curve: passes through the knots and stays monotone. */
    const double curve[5][2] = {{0.0, 0.0}, {0.1, 0.2}, {0.2, 1.5}, {0.3, 1.6}, {0.4, 5.0}};
    p.table = &curve[0][0];
    p.table_rows = 5;
    for (int k = 0; k < 5; ++k) assert_close(spring_force(&p, curve[k][0] * l0, &energy), curve[k][1], 1e-12);
    double previous = -1.0;
    for (int k = 0; k <= 400; ++k) {
        const double f = spring_force(&p, 0.001 * k * l0, &energy);
        assert_true(f >= previous);
        previous = f;
    }
}

/* Stiff body (E = 1e9 Pa) at 100 x dt_crit: the reject policy returns SH_ERR_UNSTABLE and
 * leaves the state bit for bit; the sub-step policy stays finite and bounded. */
static void test_stiff_policies(void** state) {
    (void)state;
    sh_mesh* box = sh_test_box(0.1, 0.05, 0.05, 4, 2, 2);
    sh_world* world = sh_test_world(-9.81);
    sh_body_id rejecting = add_fem(world, box, SH_MATERIAL_STVK, 1e9, 1000.0, SH_INTEGRATOR_SYMPLECTIC_EULER, SH_UNSTABLE_REJECT);
    sh_body_id substepping = add_fem(world, box, SH_MATERIAL_STVK, 1e9, 1000.0, SH_INTEGRATOR_SYMPLECTIC_EULER, SH_UNSTABLE_SUBSTEP);
    sh_body_info info;
    assert_ok(sh_body_get_info(world, rejecting, &info));
    const int n = info.node_count;
    const double dt = 100.0 * info.dt_critical;
    double x0[3 * 100], v0[3 * 100], x[3 * 100], v[3 * 100];
    for (int k = 0; k < 3 * n; ++k) v0[k] = 0.01 * sin(k);
    assert_ok(sh_body_set_velocities(world, rejecting, v0, n));
    assert_ok(sh_body_get_positions(world, rejecting, x0, n));
    assert_ok(sh_body_get_velocities(world, rejecting, v0, n));
    uint64_t warnings[SH_WARN_COUNT];
    for (int s = 0; s < 20; ++s) {
        sh_step_report report;
        assert_status(sh_world_step(world, dt, &report), SH_ERR_UNSTABLE);
        assert_int_equal(report.unstable_body_count, 1);
        assert_true(report.substeps >= 100);
        assert_true(isfinite(report.kinetic_energy) && isfinite(report.elastic_energy));
    }
    assert_ok(sh_body_get_positions(world, rejecting, x, n));
    assert_ok(sh_body_get_velocities(world, rejecting, v, n));
    assert_memory_equal(x, x0, sizeof(double) * 3 * n);
    assert_memory_equal(v, v0, sizeof(double) * 3 * n);
    assert_ok(sh_world_get_warnings(world, warnings));
    assert_int_equal(warnings[SH_WARN_UNSTABLE], 20);
    assert_ok(sh_body_get_positions(world, substepping, x, n));
    for (int k = 0; k < 3 * n; ++k) assert_true(isfinite(x[k]) && fabs(x[k] - x0[k]) < 0.01);
    assert_ok(sh_world_destroy(world));
    assert_ok(sh_mesh_destroy(box));
}

/* A state that runs away (forward Euler far above its critical step, sub-stepping disabled by
 * the runaway test) is rolled back bit for bit. */
static void test_runaway_rollback(void** state) {
    (void)state;
    sh_mesh* box = sh_test_box(0.1, 0.05, 0.05, 2, 1, 1);
    sh_world* world = sh_test_world(0.0);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = box;
    def.material.young = 1e5;
    def.runaway_speed = 1.0; /* m/s */
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    const int n = info.node_count;
    double v[3 * 32], x0[3 * 32], x[3 * 32];
    for (int k = 0; k < 3 * n; ++k) v[k] = 0.0;
    v[3 * (n - 1)] = 5.0; /* one node faster than the runaway speed */
    assert_ok(sh_body_set_velocities(world, body, v, n));
    assert_ok(sh_body_get_positions(world, body, x0, n));
    assert_status(sh_world_step(world, 0.5 * info.dt_critical, NULL), SH_ERR_UNSTABLE);
    assert_non_null(strstr(sh_last_error_message(), "rolled back"));
    assert_ok(sh_body_get_positions(world, body, x, n));
    assert_memory_equal(x, x0, sizeof(double) * 3 * n);
    assert_ok(sh_world_destroy(world));
    assert_ok(sh_mesh_destroy(box));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lumped_mass),       cmocka_unit_test(test_lumped_mass_liver),
        cmocka_unit_test(test_momentum_conserved), cmocka_unit_test(test_patch),
        cmocka_unit_test(test_fixed_nodes_and_loads), cmocka_unit_test(test_prescribed_positions),
        cmocka_unit_test(test_spring_laws),       cmocka_unit_test(test_stiff_policies),
        cmocka_unit_test(test_runaway_rollback),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
