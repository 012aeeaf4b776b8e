/* Stability on stiff and extreme cases. Every case asserts a criterion whose value comes from
 * outside the library: conservation or dissipation laws of the integrators (with the exact
 * discrete invariants where they exist), hand formulas for signed tet volumes, the analytic
 * amplification factors of the explicit schemes, and the spectrum of M^-1 K computed here by a
 * hand-written Jacobi eigensolver from the library's elastic forces.
 *
 *  1. E = 1e9 Pa, implicit Euler at 1 ms: a cube pressed by prescribed nodes and released;
 *     total energy (kinetic + elastic + gravity) never grows after the release.
 *  2. nu = 0.49 and 0.499: finite with explicit sub-stepping and implicit Euler; SH_WARN_LOCKING
 *     counted, and not for nu = 0.3.
 *  3. large deformation: a block squeezed to 10 % and stretched to 300 % of its height, then
 *     released: neo-Hookean and corotational return to the rest shape, no tet left inverted.
 *     The same loads quasi-statically through sh_world_solve_static.
 *  4. inversion: a tet's apex pushed through its base; neo-Hookean and corotational recover,
 *     StVK stays inverted (its reflected rest shape has zero energy) but stays finite, and
 *     SH_WARN_INVERTED reports it. Implicit Euler with Newton iterations must keep stepping a
 *     body that has nearly come to rest.
 *  5. node mass ratios of 1e6: symplectic Euler conserves its discrete invariant, RK4 and
 *     implicit Euler dissipate.
 *  6. the critical step of every explicit integrator against the blow-up step measured on bars.
 * Each case prints what it measured (cmocka's print_message) and its CPU time.
 */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* ------------------------------------------------------------------------------------------ */
/* Helpers                                                                                      */

static double seconds_since(clock_t start) { return (double)(clock() - start) / CLOCKS_PER_SEC; }

/* Rest nodes and tets of a mesh. */
typedef sh_test_mesh_arrays mesh_data;

/* Smallest det F = V / V0 over the tets (V0 from the rest positions). */
static double min_det_f(const mesh_data* m, const double* x) {
    double lowest = INFINITY;
    for (int t = 0; t < m->tet_count; ++t) {
        const double j = sh_test_tet_volume(x, &m->tets[4 * t]) / sh_test_tet_volume(m->nodes, &m->tets[4 * t]);
        lowest = j < lowest ? j : lowest;
    }
    return lowest;
}

static int all_finite(const double* a, int count) {
    for (int i = 0; i < count; ++i)
        if (!isfinite(a[i])) return 0;
    return 1;
}

/* Largest |x - rest| over all coordinates. */
static double max_displacement(const double* x, const double* rest, int n) {
    double d = 0.0;
    for (int i = 0; i < 3 * n; ++i) d = fmax(d, fabs(x[i] - rest[i]));
    return d;
}

/* Nodes whose coordinate `axis` equals value (to 1e-12 m); returns their count. */
static int nodes_at(const mesh_data* m, int axis, double value, int32_t* out) {
    return sh_test_nodes_at(m->nodes, m->node_count, axis, value, out);
}

static double total_energy(const sh_step_report* r) { return r->kinetic_energy + r->elastic_energy + r->potential_energy; }

/* One world step that must never crash or return garbage: SH_OK with finite positions, or a
 * rollback status with the body's positions and velocities exactly as before the call. */
static sh_status step_guarded(sh_world* world, sh_body_id body, int n, double dt, sh_step_report* report) {
    double* x0 = malloc(sizeof(double) * 6 * (size_t)n);
    double* x1 = malloc(sizeof(double) * 6 * (size_t)n);
    assert_ok(sh_body_get_positions(world, body, x0, n));
    assert_ok(sh_body_get_velocities(world, body, x0 + 3 * n, n));
    const sh_status status = sh_world_step(world, dt, report);
    char message[512];
    snprintf(message, sizeof message, "%s", sh_last_error_message());
    assert_ok(sh_body_get_positions(world, body, x1, n));
    assert_ok(sh_body_get_velocities(world, body, x1 + 3 * n, n));
    if (status == SH_OK) {
        assert_true(all_finite(x1, 6 * n));
    } else {
        if (status != SH_ERR_UNSTABLE && status != SH_ERR_NOT_CONVERGED && status != SH_ERR_SOLVER)
            print_error("unexpected status %s: %s\n", sh_status_string(status), message);
        assert_true(status == SH_ERR_UNSTABLE || status == SH_ERR_NOT_CONVERGED || status == SH_ERR_SOLVER);
        assert_memory_equal(x0, x1, sizeof(double) * 6 * (size_t)n);
    }
    free(x0);
    free(x1);
    return status;
}

static const char* model_name(sh_material_model model) {
    static const char* names[4] = {"linear", "StVK", "corotational", "neo-Hookean"};
    return names[model];
}

/* Cyclic Jacobi eigensolver for a symmetric n x n matrix a (row-major, destroyed): eigenvalues
 * into values, eigenvectors as the columns of vectors (row-major). */
