/*
 * softhap_bench accuracy: error against run time. One JSON line per run on
 * stdout, progress on stderr; scripts/report.py turns the lines into report/accuracy.md and plots.
 *
 *   softhap_bench accuracy [--quick] [--jobs N] [FILTER]
 *
 * FILTER keeps the jobs whose name contains it: dynamic/ny<N>/<material>, static/eb/ny<N>,
 * static/nonlinear, oscillator.
 *
 * Studies ("study" field of each line):
 *  - "dynamic": a cantilever bar L x a x a (0.1 x 0.01 x 0.01 m, Kuhn-split cubes, nx = 10 ny),
 *    clamped at x = 0, released from rest under gravity -z. For each mesh resolution, material
 *    model and method, a sweep of time steps to t = 0.5 s. Explicit methods run under
 *    SH_UNSTABLE_REJECT (never sub-stepped) at dt = dt_crit * 2^(-k/2), k = 0..K, with dt_crit
 *    the body's own (RK4's is sqrt(2) larger); a rolled-back step ends the run, which is written
 *    with "status":"unstable". Implicit Euler runs at dt = 0.5 s / (10 * 2^j), with one Newton
 *    iteration (linearised, Baraff-Witkin) and with Newton to 1e-8, down to a step count set per
 *    resolution by its cost (kResolutions). Reference ("dynamic_reference"):
 *    the same mesh and material with RK4 at a step 16x smaller than the smallest explicit step of
 *    the sweep; it serves every row, implicit ones included. error = max over nodes of
 *    |x - x_ref| at t = 0.5 s / max over nodes of |x_ref - X| (the reference's tip displacement).
 *    Every body has the same Rayleigh damping, alpha = 0.5 1/s (damping_mass) and
 *    beta = 5e-5 s (damping_stiffness): mass damping alone cannot stop forward Euler and RK2 from
 *    growing the highest mesh modes (forward Euler needs dt < alpha / omega_max^2 with it, but
 *    dt < beta with stiffness damping), and beta barely touches the bending modes (damping ratio
 *    beta omega / 2 < 0.1 %). Cost: "wall_s" = CLOCK_MONOTONIC and "cpu_s" =
 *    CLOCK_PROCESS_CPUTIME_ID around the step loop (explicit steps with report NULL; implicit steps
 *    with a report, for the Newton counts). The library is single-threaded (run with
 *    OMP_NUM_THREADS=1 for CHOLMOD), so cpu_s is the wall time the run takes on an idle core, also
 *    when other processes share the machine.
 *  - "static_eb": the bar, gravity off, linear elasticity, a tip load F spread over the tip-face
 *    nodes as consistent nodal loads of a uniform traction, sized so that Euler-Bernoulli gives
 *    w = F L^3 / (3 E I) = L / 100 (I = a^4 / 12); one static solve per mesh (ny = 1..8) and
 *    Poisson ratio. w_fem = load-weighted mean z displacement of the tip face (work conjugate).
 *  - "static_nonlinear": StVK, corotational and neo-Hookean against linear on the ny = 3 bar as
 *    the tip load grows (linear deflection 0.5 % .. 50 % of L), Newton continuation from the
 *    previous load.
 *  - "oscillator": a spring body, node 0 fixed, node 1 of mass 1 kg on a linear spring
 *    k = 25 N/m (omega = 5 rad/s), released from 0.1 m stretch, no damping, no gravity; error at
 *    t = 1 s = |(x - x_exact, (v - v_exact) / omega)| / amplitude, for dt = 1/8 .. 1/8192 s.
 *
 * --jobs N (default 2) runs the independent jobs in N forked processes (one per core); each
 * run is still timed on its own, on one core. Public API only; C99 plus POSIX.
 */
#define _POSIX_C_SOURCE 200809L
#include "accuracy.h"
#include "box_mesh.h"

#include <softhap/softhap.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* ------------------------------------------------------------------------------------------ */
/* Parameters                                                                                   */

static const double kLength = 0.1;    /* bar length along x (m) */
static const double kSide = 0.01;     /* square cross-section side (m) */
static const double kYoung = 3.0e5;   /* Pa: soft tissue */
static const double kPoisson = 0.3;
static const double kDensity = 1000.0;     /* kg/m^3 */
static const double kGravity = 9.81;       /* m/s^2, along -z */
static const double kAlpha = 0.5;          /* Rayleigh mass damping (1/s) */
static const double kBeta = 5.0e-5;        /* Rayleigh stiffness damping (s) */
static const double kEndTime = 0.5;        /* dynamic: compare at t = 0.5 s */
static const double kRunaway = 10.0;       /* m/s: a blow-up is caught early */
static const int kRefFactor = 16;          /* reference step = smallest swept / 16 */
static const double kNewtonTolerance = 1e-8;
static const int kNewtonMax = 50;
/* Static solves: relative residual. The default 1e-10 is below the round-off floor of the
 * internal forces for a load of this size (the residual stalls near 2e-10 and the solve returns
 * SH_ERR_NOT_CONVERGED), so 1e-8. */
static const double kStaticTolerance = 1e-8;

static const double kOscStiffness = 25.0;  /* N/m */
static const double kOscMass = 1.0;        /* kg */
static const double kOscRest = 1.0;        /* m */
static const double kOscAmplitude = 0.1;   /* m */
static const double kOscEndTime = 1.0;     /* s */

