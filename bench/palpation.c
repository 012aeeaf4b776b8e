/*
 * softhap_bench palpation: a sphere tool pressed into the liver held at its base, the full model
 * stepped at 60 Hz with implicit Euler (as a haptic host's sim thread steps it). One JSON line
 * per material on stdout, progress on stderr.
 *
 *   softhap_bench palpation [FILTER] [--radius M] [--settle] [--meshes DIR]
 *
 * FILTER keeps the cases whose name contains it: palpation/<material>/r<radius in mm>mm, with
 * material corotational, stvk or neohookean (--settle appends "+settle"). --radius M sets the
 * sphere's radius in metres (default 0.01; 0.003 for a 3 mm probe).
 *
 * Scene. SOFA's liver2.msh (507 nodes, 1493 tets) from the mesh folder (--meshes DIR, else
 * $SOFTHAP_MESHES, the build's default or ../shared/meshes: bench_find_mesh_dir), scaled by 0.1
 * (file units to metres: 21 x 12 x 13 cm), not turned; the nodes less than 1.5 cm above its
 * lowest point are fixed; gravity on (the world default, -9.81 m/s^2 along z). Tissue:
 * E = 3 kPa (very soft), nu = 0.45, rho = 1000 kg/m^3, no damping. Implicit Euler at
 * dt = 1/60 s with the default implicit settings (a line-searched update per step, Newton
 * iterations with contact candidates, retries in up to 16 sub-steps, then the best iterate with
 * SH_WARN_NOT_CONVERGED: the world always advances).
 *
 * Tool. A sphere (Hunt-Crossley contact: stiffness 1e3 N/m^1.5, exponent 1.5, the default
 * damping 0.2 s/m, no friction) right above the liver's highest node, its lowest point kGap
 * (1 mm) above it. One untimed step with the tool there (the implicit body's first step builds
 * its solver state, the world's first its surface trees: "first_step_ms"); then the tool is
 * posed 2 cm / 60 lower before each of 60 steps (the press: 2 cm in 1 s at constant speed) and
 * held for 30 more (the hold: 0.5 s).
 *
 * Gravity and 3 kPa. Released from its rest shape, this liver does not stand: held only by its
 * lowest 1.5 cm, it collapses under its own weight within about half a second, its top falling
 * about 11 cm (to about the height of the fixed nodes), far faster than the press. So by
 * default the tool never reaches it (force 0; "tool_above_top_end_press_m" > 0 is the sphere's
 * lowest point above the liver's highest node after the press) and the steps time the collapse
 * with a tool nearby. --settle first lets it fall to rest (kSettleSteps untimed steps of 1/60 s
 * with per-node damping kSettleDamping, then cleared) and puts the tool above the collapsed
 * liver's top ("top_fall_m": how far that lies below the rest shape's top).
 * sh_world_solve_static does not serve here: it does not converge for corotational.
 *
 * Per case, over the 90 press and hold steps (each sh_world_step timed on its own with
 * CLOCK_MONOTONIC, with a step report): step time median, p99 and max (ms); the report's Newton
 * iterations and sub-steps, median and max; steps that did not return SH_OK; the growth of the
 * world's SH_WARN_NOT_CONVERGED counter; the tool's force magnitude |F| (sh_tool_get_wrench)
 * after the last press step; and over the press (the untimed step before it included) the
 * largest drop of |F| from one step to the next (0 if it never falls).
 *
 * Public API only; C99 plus POSIX clocks.
 */
#define _POSIX_C_SOURCE 200809L
#include "palpation.h"

#include "bench_util.h"

#include <softhap/softhap.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* Parameters                                                                                   */