static void jacobi_eigen(double* a, int n, double* values, double* vectors) {
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) vectors[i * n + j] = i == j ? 1.0 : 0.0;
    double norm2 = 0.0;
    for (int i = 0; i < n * n; ++i) norm2 += a[i] * a[i];
    for (int sweep = 0; sweep < 100; ++sweep) {
        double off = 0.0;
        for (int p = 0; p < n; ++p)
            for (int q = p + 1; q < n; ++q) off += a[p * n + q] * a[p * n + q];
        if (off <= 1e-30 * norm2) break;
        for (int p = 0; p < n; ++p)
            for (int q = p + 1; q < n; ++q) {
                const double apq = a[p * n + q];
                if (apq == 0.0) continue;
                const double theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                const double t = (theta >= 0.0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < n; ++k) { /* columns: A J */
                    const double akp = a[k * n + p], akq = a[k * n + q];
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for (int k = 0; k < n; ++k) { /* rows: J^T (A J) */
                    const double apk = a[p * n + k], aqk = a[q * n + k];
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for (int k = 0; k < n; ++k) {
                    const double vkp = vectors[k * n + p], vkq = vectors[k * n + q];
                    vectors[k * n + p] = c * vkp - s * vkq;
                    vectors[k * n + q] = s * vkp + c * vkq;
                }
            }
    }
    for (int i = 0; i < n; ++i) values[i] = a[i * n + i];
}

/* ------------------------------------------------------------------------------------------ */
/* 1. E = 1e9 Pa, implicit Euler at dt = 1 ms: a cube pressed and released                      */

/* A 5 cm cube (3x3x3 cells) with its bottom face fixed is pressed by 1 % (0.5 mm) by its top
 * face (prescribed nodes, 10 steps), held 20 steps, then released under gravity. With E = 1e9
 * Pa, dt = 1 ms is hundreds of explicit critical steps (printed and asserted > 100).
 * Backward Euler solved to convergence satisfies E_{n+1} - E_n = -|v_{n+1} - v_n|^2_M / 2 -
 * dt^2 v^T H v / 2 <= 0 while the elastic Hessian H is positive (small strain), so after the
 * release (no work from prescribed nodes any more) the total energy from the step report may
 * not grow by more than round-off (1e-10 relative), for every material. Also: finite, no
 * sub-steps, every node within 2 % of the cube's size of its rest box, energy dissipated. */
static void test_stiff_cube_energy_never_grows(void** state) {
    (void)state;
    const clock_t start = clock();
    const double side = 0.05;
    sh_mesh* cube = sh_test_box(side, side, side, 3, 3, 3);
    mesh_data m = sh_test_mesh_arrays_of(cube);
    int32_t bottom[16], top[16];
    const int nb = nodes_at(&m, 2, 0.0, bottom), nt = nodes_at(&m, 2, side, top);
    assert_int_equal(nb, 16);
    assert_int_equal(nt, 16);
    double targets[48];
    double* x = malloc(sizeof(double) * 3 * (size_t)m.node_count);
    for (int model = 0; model < 4; ++model) {
        sh_world* world = sh_test_world(-9.81);
        sh_fem_body_def def;
        sh_test_stiff_implicit_def(&def, cube, (sh_material_model)model);
        sh_body_id body;
        assert_ok(sh_fem_body_create(world, &def, &body));
        assert_ok(sh_body_fix_nodes(world, body, bottom, nb));
        if (model == 0) { /* the scale of the stiffness: the explicit critical step of this cube */
            sh_world* scale = sh_test_world(0.0);
            def.integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
            sh_body_id explicit_body;
            assert_ok(sh_fem_body_create(scale, &def, &explicit_body));
            sh_body_info info;
            assert_ok(sh_body_get_info(scale, explicit_body, &info));
            print_message("stiff cube: explicit dt_crit %.3g s, dt = 1 ms is %.0f of them\n", info.dt_critical, 1e-3 / info.dt_critical);
            assert_true(1e-3 / info.dt_critical > 100.0);
            assert_ok(sh_world_destroy(scale));
        }
        sh_step_report report;
        for (int s = 1; s <= 30; ++s) {
            const double press = 0.01 * side * (s < 10 ? s : 10) / 10.0;
            for (int k = 0; k < nt; ++k) {
                for (int c = 0; c < 3; ++c) targets[3 * k + c] = m.nodes[3 * top[k] + c];
                targets[3 * k + 2] -= press;
            }
            assert_ok(sh_body_prescribe_positions(world, body, top, targets, nt));
            assert_ok(sh_world_step(world, 1e-3, &report));
            assert_int_equal(report.substeps, 1);
            assert_true(isfinite(total_energy(&report)));
        }
        const double released = total_energy(&report), elastic_released = report.elastic_energy;
        assert_ok(sh_body_release_nodes(world, body, top, nt));
        double previous = released, worst_growth = -INFINITY;
        for (int s = 0; s < 200; ++s) {
            assert_ok(sh_world_step(world, 1e-3, &report));
            assert_int_equal(report.substeps, 1);
            const double total = total_energy(&report);
            assert_true(isfinite(total));
            worst_growth = fmax(worst_growth, (total - previous) / fabs(previous));
            if (!(total <= previous + 1e-10 * fabs(previous)))
                print_message("%s step %d after release: energy %.17g -> %.17g\n", model_name((sh_material_model)model), s, previous, total);
            assert_true(total <= previous + 1e-10 * fabs(previous));
            previous = total;
            assert_ok(sh_body_get_positions(world, body, x, m.node_count));
            assert_true(all_finite(x, 3 * m.node_count));
            for (int i = 0; i < 3 * m.node_count; ++i) assert_true(x[i] >= -0.02 * side && x[i] <= 1.02 * side);
        }
        assert_true(previous < released);
        print_message("stiff cube, %-12s: elastic energy at release %.4g J, total %.6g -> %.6g J, largest step change %+.2e "
                      "(relative)\n",
                      model_name((sh_material_model)model), elastic_released, released, previous, worst_growth);
        assert_ok(sh_world_destroy(world));
    }
    free(x);
    sh_test_mesh_arrays_free(&m);
    assert_ok(sh_mesh_destroy(cube));
    print_message("stiff cube: %.2f s\n", seconds_since(start));
}

/* ------------------------------------------------------------------------------------------ */
/* 2. Near-incompressible materials                                                             */

/* A 10 cm cantilever (E = 1 MPa) sags under gravity for 0.3 s with nu = 0.3, 0.49 and 0.499,
 * with symplectic Euler sub-stepped (nu = 0.499 puts lambda at 1.7e8 Pa, some 50 sub-steps per
 * 1 ms step) and with implicit Euler: every step succeeds, everything stays finite, no node moves
 * more than half the bar's length, and the tip moves down. SH_WARN_LOCKING is counted once per
 * body made with nu > 0.45 (linear tets lock), never for nu = 0.3, and once more when a region
 * gets nu = 0.499 through sh_body_set_material. The tip sags are printed: locking shows as a
 * stiffer bar at high nu, where Euler-Bernoulli's sag does not depend on nu. */
static void test_near_incompressible(void** state) {
    (void)state;
    const clock_t start = clock();
    const double length = 0.1, side = 0.02;
    sh_mesh* bar = sh_test_box(length, side, side, 5, 1, 1);
    mesh_data m = sh_test_mesh_arrays_of(bar);
    int32_t root[4], tip[4];
    const int nr = nodes_at(&m, 0, 0.0, root), ntip = nodes_at(&m, 0, length, tip);
    double* x = malloc(sizeof(double) * 3 * (size_t)m.node_count);
    const double poissons[3] = {0.3, 0.49, 0.499};
    const sh_material_model models[2] = {SH_MATERIAL_LINEAR, SH_MATERIAL_NEOHOOKEAN};
    const sh_integrator integrators[2] = {SH_INTEGRATOR_SYMPLECTIC_EULER, SH_INTEGRATOR_IMPLICIT_EULER};
    for (int mi = 0; mi < 2; ++mi)
        for (int ii = 0; ii < 2; ++ii)
            for (int pi = 0; pi < 3; ++pi) {
                sh_world* world = sh_test_world(-9.81);
                sh_fem_body_def def;
                sh_fem_body_def_default(&def);
                def.mesh = bar;
                def.material.model = models[mi];
                def.material.young = 1e6;
                def.material.poisson = poissons[pi];
                def.integrator = integrators[ii];
                def.on_unstable = SH_UNSTABLE_SUBSTEP;
                def.damping_mass = 20.0;
                sh_body_id body;
                assert_ok(sh_fem_body_create(world, &def, &body));
                uint64_t warnings[SH_WARN_COUNT];
                assert_ok(sh_world_get_warnings(world, warnings));
                assert_int_equal(warnings[SH_WARN_LOCKING], poissons[pi] > 0.45 ? 1 : 0);
                assert_ok(sh_body_fix_nodes(world, body, root, nr));
                int most_substeps = 0;
                for (int s = 0; s < 300; ++s) {
                    sh_step_report report;
                    assert_ok(sh_world_step(world, 1e-3, &report));
                    assert_true(isfinite(total_energy(&report)));
                    most_substeps = report.substeps > most_substeps ? report.substeps : most_substeps;
                    assert_ok(sh_body_get_positions(world, body, x, m.node_count));
                    assert_true(all_finite(x, 3 * m.node_count));
                    assert_true(max_displacement(x, m.nodes, m.node_count) <= 0.5 * length);
                }
                if (integrators[ii] == SH_INTEGRATOR_SYMPLECTIC_EULER) assert_true(most_substeps > 1);
                double sag = 0.0;
                for (int k = 0; k < ntip; ++k) sag += (m.nodes[3 * tip[k] + 2] - x[3 * tip[k] + 2]) / ntip;
                assert_true(sag > 0.0);
                assert_ok(sh_world_get_warnings(world, warnings));
                assert_int_equal(warnings[SH_WARN_LOCKING], poissons[pi] > 0.45 ? 1 : 0);
                assert_int_equal(warnings[SH_WARN_UNSTABLE], 0);
                print_message("cantilever %-11s %-9s nu = %.3f: tip sag %.4f mm, %d sub-steps\n", model_name(models[mi]),
                              ii == 0 ? "explicit" : "implicit", poissons[pi], 1e3 * sag, most_substeps);
                assert_ok(sh_world_destroy(world));
            }

    /* A region made nearly incompressible later is counted too. */
    sh_world* world = sh_test_world(-9.81);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = bar;
    def.material.poisson = 0.3;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    uint64_t warnings[SH_WARN_COUNT];
    assert_ok(sh_world_get_warnings(world, warnings));
    assert_int_equal(warnings[SH_WARN_LOCKING], 0);
    const int32_t region[6] = {0, 1, 2, 3, 4, 5};
    sh_material soft = sh_test_material(SH_MATERIAL_NEOHOOKEAN, 1e4, 0.45, 1000.0); /* nu = 0.45 is not above the threshold */
    assert_ok(sh_body_set_material(world, body, region, 6, &soft));
    assert_ok(sh_world_get_warnings(world, warnings));
    assert_int_equal(warnings[SH_WARN_LOCKING], 0);
    soft.poisson = 0.499;
    assert_ok(sh_body_set_material(world, body, region, 6, &soft));
    assert_ok(sh_world_get_warnings(world, warnings));
    assert_int_equal(warnings[SH_WARN_LOCKING], 1);
    assert_ok(sh_world_destroy(world));

    free(x);
    sh_test_mesh_arrays_free(&m);
    assert_ok(sh_mesh_destroy(bar));
    print_message("near-incompressible: %.2f s\n", seconds_since(start));
}

/* ------------------------------------------------------------------------------------------ */
/* 3. Large deformation                                                                         */

typedef struct {
    int failed_steps;       /* steps rolled back (status other than SH_OK) */
    int released_steps;     /* steps taken after the release */
    int at_rest;            /* 1 if every node ended slower than kRestSpeed */
    double min_det_loaded;  /* smallest det F over the loading and hold */
    double min_det_final;   /* smallest det F at the end */
    double final_error;     /* largest |x - X| at the end, relative to the block's height */
    double height_loaded;   /* top face height at full load, relative */
} deformation_result;

/* A body counts as back at rest when every node is slower than this (m/s). */
static const double kRestSpeed = 1e-7;

static double max_speed(sh_world* world, sh_body_id body, int n) {
    double* v = malloc(sizeof(double) * 3 * (size_t)n);
    assert_ok(sh_body_get_velocities(world, body, v, n));
    double fastest = 0.0;
    for (int i = 0; i < n; ++i) fastest = fmax(fastest, sqrt(v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]));
    free(v);
    return fastest;
}

