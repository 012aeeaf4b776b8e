/*
 * softhap_bench: per-step timings of the explicit full-model step, one JSON line per case.
 *
 *   softhap_bench [FILTER] [--steps N] [--meshes DIR]      FEM materials and springs
 *   softhap_bench integrators [FILTER] [--steps N]          forward/symplectic Euler, RK2, RK4
 *   softhap_bench implicit [FILTER] [--steps N] [--trace]   implicit Euler step, direct vs CG;
 *                                                           and on a 20 k-tet cube (stand, droop);
 *                                                           --trace: each step's line on stderr
 *   softhap_bench contact [FILTER] [--steps N]              collision and contact time per step
 *   softhap_bench accuracy [--quick] [--jobs N]             error against run time (accuracy.c)
 *   softhap_bench haptic [FILTER] [--steps N]               haptic step cost vs buffer size (haptic.c)
 *   softhap_bench haptic-error [FILTER]                     haptic force error vs buffer radius
 *   softhap_bench haptic-force [--csv PATH]                 haptic force smoothness, VBM vs ZOH
 *   softhap_bench palpation [FILTER] [--meshes DIR]         a sphere pressed into the liver at 60 Hz
 *                                                           (implicit, per material; palpation.c)
 *   softhap_bench cut [FILTER] [--reps N] [--meshes DIR]    sh_body_cut time vs body size and cut
 *                                                           length, the implicit step after a cut (cut.c)
 *
 * Each case builds a world with one body from a mesh in ../shared/meshes (scaled so its largest
 * extent is kMeshSize), gravity on, the highest 1% of the nodes fixed, dt = kDtFraction * dt_crit
 * so the step never sub-steps (the JSON "substeps" field is the largest count seen, and the
 * SH_WARN_SUBSTEPPED counter is checked). After a warm-up every sh_world_step is timed on its own
 * with clock_gettime(CLOCK_MONOTONIC); the times are sorted for the median, p99 and p99.9.
 * A case is timed twice: with report NULL ("case": "<material>/<mesh>") and with a step report,
 * which adds the kinetic, potential and elastic energy passes ("<material>+report/<mesh>").
 * ns_per_tet_step = median step time / tets (also for springs, whose "springs" field gives the
 * spring count). FILTER keeps the cases whose name contains it.
 *
 * Public API only; C99 (plus POSIX clocks and, on Linux, pinning to the current CPU).
 */
#define _GNU_SOURCE /* M_PI */
#include <softhap/softhap.h>

#include "accuracy.h"
#include "box_mesh.h"
#include "bench_util.h"
#include "cut.h"
#include "haptic.h"
#include "palpation.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef SOFTHAP_BENCH_MESH_DIR
#define SOFTHAP_BENCH_MESH_DIR "../shared/meshes"
#endif

static const double kMeshSize = 0.15;      /* largest extent after scaling (m): organ-sized */
static const double kYoung = 3.0e4;        /* Pa: soft tissue */
static const double kPoisson = 0.45;
static const double kDensity = 1000.0;     /* kg/m^3 */
static const double kDtFraction = 0.5;     /* dt = kDtFraction * dt_crit: no sub-stepping */
static const double kFixedFraction = 0.01; /* the highest 1% of the nodes are fixed */
static const double kCaseSeconds = 1.0;    /* timed budget of a case without report */
static const double kReportSeconds = 0.5;  /* timed budget of a case with report */
static const int kMinSteps = 500, kMaxSteps = 2000, kWarmupSteps = 30;

static const char* const kMeshes[] = {"Armadillo_Tetra_4406", "raptorTetra_8418", "raptorTetra_19409"};
static const char* g_mesh_dir = NULL;
static int g_steps = 0; /* --steps N; 0 = adaptive */
static double g_factor_reuse = -1.0; /* implicit: --factor-reuse X; < 0 = the default */
static int g_trace = 0; /* implicit: --trace, one JSON line per timed step on stderr */

/* ------------------------------------------------------------------------------------------ */
/* Scenes                                                                                       */

typedef struct {
    const char* name;
    sh_mesh* mesh;       /* scaled copy */
    sh_mesh_info info;
    double* rest;        /* node_count x 3 */
    int32_t* fixed;      /* highest nodes */
    int32_t fixed_count;
    int32_t edge_count;
    double mean_edge;    /* m */
} bench_mesh;

/* Heights of nodes for the sort below (qsort has no context argument in C99). */
static const double* g_sort_nodes;
static int cmp_node_height(const void* a, const void* b) {
    const double za = g_sort_nodes[3 * *(const int32_t*)a + 2], zb = g_sort_nodes[3 * *(const int32_t*)b + 2];
    return za > zb ? -1 : za < zb;
}