static const char* const kMeshFile = "liver2.msh";
static const char* const kMeshName = "liver2";
static const double kMeshScale = 0.1;      /* file units to metres */
static const double kFixedHeight = 0.015;  /* m: the nodes closer than this to the lowest are fixed */
static const double kYoung = 3.0e3;        /* Pa: 3 kPa, very soft tissue */
static const double kPoisson = 0.45;
static const double kDensity = 1000.0;     /* kg/m^3 */
static const double kDt = 1.0 / 60.0;      /* s: 60 Hz */
static const double kSettleDamping = 20.0; /* 1/s per node, while settling (--settle) */
static const int kSettleSteps = 120;       /* 2 s */
static const double kToolRadius = 0.01;    /* m: default; --radius */
static const double kToolStiffness = 1e3;  /* N/m^1.5 */
static const double kToolExponent = 1.5;
static const double kGap = 1e-3;           /* m: the sphere's lowest point above the top at start */
static const double kPressDepth = 0.02;    /* m */
enum { kPressSteps = 60, kHoldSteps = 30, kSteps = kPressSteps + kHoldSteps }; /* 1 s, 0.5 s */

typedef struct {
    const char* name;
    sh_material_model model;
} material_case;

static const material_case kMaterials[] = {{"corotational", SH_MATERIAL_COROTATIONAL},
                                           {"stvk", SH_MATERIAL_STVK},
                                           {"neohookean", SH_MATERIAL_NEOHOOKEAN}};

/* The command line. */
typedef struct {
    const char* filter; /* NULL: every case */
    double radius;      /* m */
    int settle;         /* --settle */
} palpation_options;

/* ------------------------------------------------------------------------------------------ */
/* Scene                                                                                        */

/* The liver in metres and the nodes its base holds. */
typedef struct {
    sh_mesh* mesh;
    int32_t node_count, tet_count;
    double rest_top;   /* height of its highest node (m) */
    int32_t* fixed;
    int32_t fixed_count;
} liver_mesh;

/* Loads dir/liver2.msh scaled by kMeshScale into *out and picks the nodes less than kFixedHeight
 * above its lowest point. 0 with a message on stderr if the file does not load. */
static int load_liver(const char* dir, liver_mesh* out) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, kMeshFile);
    sh_mesh* raw = NULL;
    if (sh_mesh_load(path, &raw) != SH_OK) {
        fprintf(stderr, "softhap_bench: cannot load %s: %s\n", path, sh_last_error_message());
        return 0;
    }
    CHECK(sh_mesh_transform(raw, kMeshScale, NULL, &out->mesh));
    CHECK(sh_mesh_destroy(raw));
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(out->mesh, &info));
    out->node_count = info.node_count;
    out->tet_count = info.tet_count;
    out->rest_top = info.bounds_max[2];
    double* nodes = (double*)xmalloc(sizeof(double) * 3 * (size_t)info.node_count);
    CHECK(sh_mesh_get_nodes(out->mesh, nodes, 3 * (int64_t)info.node_count));
    out->fixed = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)info.node_count);
    out->fixed_count = 0;
    for (int32_t i = 0; i < info.node_count; ++i)
        if (nodes[3 * i + 2] < info.bounds_min[2] + kFixedHeight) out->fixed[out->fixed_count++] = i;
    free(nodes);
    return 1;
}

static void free_liver(liver_mesh* m) {
    sh_mesh_destroy(m->mesh);
    free(m->fixed);
}

/* A world with gravity (the default) and the liver as one implicit-Euler body of the given
 * model, its base fixed; the body's id in *body. */
static sh_world* make_world(const liver_mesh* m, sh_material_model model, sh_body_id* body) {
    sh_world_def wd;
    sh_world_def_default(&wd);
    sh_world* world = NULL;
    CHECK(sh_world_create(&wd, &world));
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = m->mesh;
    def.material.model = model;
    def.material.young = kYoung;
    def.material.poisson = kPoisson;
    def.material.density = kDensity;
    def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    CHECK(sh_world_add_fem_body(world, &def, body));
    CHECK(sh_body_fix_nodes(world, *body, m->fixed, m->fixed_count));
    return world;
}

/* --settle: lets the liver fall to rest before the press, kSettleSteps untimed steps with
 * per-node damping kSettleDamping, which is then cleared. Reports on stderr. */