/* A 2 cm block (3x3x3 cells, E = 10 kPa, nu = 0.3, no gravity, mass damping 100 1/s) with its
 * bottom face fixed: the top face is prescribed from height H to ratio * H over 40 steps of 2 ms
 * (implicit Euler, Newton iterations to 1e-6), held 20 steps, then released and stepped until
 * every node is slower than kRestSpeed (at most 400 steps) or a step is rolled back. */
static deformation_result deform_block(sh_material_model model, double ratio) {
    const double side = 0.02, dt = 2e-3;
    sh_mesh* block = sh_test_box(side, side, side, 3, 3, 3);
    mesh_data m = sh_test_mesh_arrays_of(block);
    int32_t bottom[16], top[16];
    const int nb = nodes_at(&m, 2, 0.0, bottom), nt = nodes_at(&m, 2, side, top);
    sh_world* world = sh_test_world(0.0);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = block;
    def.material.model = model;
    def.material.young = 1e4;
    def.material.poisson = 0.3;
    def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    def.implicit.newton_max_iterations = 30;
    def.implicit.newton_tolerance = 1e-6;
    def.damping_mass = 100.0;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    assert_ok(sh_body_fix_nodes(world, body, bottom, nb));
    double* x = malloc(sizeof(double) * 3 * (size_t)m.node_count);
    double targets[48];
    deformation_result r = {0, 0, 0, INFINITY, INFINITY, 0.0, 0.0};
    const int ramp = 40, hold = 20, free_steps = 400;
    for (int s = 1; s <= ramp + hold + free_steps; ++s) {
        if (s <= ramp) {
            const double h = side * (1.0 + (ratio - 1.0) * s / ramp);
            for (int k = 0; k < nt; ++k) {
                for (int c = 0; c < 2; ++c) targets[3 * k + c] = m.nodes[3 * top[k] + c];
                targets[3 * k + 2] = h;
            }
            assert_ok(sh_body_prescribe_positions(world, body, top, targets, nt));
        }
        if (s == ramp + hold + 1) assert_ok(sh_body_release_nodes(world, body, top, nt));
        sh_step_report report;
        if (step_guarded(world, body, m.node_count, dt, &report) != SH_OK) {
            ++r.failed_steps;
            /* After the release nothing changes between steps: a rolled-back step would fail
             * again at every later step. */
            if (s > ramp + hold) break;
        }
        assert_ok(sh_body_get_positions(world, body, x, m.node_count));
        if (s <= ramp + hold) r.min_det_loaded = fmin(r.min_det_loaded, min_det_f(&m, x));
        if (s == ramp + hold) r.height_loaded = x[3 * top[0] + 2] / side;
        if (s > ramp + hold) {
            r.released_steps = s - ramp - hold;
            r.at_rest = max_speed(world, body, m.node_count) < kRestSpeed;
            if (r.at_rest) break;
        }
    }
    r.min_det_final = min_det_f(&m, x);
    r.final_error = max_displacement(x, m.nodes, m.node_count) / side;
    free(x);
    assert_ok(sh_world_destroy(world));
    sh_test_mesh_arrays_free(&m);
    assert_ok(sh_mesh_destroy(block));
    return r;
}

/* Squeezed to 10 % and stretched to 300 % of its height, then released: neo-Hookean and
 * corotational take every step (no rollback), reach the prescribed height, come back to rest
 * within 400 steps, and then are at the rest shape within 1e-5 of the block's size with every
 * tet's det F > 0 (signed volumes). Tets may invert while squeezed (neither law has an energy
 * barrier at J = 0); the smallest det F under load is printed. StVK is run through the same
 * loads under the step_guarded contract only (finite, or rolled back unchanged); its outcome
 * is printed. */
static void test_large_deformation(void** state) {
    (void)state;
    const clock_t start = clock();
    const double ratios[2] = {0.1, 3.0};
    const sh_material_model models[3] = {SH_MATERIAL_NEOHOOKEAN, SH_MATERIAL_COROTATIONAL, SH_MATERIAL_STVK};
    for (int mi = 0; mi < 3; ++mi)
        for (int ri = 0; ri < 2; ++ri) {
            const clock_t case_start = clock();
            const deformation_result r = deform_block(models[mi], ratios[ri]);
            print_message("block %-12s to %3.0f %%: %d rolled-back steps, loaded height %.4f, min det F loaded %+.4f; "
                          "released: %s after %d steps, min det F %+.6f, max |x - X| / H %.2e (%.2f s)\n",
                          model_name(models[mi]), 100 * ratios[ri], r.failed_steps, r.height_loaded, r.min_det_loaded,
                          r.at_rest ? "at rest" : "stopped", r.released_steps, r.min_det_final, r.final_error,
                          seconds_since(case_start));
            if (models[mi] == SH_MATERIAL_STVK) continue;
            assert_int_equal(r.failed_steps, 0);
            assert_close(r.height_loaded, ratios[ri], 1e-12);
            assert_true(r.at_rest);
            assert_true(r.min_det_final > 0.0);
            assert_true(r.final_error <= 1e-5);
        }
    print_message("large deformation: %.2f s\n", seconds_since(start));
}

/* The same block and loads quasi-statically: the host moves the prescribed top face in 40
 * increments (10 %) or 20 increments (300 %) and calls sh_world_solve_static after each (its
 * load_steps scale applied forces, not prescribed positions), tolerance 1e-8, up to 2000
 * Newton iterations per increment (the PSD-projected tangent converges linearly near the
 * squeezed states). Neo-Hookean and corotational: every increment converges; with the top face
 * released one more static solve returns to the rest shape (the only equilibrium without load)
 * within 1e-7 of the block's size, every det F > 0. The largest iteration count and the
 * smallest det F of the loaded equilibria are printed. */
static void test_large_deformation_static(void** state) {
    (void)state;
    const clock_t start = clock();
    const double side = 0.02, ratios[2] = {0.1, 3.0};
    const int increments[2] = {40, 20};
    const sh_material_model models[2] = {SH_MATERIAL_NEOHOOKEAN, SH_MATERIAL_COROTATIONAL};
    sh_mesh* block = sh_test_box(side, side, side, 3, 3, 3);
    mesh_data m = sh_test_mesh_arrays_of(block);
    int32_t bottom[16], top[16];
    const int nb = nodes_at(&m, 2, 0.0, bottom), nt = nodes_at(&m, 2, side, top);
    double* x = malloc(sizeof(double) * 3 * (size_t)m.node_count);
    double targets[48];
    for (int mi = 0; mi < 2; ++mi)
        for (int ri = 0; ri < 2; ++ri) {
            sh_world* world = sh_test_world(0.0);
            sh_fem_body_def def;
            sh_fem_body_def_default(&def);
            def.mesh = block;
            def.material.model = models[mi];
            def.material.young = 1e4;
            def.material.poisson = 0.3;
            sh_body_id body;
            assert_ok(sh_fem_body_create(world, &def, &body));
            assert_ok(sh_body_fix_nodes(world, body, bottom, nb));
            sh_static_def sdef;
            sh_static_def_default(&sdef);
            sdef.tolerance = 1e-8;
            sdef.max_iterations = 2000;
            sh_static_report report;
            int most_iterations = 0;
            double min_det_loaded = INFINITY;
            for (int k = 1; k <= increments[ri]; ++k) {
                const double h = side * (1.0 + (ratios[ri] - 1.0) * k / increments[ri]);
                for (int a = 0; a < nt; ++a) {
                    for (int c = 0; c < 2; ++c) targets[3 * a + c] = m.nodes[3 * top[a] + c];
                    targets[3 * a + 2] = h;
                }
                assert_ok(sh_body_prescribe_positions(world, body, top, targets, nt));
                assert_ok(sh_world_solve_static(world, &sdef, &report));
                assert_true(report.converged);
                most_iterations = report.iterations > most_iterations ? report.iterations : most_iterations;
                assert_ok(sh_body_get_positions(world, body, x, m.node_count));
                assert_true(all_finite(x, 3 * m.node_count));
                min_det_loaded = fmin(min_det_loaded, min_det_f(&m, x));
            }
            assert_close(x[3 * top[0] + 2] / side, ratios[ri], 1e-12);
            assert_ok(sh_body_release_nodes(world, body, top, nt));
            assert_ok(sh_world_solve_static(world, &sdef, &report));
            assert_ok(sh_body_get_positions(world, body, x, m.node_count));
            const double error = max_displacement(x, m.nodes, m.node_count) / side, det = min_det_f(&m, x);
            print_message("static block %-12s to %3.0f %%: at most %d iterations per increment, min det F loaded %+.4f; "
                          "released in %d iterations: min det F %.6f, max |x - X| / H %.2e\n",
                          model_name(models[mi]), 100 * ratios[ri], most_iterations, min_det_loaded, report.iterations,
                          det, error);
            assert_true(det > 0.0);
            assert_true(error <= 1e-7);
            assert_ok(sh_world_destroy(world));
        }
    free(x);
    sh_test_mesh_arrays_free(&m);
    assert_ok(sh_mesh_destroy(block));
    print_message("large deformation, static: %.2f s\n", seconds_since(start));
}