typedef struct {
    const char* name;
    sh_integrator integrator;
    int newton; /* implicit: Newton iteration cap (1 = linearised step) */
} method_t;

static const method_t kMethods[] = {{"forward_euler", SH_INTEGRATOR_FORWARD_EULER, 0},
                                    {"symplectic_euler", SH_INTEGRATOR_SYMPLECTIC_EULER, 0},
                                    {"rk2", SH_INTEGRATOR_RK2, 0},
                                    {"rk4", SH_INTEGRATOR_RK4, 0},
                                    {"implicit_euler_n1", SH_INTEGRATOR_IMPLICIT_EULER, 1},
                                    {"implicit_euler_newton", SH_INTEGRATOR_IMPLICIT_EULER, kNewtonMax}};
enum { kMethodCount = sizeof kMethods / sizeof kMethods[0], kRk4 = 3 };

typedef struct {
    const char* name;
    sh_material_model model;
} material_t;

static const material_t kMaterials[] = {{"linear", SH_MATERIAL_LINEAR},
                                        {"stvk", SH_MATERIAL_STVK},
                                        {"corotational", SH_MATERIAL_COROTATIONAL},
                                        {"neohookean", SH_MATERIAL_NEOHOOKEAN}};
enum { kMaterialCount = sizeof kMaterials / sizeof kMaterials[0] };

/* Dynamic mesh resolutions: ny cells across, explicit levels K (dt down to dt_crit 2^(-K/2)),
 * largest implicit step counts with one Newton iteration and with Newton to convergence (their
 * cost: a tangent assembly with per-element PSD projection and a factorisation per iteration). */
typedef struct {
    int ny, levels, implicit_max_steps, newton_max_steps;
} resolution_t;

static const resolution_t kResolutions[] = {{1, 6, 2560, 640}, {2, 4, 640, 160}};
static const resolution_t kQuickResolutions[] = {{1, 2, 160, 80}};

static const int kStaticNy[] = {1, 2, 3, 4, 6, 8};
static const int kQuickStaticNy[] = {1, 2};
static const double kStaticPoisson[] = {0.0, 0.3, 0.45};
static const double kNonlinearDeflections[] = {0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5};
static const int kNonlinearNy = 3;

static int g_quick = 0;

/* ------------------------------------------------------------------------------------------ */
/* Helpers                                                                                      */

#define CHECK(expr)                                                                                 \
    do {                                                                                            \
        sh_status s_ = (expr);                                                                      \
        if (s_ != SH_OK) {                                                                          \
            fprintf(stderr, "softhap_bench accuracy: %s failed: %s (%s)\n", #expr,                  \
                    sh_status_string(s_), sh_last_error_message());                                 \
            exit(1);                                                                                \
        }                                                                                           \
    } while (0)

static double now_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* CPU time of this process (s): what the run cost when other processes share the cores. */
static double cpu_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void* xcalloc(size_t count, size_t size) {
    void* p = calloc(count ? count : 1, size);
    if (!p) {
        fprintf(stderr, "softhap_bench accuracy: out of memory\n");
        exit(1);
    }
    return p;
}

/* A JSON number, or null when not finite. */
static void jnum(FILE* out, const char* key, double value) {
    if (isfinite(value))
        fprintf(out, ",\"%s\":%.9g", key, value);
    else
        fprintf(out, ",\"%s\":null", key);
}

static const char* status_name(sh_status s) {
    switch (s) {
        case SH_OK: return "ok";
        case SH_ERR_UNSTABLE: return "unstable";
        case SH_ERR_NOT_CONVERGED: return "not_converged";
        case SH_ERR_SOLVER: return "solver_failed";
        default: return "error";
    }
}

/* ------------------------------------------------------------------------------------------ */
/* The bar                                                                                      */

typedef struct {
    int nx, ny, nz;
    int32_t node_count, tet_count;
    sh_mesh* mesh;
    double* rest;         /* node_count x 3 */
    int32_t* fixed;       /* nodes at x = 0 */
    int fixed_count;
    double* tip_weight;   /* node_count: share of a uniform tip traction (sums to 1) */
} bar_t;