static void settle(sh_world* world, sh_body_id body, const liver_mesh* m, const char* name) {
    double* damping = (double*)xmalloc(sizeof(double) * (size_t)m->node_count);
    for (int32_t i = 0; i < m->node_count; ++i) damping[i] = kSettleDamping;
    CHECK(sh_body_set_node_damping(world, body, damping, m->node_count));
    free(damping);
    sh_step_report report;
    memset(&report, 0, sizeof report);
    int failed = 0;
    const double t0 = now_ns();
    for (int s = 0; s < kSettleSteps; ++s) failed += sh_world_step(world, kDt, &report) != SH_OK;
    CHECK(sh_body_set_node_damping(world, body, NULL, m->node_count));
    fprintf(stderr, "%s: settled for %g s (%.1f s of wall time): kinetic energy %.3g J, %d failed steps\n", name,
            kSettleSteps * kDt, (now_ns() - t0) * 1e-9, report.kinetic_energy, failed);
}

/* The highest node that carries mass (orphans have none) at the body's current positions into
 * out (m). */
static void top_point(const sh_world* world, sh_body_id body, const liver_mesh* m, double out[3]) {
    const int32_t n = m->node_count;
    double* x = (double*)xmalloc(sizeof(double) * 3 * (size_t)n);
    double* mass = (double*)xmalloc(sizeof(double) * (size_t)n);
    CHECK(sh_body_get_positions(world, body, x, 3 * (int64_t)n));
    CHECK(sh_body_get_masses(world, body, mass, n));
    int32_t top = -1;
    for (int32_t i = 0; i < n; ++i)
        if (mass[i] > 0.0 && (top < 0 || x[3 * i + 2] > x[3 * top + 2])) top = i;
    for (int k = 0; k < 3; ++k) out[k] = x[3 * top + k];
    free(x);
    free(mass);
}

/* The sphere tool of the given radius right above top, its lowest point kGap above it; its
 * centre in start. */
static sh_tool_id add_tool(sh_world* world, double radius, const double top[3], double start[3]) {
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_SPHERE;
    def.shape.radius = radius;
    def.contact.stiffness = kToolStiffness;
    def.contact.exponent = kToolExponent;
    for (int k = 0; k < 3; ++k) def.position[k] = start[k] = top[k];
    def.position[2] = start[2] = top[2] + kGap + radius;
    sh_tool_id tool;
    CHECK(sh_tool_create(world, &def, &tool));
    return tool;
}

/* ------------------------------------------------------------------------------------------ */
/* The press                                                                                    */

/* Per-step samples of the press and hold, and what the case reports besides. */
typedef struct {
    double ms[kSteps];        /* wall time of sh_world_step (ms) */
    double newton[kSteps];    /* report.newton_iterations */
    double substeps[kSteps];  /* report.substeps */
    double force[kSteps + 1]; /* |F| on the tool (N): [0] after the untimed step, [s + 1] after step s */
    double first_ms;          /* the untimed step (ms) */
    double top_fall;          /* the highest node below the rest shape's top when the press starts (m) */
    double above_top;         /* after the press: the sphere's lowest point above the highest node (m) */
    double depth_end_press;   /* after the press: the tool's deepest penetration (m) */
    int contacts_end_press;   /* after the press: its contact points */
    int failed;               /* steps that did not return SH_OK */
    unsigned long long not_converged; /* growth of the SH_WARN_NOT_CONVERGED counter */
} press_log;

/* |F| of the tool's reaction force after the last step (N). */
static double tool_force(const sh_world* world, sh_tool_id tool) {
    double f[3], torque[3];
    CHECK(sh_tool_get_wrench(world, tool, f, torque));
    return sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
}

/* Step s (-1: the untimed one), timed; a failure is counted (and the first one printed). */
static void logged_step(sh_world* world, int s, const char* name, press_log* log) {
    sh_step_report report;
    memset(&report, 0, sizeof report);
    const double t0 = now_ns();
    const sh_status st = sh_world_step(world, kDt, &report);
    const double ms = (now_ns() - t0) * 1e-6;
    if (st != SH_OK && !log->failed++)
        fprintf(stderr, "%s: step %d: %s (%s)\n", name, s, sh_status_string(st), sh_last_error_message());
    if (s < 0) {
        log->first_ms = ms;
        return;
    }
    log->ms[s] = ms;
    log->newton[s] = report.newton_iterations;
    log->substeps[s] = report.substeps;
}