/* ------------------------------------------------------------------------------------------ */
/* 4. Inversion                                                                                 */

static const double kTetSize = 0.01;

/* A 1 cm unit tet (E = 10 kPa, nu = 0.3, no gravity, mass damping 100 1/s) with its base
 * (nodes 0, 1, 2) fixed and its apex (node 3, rest (0, 0, s)) put at (0.2 s, 0.2 s, -0.5 s):
 * det F = -0.5. */
static sh_world* inverted_tet(sh_material_model model, sh_integrator integrator, sh_body_id* out_body) {
    sh_mesh* tet = sh_test_unit_tet(kTetSize);
    sh_world* world = sh_test_world(0.0);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = tet;
    def.material.model = model;
    def.material.young = 1e4;
    def.material.poisson = 0.3;
    def.integrator = integrator;
    def.on_unstable = SH_UNSTABLE_SUBSTEP;
    def.damping_mass = 100.0;
    def.implicit.newton_max_iterations = 20;
    def.implicit.newton_tolerance = 1e-8;
    assert_ok(sh_fem_body_create(world, &def, out_body));
    assert_ok(sh_mesh_destroy(tet));
    const int32_t base[3] = {0, 1, 2};
    assert_ok(sh_body_fix_nodes(world, *out_body, base, 3));
    const double s = kTetSize;
    const double x[12] = {0, 0, 0, s, 0, 0, 0, s, 0, 0.2 * s, 0.2 * s, -0.5 * s};
    assert_ok(sh_body_set_positions(world, *out_body, x, 4));
    return world;
}

static const int32_t kUnitTet[4] = {0, 1, 2, 3};

/* det F of the unit tet: its signed volume over s^3 / 6. */
static double unit_tet_det(sh_world* world, sh_body_id body) {
    double x[12];
    assert_ok(sh_body_get_positions(world, body, x, 4));
    return sh_test_tet_volume(x, kUnitTet) / (kTetSize * kTetSize * kTetSize / 6.0);
}

/* Released from det F = -0.5 and stepped 1 ms at a time, with symplectic Euler and RK4
 * (sub-stepped) and with implicit Euler (Newton iterations), until the apex is slower than kRestSpeed: every step
 * is finite or rolled back unchanged (step_guarded); neo-Hookean and corotational take every
 * step, reach det F > 0 within 300 steps (signed volume), come to rest within 400, and are then
 * at the rest shape (apex within 1e-6 s of (0, 0, s)). StVK's stored energy vanishes on the
 * reflected rest shape (F = diag(1, 1, -1) gives C = I), so it may settle there inverted: that
 * is printed, not asserted (its report is test_inversion_warned's business). */
static void test_inversion_recovery(void** state) {
    (void)state;
    const clock_t start = clock();
    const sh_material_model models[3] = {SH_MATERIAL_NEOHOOKEAN, SH_MATERIAL_COROTATIONAL, SH_MATERIAL_STVK};
    const sh_integrator integrators[3] = {SH_INTEGRATOR_SYMPLECTIC_EULER, SH_INTEGRATOR_RK4, SH_INTEGRATOR_IMPLICIT_EULER};
    const char* integrator_names[3] = {"symplectic", "RK4", "implicit"};
    for (int mi = 0; mi < 3; ++mi)
        for (int ii = 0; ii < 3; ++ii) {
            sh_body_id body;
            sh_world* world = inverted_tet(models[mi], integrators[ii], &body);
            assert_close(unit_tet_det(world, body), -0.5, 1e-12);
            int recovered_at = -1, failed = 0, steps = 0;
            for (int s = 1; s <= 400; ++s) {
                sh_step_report report;
                if (step_guarded(world, body, 4, 1e-3, &report) != SH_OK) ++failed;
                if (recovered_at < 0 && unit_tet_det(world, body) > 0.0) recovered_at = s;
                steps = s;
                if (max_speed(world, body, 4) < kRestSpeed) break;
            }
            double x[12];
            assert_ok(sh_body_get_positions(world, body, x, 4));
            const double apex_error = sqrt(x[9] * x[9] + x[10] * x[10] + (x[11] - kTetSize) * (x[11] - kTetSize));
            const double det = unit_tet_det(world, body);
            print_message("inverted tet %-12s %-10s: det F > 0 from step %d, at rest after %d steps, final det F %.6f, "
                          "apex error %.2e s, %d rolled-back steps\n",
                          model_name(models[mi]), integrator_names[ii], recovered_at, steps, det,
                          apex_error / kTetSize, failed);
            if (models[mi] != SH_MATERIAL_STVK) {
                assert_int_equal(failed, 0);
                assert_true(steps < 400);
                assert_true(recovered_at > 0 && recovered_at <= 300);
                assert_true(det > 0.0);
                assert_true(apex_error <= 1e-6 * kTetSize);
            }
            assert_ok(sh_world_destroy(world));
        }
    print_message("inversion recovery: %.2f s\n", seconds_since(start));
}

/* SH_WARN_INVERTED ("an element had det F <= 0 during a step"): the first step from det F =
 * -0.5 (its first force evaluation sees the inverted tet) raises it (report bit and world
 * counter) for neo-Hookean, corotational and StVK, with symplectic Euler, RK4 and implicit Euler,
 * including the steps that end with the tet already recovered; so does every later step that
 * starts and ends inverted (StVK staying on its reflected rest shape); no step that starts and
 * ends with det F > 0.5 raises it (after neo-Hookean and corotational have recovered); and the
 * world counter equals the number of steps whose report has the bit (once per step). Run until
 * the apex is at rest (at most 400 steps). Then one 10 ms step from det F = -0.01 (at rest)
 * must raise it too, also when the tet is upright at the end of the step: the header promises
 * det F <= 0 "at a force evaluation of a step", and the step's first evaluation is at the
 * inverted start. A case that only misses the warning is listed and fails at the end. */