/* [0,L] x [0,a] x [0,a] in nx*ny*ny cubes of 6 tets (box_mesh.h). */
static void bar_build(bar_t* b, int ny) {
    memset(b, 0, sizeof *b);
    b->ny = b->nz = ny;
    b->nx = (int)lround(kLength / kSide) * ny;
    int32_t* tets = NULL;
    sh_test_box_arrays(kLength, kSide, kSide, b->nx, ny, ny, &b->rest, &b->node_count, &tets, &b->tet_count);
    if (!b->rest || !tets) {
        fprintf(stderr, "softhap_bench: out of memory\n");
        exit(1);
    }
    CHECK(sh_mesh_create(b->rest, b->node_count, tets, b->tet_count, &b->mesh));
    free(tets);

    b->fixed = (int32_t*)xcalloc((size_t)b->node_count, sizeof(int32_t));
    for (int i = 0; i < b->node_count; ++i)
        if (b->rest[3 * i] < 1e-12) b->fixed[b->fixed_count++] = i;

    /* Consistent loads of a uniform traction on the x = L face: area / 3 per triangle node. */
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(b->mesh, &info));
    int32_t* tris = (int32_t*)xcalloc(3 * (size_t)info.surface_triangle_count, sizeof(int32_t));
    CHECK(sh_mesh_get_surface_triangles(b->mesh, tris, info.surface_triangle_count));
    b->tip_weight = (double*)xcalloc((size_t)b->node_count, sizeof(double));
    const double tip = kLength - 1e-12;
    double area_sum = 0.0;
    for (int f = 0; f < info.surface_triangle_count; ++f) {
        const int32_t* tri = &tris[3 * f];
        const double* p0 = &b->rest[3 * tri[0]];
        const double* p1 = &b->rest[3 * tri[1]];
        const double* p2 = &b->rest[3 * tri[2]];
        if (p0[0] < tip || p1[0] < tip || p2[0] < tip) continue;
        const double area = 0.5 * fabs((p1[1] - p0[1]) * (p2[2] - p0[2]) - (p1[2] - p0[2]) * (p2[1] - p0[1]));
        area_sum += area;
        for (int a = 0; a < 3; ++a) b->tip_weight[tri[a]] += area / 3.0;
    }
    for (int i = 0; i < b->node_count; ++i) b->tip_weight[i] /= area_sum;
    free(tris);
}

static void bar_free(bar_t* b) {
    sh_mesh_destroy(b->mesh);
    free(b->rest);
    free(b->fixed);
    free(b->tip_weight);
}

/* Load-weighted mean displacement of the tip face along axis k (m). */
static double tip_displacement(const bar_t* b, const double* x, int k) {
    double w = 0.0;
    for (int i = 0; i < b->node_count; ++i) w += b->tip_weight[i] * (x[3 * i + k] - b->rest[3 * i + k]);
    return w;
}

static sh_world* make_world(double gravity_z) {
    sh_world_def wd;
    sh_world_def_default(&wd);
    wd.gravity[0] = wd.gravity[1] = 0.0;
    wd.gravity[2] = gravity_z;
    sh_world* world = NULL;
    CHECK(sh_world_create(&wd, &world));
    return world;
}

/* The bar as an FEM body with its x = 0 face fixed. damped: the dynamic study's Rayleigh
 * damping; method NULL: static use. */
static sh_body_id add_bar(sh_world* world, const bar_t* b, sh_material_model model, double poisson,
                          const method_t* method, int damped) {
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = b->mesh;
    def.material.model = model;
    def.material.young = kYoung;
    def.material.poisson = poisson;
    def.material.density = kDensity;
    def.on_unstable = SH_UNSTABLE_REJECT;
    def.runaway_speed = kRunaway;
    if (damped) {
        def.damping_mass = kAlpha;
        def.damping_stiffness = kBeta;
    }
    if (method) {
        def.integrator = method->integrator;
        def.implicit.newton_max_iterations = method->newton > 0 ? method->newton : 1;
        def.implicit.newton_tolerance = kNewtonTolerance;
    }
    sh_body_id body = SH_NULL_ID;
    CHECK(sh_fem_body_create(world, &def, &body));
    CHECK(sh_body_fix_nodes(world, body, b->fixed, b->fixed_count));
    return body;
}

/* ------------------------------------------------------------------------------------------ */
/* Dynamic: the cantilever under gravity                                                        */

typedef struct {
    const method_t* method;
    int steps;
    double dt, dt_critical;
    sh_status status;
    int failed_step;     /* 1-based step that failed, 0 if none */
    double wall_s, cpu_s;
    double newton_mean;  /* implicit: mean Newton iterations per step */
    int newton_max;
    uint64_t substep_warnings, inverted_warnings;
    double* x;           /* final positions (node_count x 3) */
} run_t;

static double body_dt_critical(const bar_t* b, sh_material_model model, const method_t* method) {
    sh_world* world = make_world(-kGravity);
    const sh_body_id body = add_bar(world, b, model, kPoisson, method, 1);
    sh_body_info info;
    CHECK(sh_body_get_info(world, body, &info));
    CHECK(sh_world_destroy(world));
    return info.dt_critical;
}

static void run_dynamic(const bar_t* b, sh_material_model model, const method_t* method, int steps, run_t* r) {
    memset(r, 0, sizeof *r);
    r->method = method;
    r->steps = steps;
    r->dt = kEndTime / steps;
    sh_world* world = make_world(-kGravity);
    const sh_body_id body = add_bar(world, b, model, kPoisson, method, 1);
    sh_body_info info;
    CHECK(sh_body_get_info(world, body, &info));
    r->dt_critical = info.dt_critical;
    const int implicit = method->integrator == SH_INTEGRATOR_IMPLICIT_EULER;
    sh_step_report report;
    long newton_sum = 0;
    r->status = SH_OK;
    const double c0 = cpu_s();
    const double t0 = now_s();
    for (int s = 0; s < steps; ++s) {
        const sh_status st = sh_world_step(world, r->dt, implicit ? &report : NULL);
        if (implicit) {
            newton_sum += report.newton_iterations;
            if (report.newton_iterations > r->newton_max) r->newton_max = report.newton_iterations;
        }
        if (st != SH_OK) {
            r->status = st;
            r->failed_step = s + 1;
            break;
        }
    }
    r->wall_s = now_s() - t0;
    r->cpu_s = cpu_s() - c0;
    const int done = r->failed_step ? r->failed_step : steps;
    r->newton_mean = implicit && done > 0 ? (double)newton_sum / done : 0.0;
    uint64_t warnings[SH_WARN_COUNT];
    CHECK(sh_world_get_warnings(world, warnings));
    r->substep_warnings = warnings[SH_WARN_SUBSTEPPED];
    r->inverted_warnings = warnings[SH_WARN_INVERTED];
    r->x = (double*)xcalloc(3 * (size_t)b->node_count, sizeof(double));
    CHECK(sh_body_get_positions(world, body, r->x, b->node_count));
    CHECK(sh_world_destroy(world));
}