/* Loads g_mesh_dir/file as m, named name. */
static int load_mesh_file(const char* file, const char* name, bench_mesh* m) {
    double* nodes = NULL;
    if (!bench_load_scaled_mesh(g_mesh_dir, file, NULL, kMeshSize, &m->mesh, &nodes)) return 0;
    CHECK(sh_mesh_get_info(m->mesh, &m->info));
    const int32_t n = m->info.node_count;
    m->name = name;
    m->rest = nodes;

    /* The highest kFixedFraction of the nodes (at least 4); orphans are skipped by the body. */
    int32_t* order = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)n);
    for (int32_t i = 0; i < n; ++i) order[i] = i;
    g_sort_nodes = nodes;
    qsort(order, (size_t)n, sizeof(int32_t), cmp_node_height);
    m->fixed_count = (int32_t)(kFixedFraction * n);
    if (m->fixed_count < 4) m->fixed_count = 4;
    m->fixed = order;

    m->edge_count = m->info.edge_count;
    int32_t* edges = (int32_t*)xmalloc(sizeof(int32_t) * 2 * (size_t)m->edge_count);
    CHECK(sh_mesh_get_edges(m->mesh, edges, m->edge_count));
    double sum = 0.0;
    for (int32_t e = 0; e < m->edge_count; ++e) sum += distance3(&nodes[3 * edges[2 * e]], &nodes[3 * edges[2 * e + 1]]);
    m->mean_edge = sum / m->edge_count;
    free(edges);
    return 1;
}

/* Loads g_mesh_dir/<name>.vtu. */
static int load_mesh(const char* name, bench_mesh* m) {
    char file[1024];
    snprintf(file, sizeof file, "%s.vtu", name);
    return load_mesh_file(file, name, m);
}

static void free_mesh(bench_mesh* m) {
    sh_mesh_destroy(m->mesh);
    free(m->rest);
    free(m->fixed);
}

/* A body kind: an FEM material (model >= 0) or springs on the mesh edges (model < 0). */
typedef struct {
    const char* name;
    int model;
} body_kind;

static const body_kind kKinds[] = {{"linear", SH_MATERIAL_LINEAR},
                                   {"stvk", SH_MATERIAL_STVK},
                                   {"corotational", SH_MATERIAL_COROTATIONAL},
                                   {"neohookean", SH_MATERIAL_NEOHOOKEAN},
                                   {"springs", -1}};

static sh_body_id add_body(sh_world* world, const bench_mesh* m, int model, sh_integrator integrator,
                           const sh_implicit_settings* implicit) {
    sh_body_id body = SH_NULL_ID;
    if (model >= 0) {
        sh_fem_body_def def = bench_fem_body_def(m->mesh, (sh_material_model)model, kYoung, kPoisson, kDensity);
        def.integrator = integrator;
        if (implicit) def.implicit = *implicit;
        CHECK(sh_fem_body_create(world, &def, &body));
    } else {
        /* A rod of section l^2 and length l has axial stiffness E l; nodes share the mass. */
        sh_spring_body_def def;
        sh_spring_body_def_default(&def);
        def.mesh = m->mesh;
        def.params.law = SH_SPRING_LINEAR;
        def.params.stiffness = kYoung * m->mean_edge;
        def.node_mass = kDensity * m->info.volume / (m->info.node_count - m->info.orphan_node_count);
        def.integrator = integrator;
        if (implicit) def.implicit = *implicit;
        CHECK(sh_spring_body_create(world, &def, &body));
    }
    CHECK(sh_body_fix_nodes(world, body, m->fixed, m->fixed_count));
    return body;
}

/* ------------------------------------------------------------------------------------------ */
/* Timing                                                                                       */

typedef struct {
    int steps;
    double min_ns, median_ns, p99_ns, p999_ns, mean_ns;
    int substeps;     /* largest seen in reports */
    int failed;       /* steps that did not return SH_OK */
    sh_step_report last;
} timing;

/* Steps to time so that the case takes about budget seconds at per_step_ns. */
static int step_count(double budget, double per_step_ns) {
    if (g_steps > 0) return g_steps;
    double n = budget * 1e9 / (per_step_ns > 1.0 ? per_step_ns : 1.0);
    if (n < kMinSteps) n = kMinSteps;
    if (n > kMaxSteps) n = kMaxSteps;
    return (int)n;
}

/* Optional reset to rest every reset_every steps (outside the timed region); 0 = never. */
typedef struct {
    sh_body_id body;
    const bench_mesh* mesh;
    double* zeros;
    int reset_every;
} reset_plan;

static void reset_body(sh_world* world, const reset_plan* r) {
    CHECK(sh_body_set_positions(world, r->body, r->mesh->rest, r->mesh->info.node_count));
    CHECK(sh_body_set_velocities(world, r->body, r->zeros, r->mesh->info.node_count));
}

static timing time_steps(sh_world* world, double dt, int with_report, double budget, const reset_plan* reset) {
    timing t;
    memset(&t, 0, sizeof t);
    t.substeps = 0;
    sh_step_report report;
    double warm = 0.0;
    for (int s = 0; s < kWarmupSteps; ++s) {
        const double t0 = now_ns();
        const sh_status st = sh_world_step(world, dt, &report); /* warm-up always reports */
        warm = now_ns() - t0;
        if (st != SH_OK) ++t.failed;
        if (report.substeps > t.substeps) t.substeps = report.substeps;
    }
    t.steps = step_count(budget, warm);
    double* ns = (double*)xmalloc(sizeof(double) * (size_t)t.steps);
    for (int s = 0; s < t.steps; ++s) {
        if (reset && reset->reset_every > 0 && s % reset->reset_every == 0) reset_body(world, reset);
        const double t0 = now_ns();
        const sh_status st = sh_world_step(world, dt, with_report ? &report : NULL);
        ns[s] = now_ns() - t0;
        if (st != SH_OK) ++t.failed;
        if (with_report && report.substeps > t.substeps) t.substeps = report.substeps;
    }
    const stats st = summarize(ns, t.steps); /* sorts ns */
    t.mean_ns = st.mean;
    t.min_ns = ns[0];
    t.median_ns = st.median;
    t.p99_ns = st.p99;
    t.p999_ns = st.p999;
    free(ns);
    CHECK(sh_world_step(world, dt, &report));
    t.last = report;
    if (report.substeps > t.substeps) t.substeps = report.substeps;
    return t;
}