static void test_inversion_warned(void** state) {
    (void)state;
    const sh_material_model models[3] = {SH_MATERIAL_NEOHOOKEAN, SH_MATERIAL_COROTATIONAL, SH_MATERIAL_STVK};
    const sh_integrator integrators[3] = {SH_INTEGRATOR_SYMPLECTIC_EULER, SH_INTEGRATOR_RK4, SH_INTEGRATOR_IMPLICIT_EULER};
    const char* integrator_names[3] = {"symplectic", "RK4", "implicit"};
    int missing = 0;
    for (int mi = 0; mi < 3; ++mi)
        for (int ii = 0; ii < 3; ++ii) {
            const char* integrator = integrator_names[ii];
            sh_body_id body;
            sh_world* world = inverted_tet(models[mi], integrators[ii], &body);
            sh_step_report report;
            assert_int_equal(step_guarded(world, body, 4, 1e-3, &report), SH_OK);
            uint64_t warnings[SH_WARN_COUNT];
            assert_ok(sh_world_get_warnings(world, warnings));
            if (!((report.warnings >> SH_WARN_INVERTED) & 1u) || warnings[SH_WARN_INVERTED] < 1) {
                print_message("inverted tet %-12s %-10s: first step from det F = -0.5: report bit %u, world counter %llu: "
                              "SH_WARN_INVERTED not raised\n",
                              model_name(models[mi]), integrator, (report.warnings >> SH_WARN_INVERTED) & 1u,
                              (unsigned long long)warnings[SH_WARN_INVERTED]);
                ++missing;
            }
            int false_reports = 0, inverted_unreported = 0, inverted_steps = 0;
            uint64_t reported_steps = (report.warnings >> SH_WARN_INVERTED) & 1u;
            for (int s = 2; s <= 400 && max_speed(world, body, 4) >= kRestSpeed; ++s) {
                const double before = unit_tet_det(world, body);
                assert_int_equal(step_guarded(world, body, 4, 1e-3, &report), SH_OK);
                const unsigned bit = (report.warnings >> SH_WARN_INVERTED) & 1u;
                reported_steps += bit;
                const double after = unit_tet_det(world, body);
                if (bit && before > 0.5 && after > 0.5) ++false_reports;
                if (before <= 0.0 && after <= 0.0) {
                    ++inverted_steps;
                    if (!bit) ++inverted_unreported;
                }
            }
            assert_int_equal(false_reports, 0);
            assert_ok(sh_world_get_warnings(world, warnings));
            assert_int_equal(warnings[SH_WARN_INVERTED], reported_steps); /* once per step */
            if (inverted_unreported) {
                print_message("inverted tet %-12s %-10s: %d of %d steps from and to det F <= 0 without SH_WARN_INVERTED\n",
                              model_name(models[mi]), integrator, inverted_unreported, inverted_steps);
                ++missing;
            }

            /* One 10 ms step (several sub-steps for the explicit schemes) from a barely inverted
             * tet, det F = -0.01 at rest: its first force evaluation sees det F <= 0 even when
             * the tet is upright again by the end of the step. */
            const double s = kTetSize;
            const double barely[12] = {0, 0, 0, s, 0, 0, 0, s, 0, 0.2 * s, 0.2 * s, -0.01 * s};
            const double rest_v[12] = {0};
            assert_ok(sh_body_set_positions(world, body, barely, 4));
            assert_ok(sh_body_set_velocities(world, body, rest_v, 4));
            assert_int_equal(step_guarded(world, body, 4, 1e-2, &report), SH_OK);
            if (!((report.warnings >> SH_WARN_INVERTED) & 1u)) {
                print_message("inverted tet %-12s %-10s: a 10 ms step (%d sub-steps) from det F = -0.01 ending at det F = "
                              "%+.3f: SH_WARN_INVERTED not raised\n",
                              model_name(models[mi]), integrator, report.substeps, unit_tet_det(world, body));
                ++missing;
            }
            assert_ok(sh_world_destroy(world));
        }
    assert_int_equal(missing, 0);
}

/* Implicit Euler with Newton iterations on a body that has nearly come to rest with no load
 * (no gravity, no external force): a 1 cm tet with its base fixed, apex 1e-11 m off its rest
 * position, moving at 1e-15 m/s. The backward Euler equations have a solution next to the
 * current state, and every step must find it (SH_OK, finite): a rollback here would repeat at
 * every later step, since the state does not change, and freeze the body for good. Every
 * material, newton_max_iterations = 20, newton_tolerance = 1e-8, with and without damping. */
static void test_implicit_newton_near_rest(void** state) {
    (void)state;
    int failures = 0;
    for (int model = 0; model < 4; ++model)
        for (int damped = 0; damped < 2; ++damped) {
            sh_mesh* tet = sh_test_unit_tet(kTetSize);
            sh_world* world = sh_test_world(0.0);
            sh_fem_body_def def;
            sh_fem_body_def_default(&def);
            def.mesh = tet;
            def.material.model = (sh_material_model)model;
            def.material.young = 1e4;
            def.material.poisson = 0.3;
            def.damping_mass = damped ? 100.0 : 0.0;
            def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
            def.implicit.newton_max_iterations = 20;
            def.implicit.newton_tolerance = 1e-8;
            sh_body_id body;
            assert_ok(sh_fem_body_create(world, &def, &body));
            assert_ok(sh_mesh_destroy(tet));
            const int32_t base[3] = {0, 1, 2};
            assert_ok(sh_body_fix_nodes(world, body, base, 3));
            const double s = kTetSize;
            const double x[12] = {0, 0, 0, s, 0, 0, 0, s, 0, -1e-11, -1e-11, s};
            const double v[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1e-15};
            assert_ok(sh_body_set_positions(world, body, x, 4));
            assert_ok(sh_body_set_velocities(world, body, v, 4));
            sh_step_report report;
            for (int step = 0; step < 5; ++step) {
                const sh_status status = step_guarded(world, body, 4, 1e-3, &report);
                if (status != SH_OK) {
                    print_message("%s, damping %g 1/s: step %d %s (Newton iterations %d, relative residual %.3g)\n",
                                  model_name((sh_material_model)model), def.damping_mass, step, sh_status_string(status),
                                  report.newton_iterations, report.newton_residual);
                    ++failures;
                    break;
                }
            }
            assert_ok(sh_world_destroy(world));
        }
    assert_int_equal(failures, 0);
}

/* ------------------------------------------------------------------------------------------ */
/* 5. Mass ratios of 1e6 between neighbouring nodes                                             */

enum { kChainNodes = 21 };
static const double kChainSpacing = 0.01, kChainStiffness = 100.0, kHeavy = 1.0, kLight = 1e-6;

/* A chain of 21 nodes along x, 1 cm apart, linear springs k = 100 N/m between neighbours,
 * masses alternating 1 kg (even nodes) and 1 mg (odd nodes), node 0 fixed, no gravity. It starts
 * with axial displacements of 0.1 mm and axial velocities giving every node about the same
 * kinetic energy, so the fast light-node modes (omega ~ sqrt(2 k / 1e-6) ~ 1.4e4 rad/s) and the
 * slow heavy ones both carry energy. Motion stays on the x axis with every spring stretched or
 * compressed by far less than its length, so the system is exactly linear. */
static sh_body_id add_chain(sh_world* world, sh_integrator integrator, sh_linear_solver solver) {
    double nodes[3 * kChainNodes] = {0}, masses[kChainNodes];
    int32_t springs[2 * (kChainNodes - 1)];
    for (int i = 0; i < kChainNodes; ++i) {
        nodes[3 * i] = kChainSpacing * i;
        masses[i] = i % 2 ? kLight : kHeavy;
    }
    for (int i = 0; i + 1 < kChainNodes; ++i) {
        springs[2 * i] = i;
        springs[2 * i + 1] = i + 1;
    }
    sh_spring_body_def def;
    sh_spring_body_def_default(&def);
    def.nodes = nodes;
    def.node_count = kChainNodes;
    def.springs = springs;
    def.spring_count = kChainNodes - 1;
    def.params.stiffness = kChainStiffness;
    def.node_masses = masses;
    def.integrator = integrator;
    def.on_unstable = SH_UNSTABLE_SUBSTEP;
    def.implicit.linear_solver = solver;
    def.implicit.cg_tolerance = 1e-13;
    sh_body_id body;
    assert_ok(sh_spring_body_create(world, &def, &body));
    const int32_t anchor = 0;
    assert_ok(sh_body_fix_nodes(world, body, &anchor, 1));
    double x[3 * kChainNodes] = {0}, v[3 * kChainNodes] = {0};
    for (int i = 0; i < kChainNodes; ++i) {
        x[3 * i] = nodes[3 * i] + (i ? 1e-4 * sin(1.7 * i) : 0.0);
        v[3 * i] = 1e-3 * cos(2.3 * i) / sqrt(masses[i]);
    }
    assert_ok(sh_body_set_positions(world, body, x, kChainNodes));
    assert_ok(sh_body_set_velocities(world, body, v, kChainNodes));
    return body;
}

/* Kinetic + elastic energy H of the chain and v . f (f the elastic forces). */
static void chain_energy(sh_world* world, sh_body_id body, double* energy, double* v_dot_f) {
    double v[3 * kChainNodes], f[3 * kChainNodes], elastic;
    assert_ok(sh_body_get_velocities(world, body, v, kChainNodes));
    assert_ok(sh_body_get_elastic_forces(world, body, f, kChainNodes));
    assert_ok(sh_body_get_elastic_energy(world, body, &elastic));
    double kinetic = 0.0, power = 0.0;
    for (int i = 0; i < kChainNodes; ++i) {
        const double m = i % 2 ? kLight : kHeavy;
        for (int k = 0; k < 3; ++k) {
            kinetic += 0.5 * m * v[3 * i + k] * v[3 * i + k];
            power += v[3 * i + k] * f[3 * i + k];
        }
    }
    *energy = kinetic + elastic;
    *v_dot_f = power;
}