/* Steps to kEndTime with dt at most target (never above: dt_crit must not be exceeded). */
static int steps_for(double target) {
    int n = (int)ceil(kEndTime / (target * (1.0 - 1e-12)));
    return n < 1 ? 1 : n;
}

static void mesh_fields(FILE* out, const bar_t* b) {
    fprintf(out, ",\"mesh\":\"%dx%dx%d\",\"ny\":%d,\"nodes\":%d,\"tets\":%d", b->nx, b->ny, b->nz, b->ny,
            b->node_count, b->tet_count);
}

/* One method's sweep of time steps into runs[*run_count..] (see the header); the largest step
 * count of an explicit run into *finest_explicit. */
static void sweep_method(const bar_t* b, const resolution_t* res, const material_t* mat, const method_t* method,
                         run_t* runs, int* run_count, int* finest_explicit) {
    const double start = now_s();
    int stable = 0, count = 0;
    if (method->integrator != SH_INTEGRATOR_IMPLICIT_EULER) {
        const double dtc = body_dt_critical(b, mat->model, method);
        for (int k = 0; k <= res->levels; ++k) {
            const int n = steps_for(dtc * pow(2.0, -0.5 * k));
            run_dynamic(b, mat->model, method, n, &runs[*run_count]);
            stable += runs[*run_count].status == SH_OK;
            if (n > *finest_explicit) *finest_explicit = n;
            ++*run_count, ++count;
        }
    } else {
        const int max_steps = method->newton > 1 ? res->newton_max_steps : res->implicit_max_steps;
        for (int n = 10; n <= max_steps; n *= 2) {
            run_dynamic(b, mat->model, method, n, &runs[*run_count]);
            stable += runs[*run_count].status == SH_OK;
            ++*run_count, ++count;
        }
    }
    fprintf(stderr, "accuracy: dynamic ny=%d %-12s %-22s %d runs (%d ok) in %.1f s\n", res->ny, mat->name,
            method->name, count, stable, now_s() - start);
}

/* The reference's line; returns its largest node displacement from rest, the error's scale. */
static double print_dynamic_reference(FILE* out, const bar_t* b, const material_t* mat, const run_t* ref) {
    double deflection = 0.0;
    for (int i = 0; i < b->node_count; ++i) {
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) d2 += (ref->x[3 * i + k] - b->rest[3 * i + k]) * (ref->x[3 * i + k] - b->rest[3 * i + k]);
        if (d2 > deflection * deflection) deflection = sqrt(d2);
    }
    fprintf(out, "{\"study\":\"dynamic_reference\"");
    mesh_fields(out, b);
    fprintf(out, ",\"material\":\"%s\",\"method\":\"rk4\",\"steps\":%d", mat->name, ref->steps);
    jnum(out, "dt", ref->dt);
    jnum(out, "dt_critical", ref->dt_critical);
    jnum(out, "wall_s", ref->wall_s);
    jnum(out, "cpu_s", ref->cpu_s);
    jnum(out, "max_displacement", deflection);
    jnum(out, "tip_z", tip_displacement(b, ref->x, 2));
    jnum(out, "tip_x", tip_displacement(b, ref->x, 0));
    fprintf(out, ",\"inverted_warnings\":%llu}\n", (unsigned long long)ref->inverted_warnings);
    return deflection;
}

/* One run's line: its error against the reference, relative to the reference's deflection. */
static void print_dynamic_run(FILE* out, const bar_t* b, const material_t* mat, const run_t* run, const run_t* ref,
                              double deflection) {
    double error = NAN;
    if (run->status == SH_OK) {
        double worst = 0.0;
        for (int i = 0; i < b->node_count; ++i) {
            double d2 = 0.0;
            for (int k = 0; k < 3; ++k) d2 += (run->x[3 * i + k] - ref->x[3 * i + k]) * (run->x[3 * i + k] - ref->x[3 * i + k]);
            if (d2 > worst) worst = d2;
        }
        error = sqrt(worst) / deflection;
    }
    fprintf(out, "{\"study\":\"dynamic\"");
    mesh_fields(out, b);
    fprintf(out, ",\"material\":\"%s\",\"method\":\"%s\",\"steps\":%d", mat->name, run->method->name, run->steps);
    jnum(out, "dt", run->dt);
    jnum(out, "dt_critical", run->dt_critical);
    jnum(out, "dt_over_critical", run->dt / run->dt_critical);
    fprintf(out, ",\"status\":\"%s\",\"failed_step\":%d", status_name(run->status), run->failed_step);
    jnum(out, "wall_s", run->wall_s);
    jnum(out, "cpu_s", run->cpu_s);
    jnum(out, "error", error);
    if (run->method->integrator == SH_INTEGRATOR_IMPLICIT_EULER) {
        jnum(out, "newton_mean", run->newton_mean);
        fprintf(out, ",\"newton_max\":%d", run->newton_max);
    }
    fprintf(out, ",\"substep_warnings\":%llu,\"inverted_warnings\":%llu", (unsigned long long)run->substep_warnings,
            (unsigned long long)run->inverted_warnings);
    fprintf(out, ",\"reference\":\"rk4\"");
    jnum(out, "reference_dt", ref->dt);
    fprintf(out, "}\n");
}