static void print_case(const char* name, const bench_mesh* m, int springs, double dt, const timing* t,
                       uint64_t substep_warnings, int with_report) {
    printf("{\"case\":\"%s\",\"tets\":%d,", name, m->info.tet_count);
    if (springs) printf("\"springs\":%d,", m->edge_count);
    printf("\"ns_per_tet_step\":%.2f,\"median_us\":%.2f,\"p99_us\":%.2f,\"p999_us\":%.2f,\"mean_us\":%.2f,\"min_us\":%.2f,"
           "\"steps\":%d,\"substeps\":%d,\"substep_warnings\":%llu,\"failed_steps\":%d,\"dt\":%.4g,\"dt_crit\":%.4g",
           t->median_ns / m->info.tet_count, t->median_ns * 1e-3, t->p99_ns * 1e-3, t->p999_ns * 1e-3,
           t->mean_ns * 1e-3, t->min_ns * 1e-3, t->steps, t->substeps, (unsigned long long)substep_warnings, t->failed, dt,
           t->last.dt_critical);
    if (with_report)
        printf(",\"kinetic_J\":%.6g,\"elastic_J\":%.6g,\"potential_J\":%.6g", t->last.kinetic_energy,
               t->last.elastic_energy, t->last.potential_energy);
    printf("}\n");
    fflush(stdout);
}

static double body_dt_crit(sh_world* world, sh_body_id body) {
    sh_body_info info;
    CHECK(sh_body_get_info(world, body, &info));
    return info.dt_critical;
}

/* One kind on one mesh: the timing without report, then with report, each in a fresh world. */
static void run_case(const bench_mesh* m, const body_kind* kind, const char* filter) {
    char name[2][256];
    snprintf(name[0], sizeof name[0], "%s/%s", kind->name, m->name);
    snprintf(name[1], sizeof name[1], "%s+report/%s", kind->name, m->name);
    for (int with_report = 0; with_report < 2; ++with_report) {
        if (!name_matches(name[with_report], filter)) continue;
        sh_world* world = bench_world_create(1);
        const sh_body_id body = add_body(world, m, kind->model, SH_INTEGRATOR_SYMPLECTIC_EULER, NULL);
        const double dt = kDtFraction * body_dt_crit(world, body);
        const timing t = time_steps(world, dt, with_report, with_report ? kReportSeconds : kCaseSeconds, NULL);
        uint64_t warnings[SH_WARN_COUNT];
        CHECK(sh_world_get_warnings(world, warnings));
        print_case(name[with_report], m, kind->model < 0, dt, &t, warnings[SH_WARN_SUBSTEPPED], with_report);
        CHECK(sh_world_destroy(world));
    }
}

/* The explicit integrators on one mesh (StVK): dt = dt_crit / 10 (forward Euler and RK2 gain
 * energy at every dt), reset to rest every 200 steps outside the timed region. */
static void run_integrators(const char* filter) {
    static const struct {
        const char* name;
        sh_integrator integrator;
    } kIntegrators[] = {{"forward_euler", SH_INTEGRATOR_FORWARD_EULER},
                        {"symplectic_euler", SH_INTEGRATOR_SYMPLECTIC_EULER},
                        {"rk2", SH_INTEGRATOR_RK2},
                        {"rk4", SH_INTEGRATOR_RK4}};
    bench_mesh m;
    if (!load_mesh("raptorTetra_8418", &m)) exit(1);
    double* zeros = (double*)calloc(3 * (size_t)m.info.node_count, sizeof(double));
    for (size_t k = 0; k < sizeof kIntegrators / sizeof kIntegrators[0]; ++k) {
        char name[256];
        snprintf(name, sizeof name, "integrator/%s/stvk/%s", kIntegrators[k].name, m.name);
        if (!name_matches(name, filter)) continue;
        sh_world* world = bench_world_create(1);
        const sh_body_id body = add_body(world, &m, SH_MATERIAL_STVK, kIntegrators[k].integrator, NULL);
        const double dt = 0.1 * body_dt_crit(world, body);
        const reset_plan reset = {body, &m, zeros, 200};
        const timing t = time_steps(world, dt, 0, kCaseSeconds, &reset);
        uint64_t warnings[SH_WARN_COUNT];
        CHECK(sh_world_get_warnings(world, warnings));
        print_case(name, &m, 0, dt, &t, warnings[SH_WARN_SUBSTEPPED], 0);
        CHECK(sh_world_destroy(world));
    }
    free(zeros);
    free_mesh(&m);
}