/* Symplectic Euler (v += h a(x), x += h v) on a linear system conserves exactly the modified
 * energy Q = H + (h/2) v . f(x) (for one mode: w^2 x^2 + v^2 - h w^2 x v, found by solving
 * A^T S A = S for the step matrix A), and |v . f| <= w_max H, so H stays within
 * H_0 (1 + z/2) / (1 - z/2), z = w_max h < 2 (w_max <= sqrt(2 k (1/m1 + 1/m2)), Gershgorin).
 * Asserted over 1 s of 1 ms steps, sub-stepped by the library at h = dt / substeps: every step
 * succeeds with the same sub-step count > 1, Q is conserved to 1e-9, H stays in the band. The
 * guard itself is checked against the chain's exact blow-up step 2 / w_max (Jacobi on the
 * tridiagonal axial stiffness): between 0.5x and 1x.
 * RK4 (stable up to w h = 2 sqrt(2), where its amplification |R(i w h)| <= 1 for every mode)
 * never lets H grow. Implicit Euler (one linearised solve is exact here; default solver and CG)
 * makes H decrease at every step. All positions stay finite. */
/* w_max of the chain's axial motion: the square root of the largest eigenvalue of
 * M^-1/2 K M^-1/2 over the free nodes 1..20 (K the tridiagonal spring matrix; transverse motion
 * has no stiffness at rest length), by the Jacobi solver. */
static double chain_highest_frequency(void) {
    enum { kFree = kChainNodes - 1 };
    double a[kFree * kFree] = {0}, values[kFree], vectors[kFree * kFree];
    for (int i = 0; i < kFree; ++i) {
        const int node = i + 1;
        const double mi = node % 2 ? kLight : kHeavy;
        a[i * kFree + i] = (node + 1 < kChainNodes ? 2.0 : 1.0) * kChainStiffness / mi;
        if (i + 1 < kFree) {
            const double mj = (node + 1) % 2 ? kLight : kHeavy;
            a[i * kFree + i + 1] = a[(i + 1) * kFree + i] = -kChainStiffness / sqrt(mi * mj);
        }
    }
    jacobi_eigen(a, kFree, values, vectors);
    double w_max = 0.0;
    for (int i = 0; i < kFree; ++i) w_max = fmax(w_max, sqrt(fmax(values[i], 0.0)));
    return w_max;
}

/* Symplectic Euler, sub-stepped: its guard within [0.5, 1] of the exact blow-up step 2 / w_max,
 * the modified energy H + h/2 p conserved, H within its band. */
static void check_mass_ratio_symplectic(double w_bound, double dt) {
    double x[3 * kChainNodes];
    sh_world* world = sh_test_world(0.0);
    const sh_body_id body = add_chain(world, SH_INTEGRATOR_SYMPLECTIC_EULER, SH_LINEAR_SOLVER_DEFAULT);
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    const double w_max = chain_highest_frequency();
    assert_true(w_max <= w_bound);
    const double guard_ratio = info.dt_critical / (2.0 / w_max);
    assert_true(guard_ratio >= 0.5 && guard_ratio <= 1.0);
    double h0, p0;
    chain_energy(world, body, &h0, &p0);
    int substeps = 0;
    double q0 = 0.0, worst_q = 0.0, highest = 0.0, band = 0.0;
    for (int s = 0; s < 1000; ++s) {
        sh_step_report report;
        assert_ok(sh_world_step(world, dt, &report));
        if (s == 0) {
            substeps = report.substeps;
            assert_true(substeps > 1);
            const double h = dt / substeps, z = w_bound * h;
            assert_true(z < 2.0);
            q0 = h0 + 0.5 * h * p0;
            band = (1.0 + 0.5 * z) / (1.0 - 0.5 * z);
        }
        assert_int_equal(report.substeps, substeps);
        double e, p;
        chain_energy(world, body, &e, &p);
        const double q = e + 0.5 * dt / substeps * p;
        worst_q = fmax(worst_q, fabs(q - q0) / q0);
        highest = fmax(highest, e / h0);
        assert_true(fabs(q - q0) <= 1e-9 * q0);
        assert_true(e <= band * h0);
        assert_ok(sh_body_get_positions(world, body, x, kChainNodes));
        assert_true(all_finite(x, 3 * kChainNodes));
    }
    print_message("mass ratio 1e6, symplectic Euler: dt_crit %.4e s = %.4f x the blow-up step 2/w_max (w_max %.6g "
                  "rad/s); %d sub-steps of 1 ms, w_max h = %.3f; modified energy drift %.1e, max H / H0 %.4f "
                  "(band %.2f)\n",
                  info.dt_critical, guard_ratio, w_max, substeps, w_max * dt / substeps, worst_q, highest, band);
    assert_ok(sh_world_destroy(world));
}

/* RK4, sub-stepped: the energy never grows. */
static void check_mass_ratio_rk4(double dt) {
    double x[3 * kChainNodes];
    sh_world* world = sh_test_world(0.0);
    const sh_body_id body = add_chain(world, SH_INTEGRATOR_RK4, SH_LINEAR_SOLVER_DEFAULT);
    double previous, p, first;
    chain_energy(world, body, &previous, &p);
    first = previous;
    int substeps = 0;
    for (int s = 0; s < 1000; ++s) {
        sh_step_report report;
        assert_ok(sh_world_step(world, dt, &report));
        substeps = report.substeps;
        assert_true(substeps > 1);
        double e;
        chain_energy(world, body, &e, &p);
        assert_true(e <= previous * (1.0 + 1e-12));
        previous = e;
        assert_ok(sh_body_get_positions(world, body, x, kChainNodes));
        assert_true(all_finite(x, 3 * kChainNodes));
    }
    print_message("mass ratio 1e6, RK4: %d sub-steps, H / H0 after 1 s %.6f\n", substeps, previous / first);
    assert_ok(sh_world_destroy(world));
}

/* Implicit Euler with solver, never sub-stepped: the energy falls at every step, and the light
 * nodes' half of it is gone after 1 s. */
static void check_mass_ratio_implicit(sh_linear_solver solver, double dt) {
    double x[3 * kChainNodes];
    sh_world* world = sh_test_world(0.0);
    const sh_body_id body = add_chain(world, SH_INTEGRATOR_IMPLICIT_EULER, solver);
    const char* name = solver == SH_LINEAR_SOLVER_CG ? "CG" : "default";
    double previous, p, first;
    chain_energy(world, body, &previous, &p);
    first = previous;
    for (int s = 0; s < 1000; ++s) {
        sh_step_report report;
        assert_ok(sh_world_step(world, dt, &report));
        assert_int_equal(report.substeps, 1);
        double e;
        chain_energy(world, body, &e, &p);
        if (!(e < previous * (1.0 + 1e-12)))
            print_message("implicit chain (%s) step %d: H %.17g -> %.17g\n", name, s, previous, e);
        assert_true(e < previous * (1.0 + 1e-12));
        previous = e;
        assert_ok(sh_body_get_positions(world, body, x, kChainNodes));
        assert_true(all_finite(x, 3 * kChainNodes));
    }
    assert_true(previous < 0.6 * first);
    print_message("mass ratio 1e6, implicit Euler (%s): H / H0 after 1 s %.6f\n", name, previous / first);
    assert_ok(sh_world_destroy(world));
}

static void test_mass_ratio(void** state) {
    (void)state;
    const clock_t start = clock();
    const double w_bound = sqrt(2.0 * kChainStiffness * (1.0 / kHeavy + 1.0 / kLight));
    const double dt = 1e-3;
    check_mass_ratio_symplectic(w_bound, dt);
    check_mass_ratio_rk4(dt);
    check_mass_ratio_implicit(SH_LINEAR_SOLVER_DEFAULT, dt);
    check_mass_ratio_implicit(SH_LINEAR_SOLVER_CG, dt);
    print_message("mass ratio: %.2f s\n", seconds_since(start));
}

/* ------------------------------------------------------------------------------------------ */
/* 6. Critical step against the measured blow-up step                                           */

/* Energy factor of one step on a mode of frequency w started at (x, 0), z = w dt, for a scheme
 * whose step on y' = L y is the polynomial R(dt L): |R(i z)|^2 (forward Euler 1 + z^2, explicit
 * midpoint 1 + z^4 / 4, RK4 1 - z^6 / 72 + z^8 / 576); symplectic Euler maps (x, 0) to
 * ((1 - z^2) x, -w z x): (1 - z^2)^2 + z^2. */