/* One resolution and material: every method's sweep, the reference, then the lines. */
static void job_dynamic(FILE* out, const resolution_t* res, const material_t* mat) {
    bar_t b;
    bar_build(&b, res->ny);
    run_t* runs = (run_t*)xcalloc(64, sizeof(run_t));
    int run_count = 0, finest_explicit = 0;
    for (int m = 0; m < kMethodCount; ++m) sweep_method(&b, res, mat, &kMethods[m], runs, &run_count, &finest_explicit);

    /* Reference: RK4 at a step 16x smaller than the smallest explicit step swept. */
    const double start = now_s();
    run_t ref;
    run_dynamic(&b, mat->model, &kMethods[kRk4], kRefFactor * finest_explicit, &ref);
    fprintf(stderr, "accuracy: dynamic ny=%d %-12s reference rk4 %d steps in %.1f s\n", res->ny, mat->name, ref.steps,
            now_s() - start);
    if (ref.status != SH_OK) {
        fprintf(stderr, "softhap_bench accuracy: the reference run failed (%s)\n", status_name(ref.status));
        exit(1);
    }
    const double deflection = print_dynamic_reference(out, &b, mat, &ref);
    for (int r = 0; r < run_count; ++r) {
        print_dynamic_run(out, &b, mat, &runs[r], &ref, deflection);
        free(runs[r].x);
    }
    free(ref.x);
    free(runs);
    bar_free(&b);
}

/* ------------------------------------------------------------------------------------------ */
/* Static: Euler-Bernoulli and the nonlinear materials against linear                           */

/* Sets the tip load F (N, along -z) as consistent nodal forces. */
static void set_tip_load(sh_world* world, sh_body_id body, const bar_t* b, double force) {
    double* f = (double*)xcalloc(3 * (size_t)b->node_count, sizeof(double));
    for (int i = 0; i < b->node_count; ++i) f[3 * i + 2] = -force * b->tip_weight[i];
    CHECK(sh_body_set_external_forces(world, body, f, b->node_count));
    free(f);
}

static double second_moment(void) { return kSide * kSide * kSide * kSide / 12.0; }

static void job_static_eb(FILE* out, int ny) {
    bar_t b;
    bar_build(&b, ny);
    const double inertia = second_moment();
    const double w_eb = 0.01 * kLength;
    const double force = w_eb * 3.0 * kYoung * inertia / (kLength * kLength * kLength);
    double* x = (double*)xcalloc(3 * (size_t)b.node_count, sizeof(double));
    for (size_t p = 0; p < sizeof kStaticPoisson / sizeof kStaticPoisson[0]; ++p) {
        const double nu = kStaticPoisson[p];
        sh_world* world = make_world(0.0);
        const sh_body_id body = add_bar(world, &b, SH_MATERIAL_LINEAR, nu, NULL, 0);
        set_tip_load(world, body, &b, force);
        sh_static_def sd;
        sh_static_def_default(&sd);
        sd.tolerance = kStaticTolerance;
        sh_static_report rep;
        const double c0 = cpu_s();
        const double t0 = now_s();
        const sh_status st = sh_world_solve_static(world, &sd, &rep);
        const double wall = now_s() - t0;
        const double cpu = cpu_s() - c0;
        CHECK(sh_body_get_positions(world, body, x, b.node_count));
        const double w = -tip_displacement(&b, x, 2);
        /* Timoshenko: add the shear deflection F L / (kappa G A), Cowper's kappa for a square. */
        const double shear = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
        const double w_timoshenko = w_eb + force * kLength / (shear * kYoung / (2.0 * (1.0 + nu)) * kSide * kSide);
        fprintf(out, "{\"study\":\"static_eb\"");
        mesh_fields(out, &b);
        jnum(out, "poisson", nu);
        jnum(out, "h", kSide / ny);
        jnum(out, "load_N", force);
        fprintf(out, ",\"status\":\"%s\",\"iterations\":%d", status_name(st), rep.iterations);
        jnum(out, "wall_s", wall);
        jnum(out, "cpu_s", cpu);
        jnum(out, "solver_wall_s", rep.wall_seconds);
        jnum(out, "w_fem", w);
        jnum(out, "w_eb", w_eb);
        jnum(out, "w_timoshenko", w_timoshenko);
        jnum(out, "rel_error", (w - w_eb) / w_eb);
        fprintf(out, "}\n");
        CHECK(sh_world_destroy(world));
    }
    fprintf(stderr, "accuracy: static Euler-Bernoulli ny=%d (%d tets) done\n", ny, b.tet_count);
    free(x);
    bar_free(&b);
}