/* The implicit Euler step on raptorTetra_19409 (gravity, highest 1% of the nodes fixed), dt =
 * kImplicitDt, one linearised solve per step (the default), per scenario, material and linear
 * solver. Scenarios: "swing": the body falls from rest and swings, so its stiffness changes a lot
 * from step to step; "ramp": gravity rises smoothly from 0 over kRampTime, so the body sags
 * slowly (a quasi-static load, as in palpation or positioning). Per step: wall time, and from the step report the
 * factorisation and solve times (assembly and the rest = wall - both) and the factorisations. */
static const double kImplicitDt = 0.01;  /* s: a 100 Hz organ step */
static const double kRampTime = 1.0;     /* s */

/* The ramp scenario's gravity at time t: 0 to -9.81 m/s^2 along z, smoothly over kRampTime. */
static void set_ramp_gravity(sh_world* world, double t) {
    const double fraction = t < kRampTime ? 0.5 * (1.0 - cos(M_PI * t / kRampTime)) : 1.0;
    const double g[3] = {0.0, 0.0, -9.81 * fraction};
    CHECK(sh_world_set_gravity(world, g));
}

/* The implicit settings of the body def's defaults with the given linear solver (and
 * --factor-reuse, if given). */
static sh_implicit_settings implicit_settings(sh_linear_solver solver) {
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    sh_implicit_settings implicit = def.implicit;
    implicit.linear_solver = solver;
    if (g_factor_reuse >= 0.0) implicit.factor_reuse = g_factor_reuse;
    return implicit;
}

/* With --trace: step s's wall time (ns) and report as one JSON line on stderr. */
static void trace_step(const char* name, int s, double ns, const sh_step_report* report) {
    if (!g_trace) return;
    fprintf(stderr,
            "{\"case\":\"%s\",\"step\":%d,\"ms\":%.3f,\"factorizations\":%d,\"newton_iterations\":%d,"
            "\"linear_iterations\":%d,\"solve_ms\":%.3f}\n",
            name, s, ns * 1e-6, report->factorizations, report->newton_iterations, report->linear_iterations,
            report->solve_seconds * 1e3);
}

/* Per-step samples of one implicit case. */
typedef struct {
    double* wall; /* ns per step, after the first */
    double factorize, solve, first_step; /* s, s, ns */
    int factorizations, failed;
    long linear_iterations;
} implicit_run;

/* The first step (the solver's analysis, kept apart), then steps timed steps; ramp: gravity
 * follows set_ramp_gravity. */
static void step_implicit(sh_world* world, int ramp, int steps, const char* name, implicit_run* r) {
    sh_step_report report;
    for (int s = -1; s < steps; ++s) {
        if (ramp) set_ramp_gravity(world, (s + 1) * kImplicitDt);
        const double t0 = now_ns();
        const sh_status st = sh_world_step(world, kImplicitDt, &report);
        const double ns = now_ns() - t0;
        if (st != SH_OK) {
            if (!r->failed) fprintf(stderr, "softhap_bench: %s step %d: %s\n", name, s, sh_last_error_message());
            ++r->failed;
        }
        if (s < 0) {
            r->first_step = ns;
            continue;
        }
        r->wall[s] = ns;
        trace_step(name, s, ns, &report);
        r->factorize += report.factorize_seconds;
        r->solve += report.solve_seconds;
        r->factorizations += report.factorize_seconds > 0.0;
        r->linear_iterations += report.linear_iterations;
    }
}

/* An implicit case's JSON line (sorts the step times). */
static void print_implicit(const char* name, const bench_mesh* m, int steps, implicit_run* r) {
    double sum = 0.0;
    for (int s = 0; s < steps; ++s) sum += r->wall[s];
    const stats t = summarize(r->wall, steps);
    printf("{\"case\":\"%s\",\"tets\":%d,\"dofs\":%d,\"dt\":%g,\"median_ms\":%.3f,\"p99_ms\":%.3f,"
           "\"p999_ms\":%.3f,\"max_ms\":%.3f,\"mean_ms\":%.3f,\"min_ms\":%.3f,\"factorize_ms_mean\":%.3f,"
           "\"solve_ms_mean\":%.3f,\"other_ms_mean\":%.3f,\"factorizations\":%d,\"linear_iterations_mean\":%.2f,"
           "\"first_step_ms\":%.1f,\"steps\":%d,\"failed_steps\":%d}\n",
           name, m->info.tet_count, 3 * (m->info.node_count - m->info.orphan_node_count - m->fixed_count), kImplicitDt,
           t.median * 1e-6, t.p99 * 1e-6, t.p999 * 1e-6, t.max * 1e-6, t.mean * 1e-6, r->wall[0] * 1e-6,
           r->factorize / steps * 1e3, r->solve / steps * 1e3, (sum * 1e-9 - r->factorize - r->solve) / steps * 1e3,
           r->factorizations, (double)r->linear_iterations / steps, r->first_step * 1e-6, steps, r->failed);
    fflush(stdout);
}