static double mode_energy_factor(sh_integrator integrator, double z) {
    const double z2 = z * z;
    switch (integrator) {
        case SH_INTEGRATOR_FORWARD_EULER: return 1.0 + z2;
        case SH_INTEGRATOR_SYMPLECTIC_EULER: return (1.0 - z2) * (1.0 - z2) + z2;
        case SH_INTEGRATOR_RK2: return 1.0 + z2 * z2 / 4.0;
        default: return 1.0 - z2 * z2 * z2 / 72.0 + z2 * z2 * z2 * z2 / 576.0;
    }
}

static sh_body_id add_bar_body(sh_world* world, const sh_mesh* bar, sh_integrator integrator, sh_material_model model) {
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = bar;
    def.material.model = model;
    def.material.young = 1e4;
    def.material.poisson = 0.3;
    def.material.density = 1000.0;
    def.integrator = integrator;
    def.on_unstable = SH_UNSTABLE_REJECT;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    return body;
}

/* The library cannot be stepped above its guard (SH_UNSTABLE_REJECT rejects, SH_UNSTABLE_SUBSTEP
 * splits), so the blow-up step is measured as follows, on free bars (sh_test_box, linear
 * material, whose forces are exactly linear):
 *  - the stiffness K is assembled column by column from sh_body_get_elastic_forces at +-eps
 *    displacements and checked symmetric; with the lumped masses of sh_body_get_masses the
 *    spectrum of M^-1/2 K M^-1/2 is computed by the Jacobi solver above (checked by its residual):
 *    w_max and its mode shape u;
 *  - each library integrator is stepped once at its own dt_crit from (rest + u, v = 0) and the
 *    energy factor is compared with the scheme's analytic factor at z = w_max dt_crit (1e-6):
 *    this shows that the library's step is the textbook scheme on the highest mode, so that its
 *    blow-up step there is the textbook one: 2 / w_max for symplectic Euler (|trace| of the step
 *    matrix 2 - z^2 reaches 2) and 2 sqrt(2) / w_max for RK4 (|R(i z)| = 1 at z^2 = 8);
 *  - w_max is also measured from the library's own forward Euler step alone, w = sqrt(factor -
 *    1) / dt, and must agree with the eigensolver's;
 *  - the criterion: 0.5 <= dt_crit / blow-up step <= 1 for symplectic Euler and RK4;
 *  - forward Euler and RK2 have no undamped stable step (their factor exceeds 1 at every dt):
 *    asserted instead that they get the symplectic Euler guard (the leapfrog limit the header
 *    documents) and that their measured growth per step at dt_crit is exactly 1 + z^2 and
 *    1 + z^4 / 4 (so at most 5 per step at the guard);
 *  - at dt_crit, 2000 steps of symplectic Euler and RK4 from the mode plus a small random
 *    velocity perturbation stay bounded (symplectic Euler within H_0 (1 + z/2) / (1 - z/2), RK4
 *    never growing), and a step 1 % above dt_crit is rejected with the state unchanged.
 * dt_crit is also the same for every material model (it is a small-strain property). */
/* The stiffness of body (a linear material, forces exactly linear) at the mesh's rest positions,
 * dofs x dofs row-major, by central differences of its elastic forces; checked symmetric. */
static double* stiffness_by_differences(sh_world* world, sh_body_id body, const mesh_data* m) {
    const int n = m->node_count, dofs = 3 * n;
    double* k = malloc(sizeof(double) * (size_t)dofs * dofs);
    double* x = malloc(sizeof(double) * (size_t)dofs);
    double* fp = malloc(sizeof(double) * (size_t)dofs);
    double* fm = malloc(sizeof(double) * (size_t)dofs);
    const double eps = 1e-6;
    for (int j = 0; j < dofs; ++j) {
        memcpy(x, m->nodes, sizeof(double) * (size_t)dofs);
        x[j] += eps;
        assert_ok(sh_body_set_positions(world, body, x, n));
        assert_ok(sh_body_get_elastic_forces(world, body, fp, n));
        x[j] -= 2 * eps;
        assert_ok(sh_body_set_positions(world, body, x, n));
        assert_ok(sh_body_get_elastic_forces(world, body, fm, n));
        for (int i = 0; i < dofs; ++i) k[i * dofs + j] = -(fp[i] - fm[i]) / (2 * eps);
    }
    double kmax = 0.0, asym = 0.0;
    for (int i = 0; i < dofs * dofs; ++i) kmax = fmax(kmax, fabs(k[i]));
    for (int i = 0; i < dofs; ++i)
        for (int j = 0; j < i; ++j) asym = fmax(asym, fabs(k[i * dofs + j] - k[j * dofs + i]));
    assert_true(asym <= 1e-8 * kmax);
    free(x);
    free(fp);
    free(fm);
    return k;
}

/* The highest mode of K with lumped masses mass (per node): the largest eigenvalue of
 * M^-1/2 K M^-1/2 by the Jacobi solver, checked by its residual. Fills u (dofs values) with
 * its mode shape in displacements, scaled to 10 um at the largest; returns w_max (rad/s). */
static double highest_mode(const double* k, const double* mass, int dofs, double* u) {
    double* a = malloc(sizeof(double) * (size_t)dofs * dofs);
    double* a_copy = malloc(sizeof(double) * (size_t)dofs * dofs);
    double* values = malloc(sizeof(double) * (size_t)dofs);
    double* vectors = malloc(sizeof(double) * (size_t)dofs * dofs);
    for (int i = 0; i < dofs; ++i)
        for (int j = 0; j < dofs; ++j)
            a[i * dofs + j] = 0.5 * (k[i * dofs + j] + k[j * dofs + i]) / sqrt(mass[i / 3] * mass[j / 3]);
    memcpy(a_copy, a, sizeof(double) * (size_t)dofs * dofs);
    jacobi_eigen(a, dofs, values, vectors);
    int top = 0;
    for (int i = 1; i < dofs; ++i)
        if (values[i] > values[top]) top = i;
    const double lambda = values[top];
    double residual = 0.0;
    for (int i = 0; i < dofs; ++i) {
        double r = -lambda * vectors[i * dofs + top];
        for (int j = 0; j < dofs; ++j) r += a_copy[i * dofs + j] * vectors[j * dofs + top];
        residual += r * r;
    }
    assert_true(sqrt(residual) <= 1e-9 * lambda);
    double umax = 0.0;
    for (int i = 0; i < dofs; ++i) {
        u[i] = vectors[i * dofs + top] / sqrt(mass[i / 3]);
        umax = fmax(umax, fabs(u[i]));
    }
    for (int i = 0; i < dofs; ++i) u[i] *= 1e-5 / umax;
    free(a);
    free(a_copy);
    free(values);
    free(vectors);
    return sqrt(lambda);
}

/* For each of the four explicit integrators, on bar: dt_crit (into dt_crit[integrator]), the
 * same for every material model, and one step at dt_crit from rest + u whose energy factor is
 * the scheme's analytic one at z = w_max dt_crit. Returns w_max as forward Euler's step measures
 * it, sqrt(factor - 1) / dt. */
static double check_one_step_on_the_mode(sh_mesh* bar, const mesh_data* m, const double* u, double w_max,
                                         double dt_crit[4]) {
    const int n = m->node_count, dofs = 3 * n;
    double* x = malloc(sizeof(double) * (size_t)dofs);
    double w_measured = 0.0;
    for (int integrator = 0; integrator < 4; ++integrator) {
        sh_world* one = sh_test_world(0.0);
        const sh_body_id body = add_bar_body(one, bar, (sh_integrator)integrator, SH_MATERIAL_LINEAR);
        sh_body_info info;
        assert_ok(sh_body_get_info(one, body, &info));
        dt_crit[integrator] = info.dt_critical;
        assert_true(isfinite(info.dt_critical) && info.dt_critical > 0.0);
        for (int model = 1; model < 4; ++model) {
            const sh_body_id other = add_bar_body(one, bar, (sh_integrator)integrator, (sh_material_model)model);
            sh_body_info other_info;
            assert_ok(sh_body_get_info(one, other, &other_info));
            assert_close(other_info.dt_critical, info.dt_critical, 1e-12);
            assert_ok(sh_body_destroy(one, other));
        }
        for (int i = 0; i < dofs; ++i) x[i] = m->nodes[i] + u[i];
        assert_ok(sh_body_set_positions(one, body, x, n));
        double e0;
        assert_ok(sh_body_get_elastic_energy(one, body, &e0));
        sh_step_report report;
        assert_ok(sh_world_step(one, info.dt_critical, &report));
        assert_int_equal(report.substeps, 1);
        const double factor = (report.kinetic_energy + report.elastic_energy) / e0;
        const double expected = mode_energy_factor((sh_integrator)integrator, w_max * info.dt_critical);
        if (!(fabs(factor - expected) <= 1e-6 * expected))
            print_message("integrator %d: energy factor %.12f, analytic %.12f at z = %.6f\n", integrator, factor,
                          expected, w_max * info.dt_critical);
        assert_true(fabs(factor - expected) <= 1e-6 * expected);
        if (integrator == SH_INTEGRATOR_FORWARD_EULER) w_measured = sqrt(factor - 1.0) / info.dt_critical;
        assert_ok(sh_world_destroy(one));
    }
    free(x);
    return w_measured;
}