static void job_static_nonlinear(FILE* out, int ny) {
    bar_t b;
    bar_build(&b, ny);
    double* x = (double*)xcalloc(3 * (size_t)b.node_count, sizeof(double));
    const int loads = (int)(sizeof kNonlinearDeflections / sizeof kNonlinearDeflections[0]);

    /* Linear compliance at a unit load (the linear answer scales exactly). */
    double compliance;
    {
        sh_world* world = make_world(0.0);
        const sh_body_id body = add_bar(world, &b, SH_MATERIAL_LINEAR, kPoisson, NULL, 0);
        set_tip_load(world, body, &b, 1.0);
        sh_static_def sd;
        sh_static_def_default(&sd);
        sd.tolerance = kStaticTolerance;
        CHECK(sh_world_solve_static(world, &sd, NULL));
        CHECK(sh_body_get_positions(world, body, x, b.node_count));
        compliance = -tip_displacement(&b, x, 2);
        CHECK(sh_world_destroy(world));
    }
    for (int m = 0; m < kMaterialCount; ++m) {
        const material_t* mat = &kMaterials[m];
        sh_world* world = make_world(0.0);
        const sh_body_id body = add_bar(world, &b, mat->model, kPoisson, NULL, 0);
        const double start = now_s();
        for (int l = 0; l < loads; ++l) {
            const double w_linear = kNonlinearDeflections[l] * kLength;
            const double force = w_linear / compliance;
            set_tip_load(world, body, &b, force);
            sh_static_def sd;
            sh_static_def_default(&sd);
            sd.tolerance = kStaticTolerance;
            sd.load_steps = 2; /* continuation from the previous load's equilibrium */
            sd.max_iterations = 60;
            sh_static_report rep;
            const double c0 = cpu_s();
            const double t0 = now_s();
            sh_status st = sh_world_solve_static(world, &sd, &rep);
            int iterations = rep.iterations, load_steps = sd.load_steps;
            if (st != SH_OK) { /* state unchanged: retry in smaller increments */
                sd.load_steps = 6;
                st = sh_world_solve_static(world, &sd, &rep);
                iterations += rep.iterations;
                load_steps = sd.load_steps;
            }
            const double wall = now_s() - t0;
            const double cpu = cpu_s() - c0;
            CHECK(sh_body_get_positions(world, body, x, b.node_count));
            const double w = -tip_displacement(&b, x, 2);
            fprintf(out, "{\"study\":\"static_nonlinear\"");
            mesh_fields(out, &b);
            fprintf(out, ",\"material\":\"%s\"", mat->name);
            jnum(out, "poisson", kPoisson);
            jnum(out, "load_N", force);
            jnum(out, "w_linear", w_linear);
            jnum(out, "w_linear_over_L", kNonlinearDeflections[l]);
            fprintf(out, ",\"status\":\"%s\",\"iterations\":%d,\"load_steps\":%d", status_name(st), iterations, load_steps);
            jnum(out, "wall_s", wall);
            jnum(out, "cpu_s", cpu);
            jnum(out, "w", st == SH_OK ? w : NAN);
            jnum(out, "tip_x", st == SH_OK ? tip_displacement(&b, x, 0) : NAN);
            jnum(out, "rel_diff", st == SH_OK ? (w - w_linear) / w_linear : NAN);
            fprintf(out, "}\n");
        }
        fprintf(stderr, "accuracy: static %s against linear (ny=%d) in %.1f s\n", mat->name, ny, now_s() - start);
        CHECK(sh_world_destroy(world));
    }
    free(x);
    bar_free(&b);
}

/* ------------------------------------------------------------------------------------------ */
/* The 1-DOF oscillator                                                                         */

static void job_oscillator(FILE* out) {
    const double omega = sqrt(kOscStiffness / kOscMass);
    const double exact_x = kOscAmplitude * cos(omega * kOscEndTime);
    const double exact_v = -kOscAmplitude * omega * sin(omega * kOscEndTime);
    const int max_power = g_quick ? 10 : 13;
    for (int m = 0; m < kMethodCount; ++m) {
        const method_t* method = &kMethods[m];
        for (int p = 3; p <= max_power; ++p) {
            const int steps = 1 << p;
            const double dt = kOscEndTime / steps;
            sh_world* world = make_world(0.0);
            const double nodes[6] = {0.0, 0.0, 0.0, kOscRest, 0.0, 0.0};
            const int32_t springs[2] = {0, 1};
            const double masses[2] = {kOscMass, kOscMass};
            sh_spring_body_def def;
            sh_spring_body_def_default(&def);
            def.nodes = nodes;
            def.node_count = 2;
            def.springs = springs;
            def.spring_count = 1;
            def.params.law = SH_SPRING_LINEAR;
            def.params.stiffness = kOscStiffness;
            def.params.damping = 0.0;
            def.node_masses = masses;
            def.integrator = method->integrator;
            def.on_unstable = SH_UNSTABLE_REJECT;
            def.damping_mass = 0.0;
            def.implicit.newton_max_iterations = method->newton > 0 ? method->newton : 1;
            def.implicit.newton_tolerance = kNewtonTolerance;
            sh_body_id body = SH_NULL_ID;
            CHECK(sh_spring_body_create(world, &def, &body));
            const int32_t fixed = 0;
            CHECK(sh_body_fix_nodes(world, body, &fixed, 1));
            const double start[6] = {0.0, 0.0, 0.0, kOscRest + kOscAmplitude, 0.0, 0.0};
            CHECK(sh_body_set_positions(world, body, start, 2));
            sh_body_info info;
            CHECK(sh_body_get_info(world, body, &info));
            sh_status status = SH_OK;
            int failed = 0;
            const double c0 = cpu_s();
            const double t0 = now_s();
            for (int s = 0; s < steps && status == SH_OK; ++s) {
                status = sh_world_step(world, dt, NULL);
                if (status != SH_OK) failed = s + 1;
            }
            const double wall = now_s() - t0;
            const double cpu = cpu_s() - c0;
            double x[6], v[6];
            CHECK(sh_body_get_positions(world, body, x, 2));
            CHECK(sh_body_get_velocities(world, body, v, 2));
            const double dx = x[3] - kOscRest - exact_x, dv = (v[3] - exact_v) / omega;
            fprintf(out, "{\"study\":\"oscillator\",\"method\":\"%s\",\"steps\":%d", method->name, steps);
            jnum(out, "dt", dt);
            jnum(out, "dt_critical", info.dt_critical);
            jnum(out, "omega_dt", omega * dt);
            fprintf(out, ",\"status\":\"%s\",\"failed_step\":%d", status_name(status), failed);
            jnum(out, "wall_s", wall);
            jnum(out, "cpu_s", cpu);
            jnum(out, "error", status == SH_OK ? sqrt(dx * dx + dv * dv) / kOscAmplitude : NAN);
            fprintf(out, "}\n");
            CHECK(sh_world_destroy(world));
        }
    }
    fprintf(stderr, "accuracy: oscillator done\n");
}