/* One scenario, body kind and linear solver in a fresh world. */
static void implicit_case(const bench_mesh* m, const char* scenario, const body_kind* kind, sh_linear_solver solver,
                          const char* name, int steps) {
    sh_world* world = bench_world_create(1);
    const sh_implicit_settings implicit = implicit_settings(solver);
    add_body(world, m, kind->model, SH_INTEGRATOR_IMPLICIT_EULER, &implicit);
    implicit_run r;
    memset(&r, 0, sizeof r);
    r.wall = (double*)xmalloc(sizeof(double) * (size_t)steps);
    step_implicit(world, strcmp(scenario, "ramp") == 0, steps, name, &r);
    print_implicit(name, m, steps, &r);
    free(r.wall);
    CHECK(sh_world_destroy(world));
}

/* Every wanted scenario, body kind and linear solver (CHOLMOD where built in). */
static void run_implicit(const char* filter) {
    static const struct {
        const char* name;
        sh_linear_solver solver;
    } kSolvers[] = {{"cholmod", SH_LINEAR_SOLVER_CHOLMOD}, {"ldlt", SH_LINEAR_SOLVER_LDLT}, {"cg", SH_LINEAR_SOLVER_CG}};
    static const char* const kScenarios[] = {"swing", "ramp"};
    const int steps = g_steps > 0 ? g_steps : 100;
    bench_mesh m;
    if (!load_mesh("raptorTetra_19409", &m)) exit(1);
    for (size_t c = 0; c < sizeof kScenarios / sizeof kScenarios[0]; ++c)
        for (size_t j = 0; j < sizeof kKinds / sizeof kKinds[0]; ++j)
            for (size_t k = 0; k < sizeof kSolvers / sizeof kSolvers[0]; ++k) {
                char name[256];
                snprintf(name, sizeof name, "implicit/%s/%s/%s/%s", kScenarios[c], kKinds[j].name, kSolvers[k].name,
                         m.name);
                if (!name_matches(name, filter)) continue;
                if (kSolvers[k].solver == SH_LINEAR_SOLVER_CHOLMOD && !(sh_build_features() & SH_FEATURE_CHOLMOD))
                    continue;
                implicit_case(&m, kScenarios[c], &kKinds[j], kSolvers[k].solver, name, steps);
            }
    free_mesh(&m);
}

/* The implicit step on the cube: 0.1 m, 15 x 15 x 15 Kuhn-split cells (20,250 tets),
 * 1 kg (1000 kg/m^3), E 1e4 Pa, nu 0.45, default implicit settings (CHOLMOD), gravity -z.
 * "stand": its bottom face fixed (it sags under its weight); "droop": its x = 0 face fixed (it
 * bends over, a large rotation). dt 1/240 s and 1/60 s. pybullet's implicit deformable solver
 * ran the same scenes for the issue (274-531 ms per step). */
static const double kCubeSize = 0.1;  /* m */
enum { kCubeCells = 15 };

/* The cube's mesh and the nodes fixed in scene (their count in *fixed_count). */
static sh_mesh* cube_mesh(const char* scene, int32_t** fixed, int32_t* fixed_count) {
    double* nodes = NULL;
    int32_t *tets = NULL, node_count = 0, tet_count = 0;
    sh_test_box_arrays(kCubeSize, kCubeSize, kCubeSize, kCubeCells, kCubeCells, kCubeCells, &nodes, &node_count, &tets,
                       &tet_count);
    if (!nodes || !tets) {
        fprintf(stderr, "softhap_bench: out of memory\n");
        exit(1);
    }
    sh_mesh* mesh = NULL;
    CHECK(sh_mesh_create(nodes, node_count, tets, tet_count, &mesh));
    const int axis = strcmp(scene, "stand") == 0 ? 2 : 0;
    *fixed = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)node_count);
    *fixed_count = 0;
    for (int32_t i = 0; i < node_count; ++i)
        if (nodes[3 * i + axis] < 1e-9) (*fixed)[(*fixed_count)++] = i;
    free(nodes);
    free(tets);
    return mesh;
}