/* Symplectic Euler and RK4 at dt_crit for 2000 steps from rest + u with a small random velocity
 * stay bounded (symplectic Euler within H_0 (1 + z/2) / (1 - z/2), RK4 never growing); a step 1 %
 * above dt_crit is then rejected with the state unchanged. */
static void check_long_runs_at_critical_step(sh_mesh* bar, const mesh_data* m, const double* u, const double* mass,
                                             double w_max) {
    const int n = m->node_count, dofs = 3 * n;
    const sh_integrator stable[2] = {SH_INTEGRATOR_SYMPLECTIC_EULER, SH_INTEGRATOR_RK4};
    double* x = malloc(sizeof(double) * (size_t)dofs);
    double* v = malloc(sizeof(double) * (size_t)dofs);
    for (int si = 0; si < 2; ++si) {
        sh_world* run = sh_test_world(0.0);
        const sh_body_id body = add_bar_body(run, bar, stable[si], SH_MATERIAL_LINEAR);
        sh_body_info info;
        assert_ok(sh_body_get_info(run, body, &info));
        unsigned seed = 12345u;
        for (int i = 0; i < dofs; ++i) {
            x[i] = m->nodes[i] + u[i];
            seed = seed * 1103515245u + 12345u;
            v[i] = 0.1 * 1e-5 * w_max * (((seed >> 8) & 0xffff) / 32768.0 - 1.0);
        }
        assert_ok(sh_body_set_positions(run, body, x, n));
        assert_ok(sh_body_set_velocities(run, body, v, n));
        double e0;
        assert_ok(sh_body_get_elastic_energy(run, body, &e0));
        for (int i = 0; i < dofs; ++i) e0 += 0.5 * mass[i / 3] * v[i] * v[i];
        const double z = w_max * info.dt_critical, band = (1.0 + 0.5 * z) / (1.0 - 0.5 * z);
        double previous = e0, highest = 0.0;
        for (int s = 0; s < 2000; ++s) {
            sh_step_report report;
            assert_ok(sh_world_step(run, info.dt_critical, &report));
            const double e = report.kinetic_energy + report.elastic_energy;
            highest = fmax(highest, e / e0);
            if (stable[si] == SH_INTEGRATOR_SYMPLECTIC_EULER) assert_true(e <= band * e0);
            else assert_true(e <= previous * (1.0 + 1e-10));
            previous = e;
        }
        print_message("  %s at dt_crit for 2000 steps: max H / H0 %.4f%s\n",
                      stable[si] == SH_INTEGRATOR_RK4 ? "RK4" : "symplectic Euler", highest,
                      stable[si] == SH_INTEGRATOR_RK4 ? " (never growing)" : "");
        double before[2][3 * 200], after[2][3 * 200];
        assert_true(dofs <= 3 * 200);
        assert_ok(sh_body_get_positions(run, body, before[0], n));
        assert_ok(sh_body_get_velocities(run, body, before[1], n));
        assert_status(sh_world_step(run, 1.01 * info.dt_critical, NULL), SH_ERR_UNSTABLE);
        assert_ok(sh_body_get_positions(run, body, after[0], n));
        assert_ok(sh_body_get_velocities(run, body, after[1], n));
        assert_memory_equal(before[0], after[0], sizeof(double) * (size_t)dofs);
        assert_memory_equal(before[1], after[1], sizeof(double) * (size_t)dofs);
        assert_ok(sh_world_destroy(run));
    }
    free(x);
    free(v);
}

/* The guards against the measured blow-up steps: 0.5 <= dt_crit / blow-up <= 1 for symplectic
 * Euler (2 / w) and RK4 (2 sqrt(2) / w); forward Euler and RK2 get symplectic Euler's guard. */
static void check_critical_ratios(const int cells[3], int dofs, double w_max, double w_measured,
                                  const double dt_crit[4]) {
    const double blowup_se = 2.0 / w_measured, blowup_rk4 = 2.0 * sqrt(2.0) / w_measured;
    const double ratio_se = dt_crit[SH_INTEGRATOR_SYMPLECTIC_EULER] / blowup_se;
    const double ratio_rk4 = dt_crit[SH_INTEGRATOR_RK4] / blowup_rk4;
    const double z_fe = w_max * dt_crit[SH_INTEGRATOR_FORWARD_EULER], z_rk2 = w_max * dt_crit[SH_INTEGRATOR_RK2];
    print_message("bar %dx%dx%d (%d DOF): w_max %.6g rad/s (forward Euler measures %.6g); symplectic Euler dt_crit "
                  "%.4e s vs blow-up 2/w %.4e s: ratio %.4f; RK4 %.4e vs 2 sqrt(2)/w %.4e: ratio %.4f; forward Euler "
                  "growth %.4f and RK2 growth %.4f per step at their dt_crit\n",
                  cells[0], cells[1], cells[2], dofs, w_max, w_measured, dt_crit[1], blowup_se, ratio_se, dt_crit[3],
                  blowup_rk4, ratio_rk4, 1.0 + z_fe * z_fe, 1.0 + pow(z_rk2, 4) / 4.0);
    assert_true(ratio_se >= 0.5 && ratio_se <= 1.0);
    assert_true(ratio_rk4 >= 0.5 && ratio_rk4 <= 1.0);
    assert_close(dt_crit[SH_INTEGRATOR_FORWARD_EULER], dt_crit[SH_INTEGRATOR_SYMPLECTIC_EULER], 1e-12);
    assert_close(dt_crit[SH_INTEGRATOR_RK2], dt_crit[SH_INTEGRATOR_SYMPLECTIC_EULER], 1e-12);
}

static void test_critical_step(void** state) {
    (void)state;
    const clock_t start = clock();
    const int cells[2][3] = {{5, 1, 1}, {8, 2, 2}};
    for (int b = 0; b < 2; ++b) {
        sh_mesh* bar = sh_test_box(0.1, 0.02, 0.02, cells[b][0], cells[b][1], cells[b][2]);
        mesh_data m = sh_test_mesh_arrays_of(bar);
        const int n = m.node_count, dofs = 3 * n;
        sh_world* world = sh_test_world(0.0);
        const sh_body_id probe = add_bar_body(world, bar, SH_INTEGRATOR_SYMPLECTIC_EULER, SH_MATERIAL_LINEAR);
        double* mass = malloc(sizeof(double) * (size_t)n);
        assert_ok(sh_body_get_masses(world, probe, mass, n));
        double* k = stiffness_by_differences(world, probe, &m);
        double* u = malloc(sizeof(double) * (size_t)dofs);
        const double w_max = highest_mode(k, mass, dofs, u);

        double dt_crit[4];
        const double w_measured = check_one_step_on_the_mode(bar, &m, u, w_max, dt_crit);
        assert_close(w_measured / w_max, 1.0, 1e-6);
        check_critical_ratios(cells[b], dofs, w_max, w_measured, dt_crit);
        check_long_runs_at_critical_step(bar, &m, u, mass, w_max);

        free(u);
        free(k);
        free(mass);
        assert_ok(sh_world_destroy(world));
        sh_test_mesh_arrays_free(&m);
        assert_ok(sh_mesh_destroy(bar));
    }
    print_message("critical step: %.2f s\n", seconds_since(start));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stiff_cube_energy_never_grows),
        cmocka_unit_test(test_near_incompressible),
        cmocka_unit_test(test_large_deformation),
        cmocka_unit_test(test_large_deformation_static),
        cmocka_unit_test(test_inversion_recovery),
        cmocka_unit_test(test_inversion_warned),
        cmocka_unit_test(test_implicit_newton_near_rest),
        cmocka_unit_test(test_mass_ratio),
        cmocka_unit_test(test_critical_step),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