/* ------------------------------------------------------------------------------------------ */
/* Jobs                                                                                         */

enum { kJobDynamic, kJobStaticEb, kJobStaticNonlinear, kJobOscillator };

typedef struct {
    int kind;
    const resolution_t* resolution;
    const material_t* material;
    int ny;
    double cost; /* rough estimate, to start the longest first */
} job_t;

static void job_name(const job_t* job, char* name, size_t size) {
    switch (job->kind) {
        case kJobDynamic: snprintf(name, size, "dynamic/ny%d/%s", job->ny, job->material->name); break;
        case kJobStaticEb: snprintf(name, size, "static/eb/ny%d", job->ny); break;
        case kJobStaticNonlinear: snprintf(name, size, "static/nonlinear"); break;
        default: snprintf(name, size, "oscillator"); break;
    }
}

static void run_job(const job_t* job, FILE* out) {
    switch (job->kind) {
        case kJobDynamic: job_dynamic(out, job->resolution, job->material); break;
        case kJobStaticEb: job_static_eb(out, job->ny); break;
        case kJobStaticNonlinear: job_static_nonlinear(out, job->ny); break;
        default: job_oscillator(out); break;
    }
    fflush(out);
}

/* Runs the jobs in `workers` forked processes fed from a pipe of job indices, longest first;
 * each job writes to its own temporary file, copied to stdout in job order at the end. */
static int run_jobs(const job_t* jobs, int count, int workers) {
    if (workers <= 1) {
        for (int j = 0; j < count; ++j) run_job(&jobs[j], stdout);
        return 0;
    }
    FILE** files = (FILE**)xcalloc((size_t)count, sizeof(FILE*));
    int* order = (int*)xcalloc((size_t)count, sizeof(int));
    for (int j = 0; j < count; ++j) {
        files[j] = tmpfile();
        if (!files[j]) {
            perror("softhap_bench accuracy: tmpfile");
            return 1;
        }
        order[j] = j;
    }
    for (int a = 1; a < count; ++a) /* insertion sort by decreasing cost */
        for (int b = a; b > 0 && jobs[order[b]].cost > jobs[order[b - 1]].cost; --b) {
            const int t = order[b];
            order[b] = order[b - 1];
            order[b - 1] = t;
        }
    int queue[2];
    if (pipe(queue) != 0) {
        perror("softhap_bench accuracy: pipe");
        return 1;
    }
    if (write(queue[1], order, sizeof(int) * (size_t)count) != (ssize_t)(sizeof(int) * (size_t)count)) {
        perror("softhap_bench accuracy: write");
        return 1;
    }
    fflush(stdout);
    fflush(stderr);
    pid_t* pids = (pid_t*)xcalloc((size_t)workers, sizeof(pid_t));
    for (int w = 0; w < workers; ++w) {
        pids[w] = fork();
        if (pids[w] < 0) {
            perror("softhap_bench accuracy: fork");
            return 1;
        }
        if (pids[w] == 0) {
            close(queue[1]);
            int j;
            while (read(queue[0], &j, sizeof j) == (ssize_t)sizeof j) run_job(&jobs[j], files[j]);
            _exit(0);
        }
    }
    close(queue[1]);
    close(queue[0]);
    int failed = 0;
    for (int w = 0; w < workers; ++w) {
        int status = 0;
        if (waitpid(pids[w], &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) failed = 1;
    }
    for (int j = 0; j < count; ++j) {
        rewind(files[j]);
        char buffer[4096];
        size_t n;
        while ((n = fread(buffer, 1, sizeof buffer, files[j])) > 0) fwrite(buffer, 1, n, stdout);
        fclose(files[j]);
    }
    fflush(stdout);
    free(pids);
    free(order);
    free(files);
    return failed;
}

static double load_average(void) {
    double load = NAN;
    FILE* f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &load) != 1) load = NAN;
        fclose(f);
    }
    return load;
}