/* One cube case: steps timed steps of dt after a first (the solver's analysis, kept apart). */
static void cube_case(const char* scene, const body_kind* kind, double dt, const char* name, int steps) {
    int32_t* fixed = NULL;
    int32_t fixed_count = 0;
    sh_mesh* mesh = cube_mesh(scene, &fixed, &fixed_count);
    sh_world* world = bench_world_create(1);
    sh_fem_body_def def = bench_fem_body_def(mesh, (sh_material_model)kind->model, 1e4, 0.45, 1000.0);
    def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    def.implicit = implicit_settings(SH_LINEAR_SOLVER_CHOLMOD);
    sh_body_id body;
    CHECK(sh_fem_body_create(world, &def, &body));
    CHECK(sh_body_fix_nodes(world, body, fixed, fixed_count));
    double* wall = (double*)xmalloc(sizeof(double) * (size_t)steps);
    sh_step_report report;
    int failed = 0;
    long factorizations = 0, newton = 0, linear = 0;
    double factorize = 0.0, solve = 0.0;
    for (int s = -1; s < steps; ++s) {
        const double t0 = now_ns();
        failed += sh_world_step(world, dt, &report) != SH_OK;
        if (s < 0) continue;
        wall[s] = now_ns() - t0;
        trace_step(name, s, wall[s], &report);
        factorizations += report.factorizations;
        newton += report.newton_iterations;
        linear += report.linear_iterations;
        factorize += report.factorize_seconds;
        solve += report.solve_seconds;
    }
    const stats t = summarize(wall, steps);
    printf("{\"case\":\"%s\",\"tets\":%d,\"dt\":%g,\"median_ms\":%.3f,\"p99_ms\":%.3f,\"max_ms\":%.3f,"
           "\"mean_ms\":%.3f,\"factorize_ms_mean\":%.3f,\"solve_ms_mean\":%.3f,\"factorizations_per_step\":%.2f,"
           "\"newton_per_step\":%.2f,\"linear_iterations_per_step\":%.2f,\"steps\":%d,\"failed_steps\":%d}\n",
           name, 6 * kCubeCells * kCubeCells * kCubeCells, dt, t.median * 1e-6, t.p99 * 1e-6, t.max * 1e-6,
           t.mean * 1e-6, factorize / steps * 1e3, solve / steps * 1e3, (double)factorizations / steps,
           (double)newton / steps, (double)linear / steps, steps, failed);
    fflush(stdout);
    free(wall);
    free(fixed);
    CHECK(sh_world_destroy(world));
    CHECK(sh_mesh_destroy(mesh));
}

/* Every wanted cube scene, step and material (CHOLMOD only: the comparison). */
static void run_cube(const char* filter) {
    static const char* const kScenes[] = {"stand", "droop"};
    static const struct {
        const char* name;
        double dt;
    } kSteps[] = {{"240hz", 1.0 / 240.0}, {"60hz", 1.0 / 60.0}};
    const int steps = g_steps > 0 ? g_steps : 30;
    if (!(sh_build_features() & SH_FEATURE_CHOLMOD)) return;
    for (size_t c = 0; c < 2; ++c)
        for (size_t d = 0; d < 2; ++d)
            for (size_t j = 0; j < sizeof kKinds / sizeof kKinds[0]; ++j) {
                if (kKinds[j].model < 0) continue;  /* springs: not in the comparison */
                char name[256];
                snprintf(name, sizeof name, "implicit/cube-%s/%s/%s/cholmod/cube_20250", kScenes[c], kSteps[d].name,
                         kKinds[j].name);
                if (name_matches(name, filter)) cube_case(kScenes[c], &kKinds[j], kSteps[d].dt, name, steps);
            }
}

/* Collision detection and contact forces per step against mesh size. Each mesh (scaled so its
 * largest extent is kMeshSize, lowest point at z = 0) is a free StVK body (no fixed nodes) on a
 * plane obstacle through z = kContactTablePress (so the nodes of its lowest kContactTablePress
 * start in contact), with a sphere tool of radius kContactToolRadius pressed kContactToolPress
 * into its highest surface node; both with friction (table mu 0.5 / 0.4, tool 0.3 / 0.2).
 * Symplectic Euler at dt = kDtFraction * dt_crit (the material's critical step; "substeps" says
 * whether the contacts made it sub-step). The tool is posed at the same place every step. After
 * kWarmupSteps (the first one builds the surface trees), each step is timed on its own with a
 * step report: wall time around sh_world_step (the report adds its energy passes), and from the
 * report collision_seconds (detection, contact forces in every sub-step, reactions) and
 * contact_count. The run covers well under a millisecond of simulated time: the body as a whole
 * barely moves, but the pressed surface nodes are light and their contacts undamped, so they
 * bounce in and out of contact (contact_count_min and _max show how much). The same body in a
 * world without tool and obstacle, stepped the same way, gives "no_contact_median_us". */
static const double kContactTablePress = 5e-4;  /* m */
static const double kContactToolRadius = 0.01;  /* m */
static const double kContactToolPress = 2e-3;   /* m */
/* Hunt-Crossley stiffness of both (N/m^1.5), without damping: the surface nodes of the finer
 * meshes weigh micrograms, and a contact's damping (its dashpot at the anticipated depth) would
 * cut the stable explicit step to a small fraction of dt, so the step would sub-step and the
 * time would measure the sub-steps rather than the contact. */
static const double kContactStiffness = 1e4;

/* Per-step samples of one contact run. */
typedef struct {
    double* wall;      /* ns, sorted */
    double* collision; /* ns, sorted */
    double* contacts;  /* sorted */
    int substeps, contact_substeps, failed;
    double dt;
} contact_run;

/* The table under m's body and the tool pressed into its highest surface node (see above); the
 * tool's id, and its centre in position. */