/* What the tool and the liver are at after the press. */
static void log_end_of_press(const sh_world* world, sh_body_id body, sh_tool_id tool, const liver_mesh* m,
                             double radius, const double pose[3], press_log* log) {
    sh_contact_state state;
    CHECK(sh_tool_get_contact(world, tool, &state));
    log->depth_end_press = state.max_depth;
    log->contacts_end_press = state.contact_count;
    double top[3];
    top_point(world, body, m, top);
    log->above_top = pose[2] - radius - top[2];
}

/* The untimed step with the tool at start, then the press and the hold (see the header). */
static void run_press(sh_world* world, sh_body_id body, sh_tool_id tool, const liver_mesh* m, double radius,
                      const double start[3], const char* name, press_log* log) {
    static const double kIdentity[4] = {1.0, 0.0, 0.0, 0.0};
    uint64_t before[SH_WARN_COUNT], after[SH_WARN_COUNT];
    logged_step(world, -1, name, log);
    log->failed = 0; /* only the press and the hold count */
    log->force[0] = tool_force(world, tool);
    CHECK(sh_world_get_warnings(world, before));
    double pose[3] = {start[0], start[1], start[2]};
    for (int s = 0; s < kSteps; ++s) {
        const int pressed = s < kPressSteps ? s + 1 : kPressSteps;
        pose[2] = start[2] - kPressDepth * pressed / kPressSteps;
        CHECK(sh_tool_set_pose(world, tool, pose, kIdentity));
        logged_step(world, s, name, log);
        log->force[s + 1] = tool_force(world, tool);
        if (s + 1 == kPressSteps) log_end_of_press(world, body, tool, m, radius, pose, log);
    }
    CHECK(sh_world_get_warnings(world, after));
    log->not_converged = (unsigned long long)(after[SH_WARN_NOT_CONVERGED] - before[SH_WARN_NOT_CONVERGED]);
}

/* ------------------------------------------------------------------------------------------ */
/* Report                                                                                       */

/* The largest drop of |F| between consecutive steps of the press, the step before it included. */
static double largest_press_drop(const press_log* log) {
    double drop = 0.0;
    for (int s = 1; s <= kPressSteps; ++s)
        if (log->force[s - 1] - log->force[s] > drop) drop = log->force[s - 1] - log->force[s];
    return drop;
}

/* Sorts v[0..kSteps) and gives its median and max. */
static void median_max(double* v, double* med, double* max) {
    qsort(v, kSteps, sizeof(double), cmp_double);
    *med = median(v, kSteps);
    *max = v[kSteps - 1];
}

/* The case's JSON line (sorts the log's samples) and a summary on stderr. */
static void print_case(const char* name, const material_case* material, const liver_mesh* m,
                       const palpation_options* o, press_log* log) {
    const double force_end = log->force[kPressSteps], drop = largest_press_drop(log);
    double ms_med, ms_max, newton_med, newton_max, sub_med, sub_max;
    median_max(log->ms, &ms_med, &ms_max);
    median_max(log->newton, &newton_med, &newton_max);
    median_max(log->substeps, &sub_med, &sub_max);
    printf("{\"case\":\"%s\",\"material\":\"%s\",\"mesh\":\"%s\",\"tets\":%d,\"nodes\":%d,\"fixed_nodes\":%d,"
           "\"young_Pa\":%g,\"poisson\":%g,\"density\":%g,\"dt\":%.6g,\"tool_radius_m\":%g,"
           "\"tool_stiffness\":%g,\"tool_exponent\":%g,\"press_m\":%g,\"settled\":%d,\"top_fall_m\":%.4g,"
           "\"steps\":%d,\"step_median_ms\":%.3f,\"step_p99_ms\":%.3f,\"step_max_ms\":%.3f,\"first_step_ms\":%.3f,"
           "\"newton_median\":%g,\"newton_max\":%g,\"substeps_median\":%g,\"substeps_max\":%g,"
           "\"failed_steps\":%d,\"not_converged\":%llu,\"force_end_press_N\":%.6g,"
           "\"force_max_drop_press_N\":%.6g,\"force_end_hold_N\":%.6g,\"contacts_end_press\":%d,"
           "\"depth_end_press_m\":%.4g,\"tool_above_top_end_press_m\":%.4g}\n",
           name, material->name, kMeshName, m->tet_count, m->node_count, m->fixed_count, kYoung, kPoisson, kDensity,
           kDt, o->radius, kToolStiffness, kToolExponent, kPressDepth, o->settle, log->top_fall, kSteps, ms_med,
           quantile(log->ms, kSteps, 0.99), ms_max, log->first_ms, newton_med, newton_max, sub_med, sub_max,
           log->failed, log->not_converged, force_end, drop, log->force[kSteps], log->contacts_end_press,
           log->depth_end_press, log->above_top);
    fflush(stdout);
    fprintf(stderr, "%s: |F| %.4g N after the press (largest drop %.4g N), step median %.2f ms, max %.2f ms\n", name,
            force_end, drop, ms_med, ms_max);
}