static void usage(void) {
    fprintf(stderr,
            "usage: softhap_bench accuracy [--quick] [--jobs N] [FILTER]\n"
            "  FILTER keeps the jobs whose name contains it: dynamic/ny<N>/<material>,\n"
            "  static/eb/ny<N>, static/nonlinear, oscillator\n"
            "  JSON lines on stdout (see bench/accuracy.c), progress on stderr; then\n"
            "  scripts/report.py FILE.jsonl report/ writes report/accuracy.md and plots\n");
}

/* The jobs of the run (the quick set with --quick) that the filter keeps, longest first in
 * run_jobs; returns their count. */
static int build_jobs(job_t jobs[64], const char* filter) {
    int count = 0;
    const resolution_t* resolutions = g_quick ? kQuickResolutions : kResolutions;
    const int resolution_count = g_quick ? (int)(sizeof kQuickResolutions / sizeof kQuickResolutions[0])
                                         : (int)(sizeof kResolutions / sizeof kResolutions[0]);
    static const double kMaterialCost[kMaterialCount] = {1.0, 1.5, 3.5, 1.5};
    for (int r = 0; r < resolution_count; ++r)
        for (int m = 0; m < kMaterialCount; ++m) {
            job_t j = {kJobDynamic, &resolutions[r], &kMaterials[m], resolutions[r].ny,
                       kMaterialCost[m] * pow(8.0, resolutions[r].ny)};
            jobs[count++] = j;
        }
    {
        const int* nys = g_quick ? kQuickStaticNy : kStaticNy;
        const int ny_count = g_quick ? (int)(sizeof kQuickStaticNy / sizeof kQuickStaticNy[0])
                                     : (int)(sizeof kStaticNy / sizeof kStaticNy[0]);
        for (int k = 0; k < ny_count; ++k) {
            job_t j = {kJobStaticEb, NULL, NULL, nys[k], 0.01 * nys[k] * nys[k] * nys[k]};
            jobs[count++] = j;
        }
        job_t j = {kJobStaticNonlinear, NULL, NULL, g_quick ? 2 : kNonlinearNy, 10.0};
        jobs[count++] = j;
    }
    {
        job_t j = {kJobOscillator, NULL, NULL, 0, 1.0};
        jobs[count++] = j;
    }
    if (filter) { /* keep the matching jobs */
        int kept = 0;
        for (int j = 0; j < count; ++j) {
            char name[128];
            job_name(&jobs[j], name, sizeof name);
            if (strstr(name, filter)) jobs[kept++] = jobs[j];
        }
        count = kept;
    }
    return count;
}

/* The run's first line: the version, the parameters every study shares and the load. */
static void print_meta(int workers, double load_before) {
    printf("{\"study\":\"meta\",\"version\":%d,\"quick\":%d,\"jobs\":%d", (int)sh_version(), g_quick, workers);
    jnum(stdout, "length_m", kLength);
    jnum(stdout, "side_m", kSide);
    jnum(stdout, "young_Pa", kYoung);
    jnum(stdout, "poisson", kPoisson);
    jnum(stdout, "density", kDensity);
    jnum(stdout, "gravity", kGravity);
    jnum(stdout, "damping_mass", kAlpha);
    jnum(stdout, "damping_stiffness", kBeta);
    jnum(stdout, "end_time", kEndTime);
    fprintf(stdout, ",\"reference_factor\":%d", kRefFactor);
    jnum(stdout, "newton_tolerance", kNewtonTolerance);
    jnum(stdout, "osc_omega", sqrt(kOscStiffness / kOscMass));
    jnum(stdout, "osc_end_time", kOscEndTime);
    jnum(stdout, "loadavg_before", load_before);
    fprintf(stdout, ",\"cholmod\":%d}\n", (sh_build_features() & SH_FEATURE_CHOLMOD) ? 1 : 0);
}

int run_accuracy(int argc, char** argv) {
    int workers = 2;
    const char* filter = NULL;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--quick") == 0) {
            g_quick = 1;
        } else if (strcmp(argv[i], "--jobs") == 0 && i + 1 < argc) {
            workers = atoi(argv[++i]);
            if (workers < 1) workers = 1;
        } else if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage();
            return 0;
        } else if (!filter && argv[i][0] != '-') {
            filter = argv[i];
        } else {
            usage();
            return 2;
        }
    }
    if (sh_version() != SH_VERSION) {
        fprintf(stderr, "softhap_bench accuracy: library version %d, header %d\n", (int)sh_version(), SH_VERSION);
        return 1;
    }

    job_t jobs[64];
    const int count = build_jobs(jobs, filter);
    const double load_before = load_average();
    const double start = now_s();
    print_meta(workers, load_before);
    const int failed = run_jobs(jobs, count, workers);
    const double total = now_s() - start;
    printf("{\"study\":\"meta_end\"");
    jnum(stdout, "total_wall_s", total);
    jnum(stdout, "loadavg_after", load_average());
    printf("}\n");
    fflush(stdout);
    fprintf(stderr, "accuracy: %s in %.1f s\n", failed ? "FAILED" : "done", total);
    return failed;
}