static sh_tool_id add_table_and_tool(sh_world* world, const bench_mesh* m, double position[3]) {
    sh_collider_def table;
    sh_collider_def_default(&table);
    table.shape.kind = SH_SHAPE_PLANE; /* normal +z */
    table.position[2] = kContactTablePress;
    table.contact.stiffness = kContactStiffness;
    table.contact.damping = 0.0;
    table.contact.static_friction = 0.5;
    table.contact.dynamic_friction = 0.4;
    sh_obstacle_id obstacle;
    CHECK(sh_obstacle_create(world, &table, &obstacle));

    int32_t tri_count;
    int32_t* tris = bench_surface_triangles(m->mesh, &tri_count);
    int32_t top = tris[0];
    for (int32_t i = 1; i < 3 * tri_count; ++i)
        if (m->rest[3 * tris[i] + 2] > m->rest[3 * top + 2]) top = tris[i];
    free(tris);
    for (int c = 0; c < 3; ++c) position[c] = m->rest[3 * top + c];
    position[2] += kContactToolRadius - kContactToolPress;
    sh_collider_def tool_def = bench_sphere_def(kContactToolRadius, position);
    tool_def.contact.stiffness = kContactStiffness;
    tool_def.contact.damping = 0.0;
    tool_def.contact.static_friction = 0.3;
    tool_def.contact.dynamic_friction = 0.2;
    sh_tool_id tool = SH_NULL_ID;
    CHECK(sh_tool_create(world, &tool_def, &tool));
    return tool;
}

/* Steps m's body (with the table and the tool if colliders) and fills r. */
static void run_contact_world(const bench_mesh* m, int colliders, int steps, const char* name, contact_run* r) {
    sh_world* world = bench_world_create(1);
    sh_fem_body_def def = bench_fem_body_def(m->mesh, SH_MATERIAL_STVK, kYoung, kPoisson, kDensity);
    def.integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
    def.on_unstable = SH_UNSTABLE_SUBSTEP;
    sh_body_id body;
    CHECK(sh_fem_body_create(world, &def, &body));
    r->dt = kDtFraction * body_dt_crit(world, body);
    double tool_position[3];
    sh_tool_id tool = SH_NULL_ID;
    if (colliders) tool = add_table_and_tool(world, m, tool_position);
    const double orientation[4] = {1.0, 0.0, 0.0, 0.0};

    r->wall = (double*)xmalloc(sizeof(double) * (size_t)steps);
    r->collision = (double*)xmalloc(sizeof(double) * (size_t)steps);
    r->contacts = (double*)xmalloc(sizeof(double) * (size_t)steps);
    r->failed = 0;
    r->substeps = r->contact_substeps = 1;
    sh_step_report report;
    for (int s = -kWarmupSteps; s < steps; ++s) {
        if (colliders) CHECK(sh_tool_set_pose(world, tool, tool_position, orientation));
        const double t0 = now_ns();
        const sh_status st = sh_world_step(world, r->dt, &report);
        const double ns = now_ns() - t0;
        if (st != SH_OK) {
            if (!r->failed) fprintf(stderr, "softhap_bench: %s step %d: %s\n", name, s, sh_last_error_message());
            ++r->failed;
        }
        if (s < 0) continue;
        r->wall[s] = ns;
        r->collision[s] = report.collision_seconds * 1e9;
        r->contacts[s] = report.contact_count;
        if (report.substeps > r->substeps) r->substeps = report.substeps;
        if (report.contact_substeps > r->contact_substeps) r->contact_substeps = report.contact_substeps;
    }
    qsort(r->wall, (size_t)steps, sizeof(double), cmp_double);
    qsort(r->collision, (size_t)steps, sizeof(double), cmp_double);
    qsort(r->contacts, (size_t)steps, sizeof(double), cmp_double);
    CHECK(sh_world_destroy(world));
}

static void free_contact_run(contact_run* r) {
    free(r->wall);
    free(r->collision);
    free(r->contacts);
}

static void run_contact(const char* filter) {
    static const struct {
        const char* name;
        const char* file;
    } kContactMeshes[] = {{"liver", "liver.msh"},
                          {"liver2", "liver2.msh"},
                          {"Armadillo_Tetra_4406", "Armadillo_Tetra_4406.vtu"},
                          {"raptorTetra_8418", "raptorTetra_8418.vtu"},
                          {"raptorTetra_19409", "raptorTetra_19409.vtu"}};
    const int steps = g_steps > 0 ? g_steps : 200;
    for (size_t k = 0; k < sizeof kContactMeshes / sizeof kContactMeshes[0]; ++k) {
        char name[256];
        snprintf(name, sizeof name, "contact/%s", kContactMeshes[k].name);
        if (!name_matches(name, filter)) continue;
        bench_mesh m;
        if (!load_mesh_file(kContactMeshes[k].file, kContactMeshes[k].name, &m)) continue; /* message printed */
        contact_run base, r;
        run_contact_world(&m, 0, steps, name, &base);
        run_contact_world(&m, 1, steps, name, &r);
        const double wall_median = median(r.wall, steps), collision_median = median(r.collision, steps);
        printf("{\"case\":\"%s\",\"mesh\":\"%s\",\"tets\":%d,\"surface_triangles\":%d,\"nodes\":%d,"
               "\"contact_count\":%g,\"contact_count_min\":%g,\"contact_count_max\":%g,"
               "\"collision_median_us\":%.2f,\"collision_p99_us\":%.2f,\"collision_p999_us\":%.2f,"
               "\"median_us\":%.2f,\"p99_us\":%.2f,\"p999_us\":%.2f,\"no_contact_median_us\":%.2f,"
               "\"collision_share\":%.3f,\"collision_ns_per_surface_triangle\":%.2f,\"substeps\":%d,"
               "\"contact_substeps\":%d,\"steps\":%d,\"failed_steps\":%d,\"dt\":%.4g,\"dt_crit\":%.4g}\n",
               name, m.name, m.info.tet_count, m.info.surface_triangle_count, m.info.node_count,
               median(r.contacts, steps), r.contacts[0], r.contacts[steps - 1], collision_median * 1e-3,
               quantile(r.collision, steps, 0.99) * 1e-3, quantile(r.collision, steps, 0.999) * 1e-3,
               wall_median * 1e-3, quantile(r.wall, steps, 0.99) * 1e-3, quantile(r.wall, steps, 0.999) * 1e-3,
               median(base.wall, steps) * 1e-3, collision_median / wall_median,
               collision_median / m.info.surface_triangle_count, r.substeps, r.contact_substeps, steps,
               r.failed + base.failed, r.dt, r.dt / kDtFraction);
        fflush(stdout);
        free_contact_run(&base);
        free_contact_run(&r);
        free_mesh(&m);
    }
}