/* One material: a fresh world (settled with --settle), the tool above its top, the press, the
 * JSON line. */
static void run_case(const liver_mesh* m, const material_case* material, const palpation_options* o) {
    char name[128];
    snprintf(name, sizeof name, "palpation/%s/r%gmm%s", material->name, o->radius * 1e3, o->settle ? "+settle" : "");
    if (o->filter && !strstr(name, o->filter)) return;
    sh_body_id body;
    sh_world* world = make_world(m, material->model, &body);
    if (o->settle) settle(world, body, m, name);
    double top[3], start[3];
    top_point(world, body, m, top);
    const sh_tool_id tool = add_tool(world, o->radius, top, start);
    press_log* log = (press_log*)xmalloc(sizeof *log);
    memset(log, 0, sizeof *log);
    log->top_fall = m->rest_top - top[2];
    fprintf(stderr, "%s: top (%.4f, %.4f, %.4f) m, %.2f cm below the rest shape's\n", name, top[0], top[1], top[2],
            log->top_fall * 1e2);
    run_press(world, body, tool, m, o->radius, start, name, log);
    print_case(name, material, m, o, log);
    free(log);
    CHECK(sh_world_destroy(world));
}

/* ------------------------------------------------------------------------------------------ */

static void usage(void) {
    fprintf(stderr, "usage: softhap_bench palpation [FILTER] [--radius M] [--settle] [--meshes DIR]\n"
                    "  FILTER  keep the cases whose name contains it (palpation/<material>/r<mm>mm[+settle])\n"
                    "  --radius M  sphere radius in metres (default 0.01; 0.003: a 3 mm probe)\n"
                    "  --settle  let the liver collapse to rest under gravity before the press\n");
}

int run_palpation(int argc, char** argv) {
    palpation_options o = {NULL, kToolRadius, 0};
    const char* given_dir = NULL;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--radius") == 0 && i + 1 < argc) {
            o.radius = atof(argv[++i]);
            if (!(o.radius > 0.0) || !isfinite(o.radius)) {
                usage();
                return 2;
            }
        } else if (strcmp(argv[i], "--settle") == 0) {
            o.settle = 1;
        } else if (strcmp(argv[i], "--meshes") == 0 && i + 1 < argc) {
            given_dir = argv[++i];
        } else if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage();
            return 0;
        } else if (!o.filter && argv[i][0] != '-') {
            o.filter = argv[i];
        } else {
            usage();
            return 2;
        }
    }
    const char* dir = bench_find_mesh_dir(given_dir, kMeshFile);
    liver_mesh m;
    if (!dir) {
        fprintf(stderr, "softhap_bench: meshes not found; pass --meshes DIR\n");
        return 1;
    }
    if (!load_liver(dir, &m)) return 1;
    fprintf(stderr, "palpation: %s/%s: %d nodes, %d tets, %d fixed; E = %g Pa; sphere radius %g m\n", dir, kMeshFile,
            m.node_count, m.tet_count, m.fixed_count, kYoung, o.radius);
    for (size_t k = 0; k < sizeof kMaterials / sizeof kMaterials[0]; ++k) run_case(&m, &kMaterials[k], &o);
    free_liver(&m);
    return 0;
}