static void usage(void) {
    fprintf(stderr,
            "usage: softhap_bench [integrators|implicit|contact] [FILTER] [--steps N] [--meshes DIR]\n"
            "       softhap_bench accuracy|haptic|haptic-error|haptic-force|palpation|cut ... (see their --help)\n"
            "  FILTER  keep the cases whose name contains it (e.g. stvk/raptorTetra_19409)\n"
            "  --steps N  timed steps per case (default: adaptive, %d..%d; implicit 100, contact 200)\n"
            "  --trace  implicit: each timed step's time, factorisations and iterations on stderr\n"
            "  --meshes DIR  mesh folder (default $SOFTHAP_MESHES, " SOFTHAP_BENCH_MESH_DIR
            ", ../shared/meshes)\n",
            kMinSteps, kMaxSteps);
}

int main(int argc, char** argv) {
    if (argc > 1 && strcmp(argv[1], "accuracy") == 0) return run_accuracy(argc - 1, argv + 1);
    if (argc > 1 && is_haptic_command(argv[1])) return run_haptic(argc - 1, argv + 1);
    if (argc > 1 && strcmp(argv[1], "palpation") == 0) return run_palpation(argc - 1, argv + 1);
    if (argc > 1 && strcmp(argv[1], "cut") == 0) return run_cut(argc - 1, argv + 1);
    const char* filter = NULL;
    int integrators = 0, implicit = 0, contact = 0;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--steps") == 0 && i + 1 < argc) {
            g_steps = atoi(argv[++i]);
            if (g_steps < 1) {
                usage();
                return 2;
            }
        } else if (strcmp(argv[i], "--trace") == 0) {
            g_trace = 1;
        } else if (strcmp(argv[i], "--factor-reuse") == 0 && i + 1 < argc) {
            g_factor_reuse = atof(argv[++i]);
        } else if (strcmp(argv[i], "--meshes") == 0 && i + 1 < argc) {
            g_mesh_dir = argv[++i];
        } else if (strcmp(argv[i], "integrators") == 0 && !integrators && !implicit && !contact) {
            integrators = 1;
        } else if (strcmp(argv[i], "implicit") == 0 && !integrators && !implicit && !contact) {
            implicit = 1;
        } else if (strcmp(argv[i], "contact") == 0 && !integrators && !implicit && !contact) {
            contact = 1;
        } else {
            const int code = bench_filter_arg(argv[i], &filter, usage);
            if (code >= 0) return code;
        }
    }
    {
        char probe[256];
        snprintf(probe, sizeof probe, "%s.vtu", kMeshes[0]);
        g_mesh_dir = bench_find_mesh_dir(g_mesh_dir, probe);
        if (!g_mesh_dir) return 1;
    }
    bench_pin_thread(bench_current_cpu()); /* one core: the one we started on */
    if (sh_version() != SH_VERSION) {
        fprintf(stderr, "softhap_bench: library version %d, header %d\n", (int)sh_version(), SH_VERSION);
        return 1;
    }
    if (integrators) {
        run_integrators(filter);
        return 0;
    }
    if (implicit) {
        run_implicit(filter);
        run_cube(filter);
        return 0;
    }
    if (contact) {
        run_contact(filter);
        return 0;
    }
    for (size_t k = 0; k < sizeof kMeshes / sizeof kMeshes[0]; ++k) {
        int wanted = 0;
        for (size_t j = 0; j < sizeof kKinds / sizeof kKinds[0]; ++j) {
            char name[256];
            snprintf(name, sizeof name, "%s/%s", kKinds[j].name, kMeshes[k]);
            char name_report[256];
            snprintf(name_report, sizeof name_report, "%s+report/%s", kKinds[j].name, kMeshes[k]);
            wanted |= name_matches(name, filter) || name_matches(name_report, filter);
        }
        if (!wanted) continue;
        bench_mesh m;
        if (!load_mesh(kMeshes[k], &m)) return 1;
        for (size_t j = 0; j < sizeof kKinds / sizeof kKinds[0]; ++j) run_case(&m, &kKinds[j], filter);
        free_mesh(&m);
    }
    return 0;
}
