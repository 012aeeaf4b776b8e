/*
 * softhap_bench palpation: a sphere tool (or a lying capsule) pressed into the liver held at its
 * base, the full model stepped at 60 Hz with implicit Euler (as a haptic host's sim thread steps
 * it). One JSON line per material and tool on stdout, progress on stderr. The scene is
 * tests/python/test_organ_scenes.py's palpation (liver_and_tool, press_triangle, pose_at).
 *
 *   softhap_bench palpation [FILTER] [--meshes DIR]
 *
 * FILTER keeps the cases whose name, palpation/<material> (the sphere) or
 * palpation/<material>/capsule, contains it (material corotational, stvk or neohookean). --meshes DIR gives the mesh folder (else bench_find_mesh_dir's search:
 * $SOFTHAP_MESHES, the build's default, ../shared/meshes, ../../shared/meshes).
 *
 * Scene. SOFA's liver2.msh (507 nodes, 1493 tets) scaled by 0.1 (21 cm long), not moved; the
 * nodes less than 1.5 cm above its lowest point are fixed; gravity off, so the tool force is the
 * contact alone. Tissue E = 3 kPa, nu = 0.45, rho = 1000 kg/m^3, no damping; implicit Euler with
 * the default implicit settings, dt = 1/60 s.
 *
 * Tool. A sphere of radius 1 cm (Hunt-Crossley contact: 1e3 N/m^1.5, exponent 1.5, the default
 * damping, friction mu_s = mu_d = 0.5) over the press triangle: of the rest surface's nearly
 * level triangles (unit normal z > 0.98), the one whose centroid lies nearest, in plan, to the
 * centroid of the fixed nodes. The sphere starts touching that triangle's plane at its centroid
 * (centre kToolRadius / normal_z above it); before step i (1..120) it is posed
 * 1.5 cm * min(1, i / 60) lower: pressed 1.5 cm in 1 s at constant speed, then held 1 s.
 * The capsule case presses a capsule of radius 2 mm and half length 1 cm lying level along x
 * (2.4 cm long, its law 4e4 N/m^1.5 so that it holds 3.6 N at its radius; friction as the
 * sphere's) over the same point: smaller across than the 15 mm triangles, so that its balls'
 * excess, not its nodes, holds it.
 *
 * Per material, over the 120 steps (each sh_world_step timed on its own with now_ns, with a step
 * report; the first includes the implicit solver's and the surface trees' set-up: "first_step_ms"):
 * step time median, p99 and max (ms); the report's Newton iterations and sub-steps, total and
 * largest per step; the world's warning counters (sh_world_get_warnings, by sh_warning name);
 * the tool's force magnitude |F| (sh_tool_get_wrench) after the last press step and after the
 * last hold step (N); steps that did not return SH_OK.
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
static const double kMeshScale = 0.1;     /* file units to metres */
static const double kFixedHeight = 0.015; /* m: nodes closer than this to the lowest are fixed */
static const double kYoung = 3.0e3;       /* Pa: very soft tissue */
static const double kPoisson = 0.45;
static const double kDensity = 1000.0;    /* kg/m^3 */
static const double kDt = 1.0 / 60.0;     /* s: 60 Hz */
static const double kToolRadius = 0.01;   /* m */
static const double kToolStiffness = 1e3; /* N/m^1.5 */
static const double kToolExponent = 1.5;
static const double kToolFriction = 0.5;  /* static and dynamic */
static const double kLevelNormalZ = 0.98; /* a press triangle's unit normal has z above this */
static const double kPressDepth = 0.015;  /* m */
static const double kCapsuleRadius = 0.002, kCapsuleHalfLength = 0.01, kCapsuleStiffness = 4e4;
static const double kLevelAlongX[4] = {0.70710678118654752, 0.0, 0.70710678118654752, 0.0};
static const double kIdentity[4] = {1.0, 0.0, 0.0, 0.0};
enum { kPressSteps = 60, kHoldSteps = 60, kSteps = kPressSteps + kHoldSteps }; /* 1 s, 1 s */

static const sh_material_model kModels[] = {SH_MATERIAL_COROTATIONAL, SH_MATERIAL_STVK, SH_MATERIAL_NEOHOOKEAN};

/* JSON keys of the sh_warning counters, in enum order. */
static const char* const kWarningNames[SH_WARN_COUNT] = {"unstable", "substepped", "inverted", "capacity",
                                                         "force_clamped", "locking", "not_converged"};

/* ------------------------------------------------------------------------------------------ */
/* Scene                                                                                        */

/* The liver in metres, the nodes its base holds and where the tool starts. */
typedef struct {
    sh_mesh* mesh;
    int32_t node_count, tet_count;
    int32_t* fixed;
    int32_t fixed_count;
    double centroid[3], normal[3]; /* the press triangle's (m, unit) */
} liver;

/* A tool the liver is pressed with. */
typedef struct {
    const char* suffix; /* of the case's name */
    sh_shape_kind kind;
    double radius, half_length, stiffness;
    const double* orientation;
} press_tool;

static const press_tool kTools[] = {
    {"", SH_SHAPE_SPHERE, kToolRadius, 0.0, kToolStiffness, kIdentity},
    {"/capsule", SH_SHAPE_CAPSULE, kCapsuleRadius, kCapsuleHalfLength, kCapsuleStiffness, kLevelAlongX},
};

/* Where tool starts: touching the press triangle's plane above its centroid (m). */
static void tool_start(const liver* l, const press_tool* tool, double start[3]) {
    for (int k = 0; k < 3; ++k) start[k] = l->centroid[k];
    start[2] += tool->radius / l->normal[2];
}

/* Picks the nodes of x[0..n) less than kFixedHeight above the lowest into l->fixed; their
 * centroid into base. */
static void fix_base(const double* x, int32_t n, liver* l, double base[3]) {
    double lowest = INFINITY;
    for (int32_t i = 0; i < n; ++i)
        if (x[3 * i + 2] < lowest) lowest = x[3 * i + 2];
    l->fixed = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)n);
    l->fixed_count = 0;
    base[0] = base[1] = base[2] = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        if (!(x[3 * i + 2] < lowest + kFixedHeight)) continue;
        l->fixed[l->fixed_count++] = i;
        for (int k = 0; k < 3; ++k) base[k] += x[3 * i + k];
    }
    for (int k = 0; k < 3; ++k) base[k] /= l->fixed_count;
}

/* The press triangle (see the header) of the surface tris[0..count) over nodes x: its centroid
 * and unit normal. 0 if no triangle is level enough. */
static int press_triangle(const double* x, const int32_t* tris, int32_t count, const double base[3],
                          double centroid[3], double normal[3]) {
    double best = INFINITY;
    for (int32_t t = 0; t < count; ++t) {
        const double* a = &x[3 * tris[3 * t]];
        const double* b = &x[3 * tris[3 * t + 1]];
        const double* c = &x[3 * tris[3 * t + 2]];
        double n[3];
        triangle_cross(a, b, c, n);
        const double length = norm3(n);
        for (int k = 0; k < 3; ++k) n[k] /= length;
        if (!(n[2] > kLevelNormalZ)) continue;
        const double g[3] = {(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0, (a[2] + b[2] + c[2]) / 3.0};
        const double plan = hypot(g[0] - base[0], g[1] - base[1]);
        if (plan >= best) continue;
        best = plan;
        for (int k = 0; k < 3; ++k) {
            centroid[k] = g[k];
            normal[k] = n[k];
        }
    }
    return isfinite(best);
}

/* Loads dir/liver2.msh scaled by kMeshScale into *l, with its fixed base and the tool's start.
 * 0 with a message on stderr if the mesh does not load or has no press triangle. */
static int load_liver(const char* dir, liver* l) {
    memset(l, 0, sizeof *l);
    sh_mesh* raw = bench_load_mesh(dir, kMeshFile);
    if (!raw) return 0;
    CHECK(sh_mesh_transform(raw, kMeshScale, NULL, &l->mesh));
    CHECK(sh_mesh_destroy(raw));
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(l->mesh, &info));
    l->node_count = info.node_count;
    l->tet_count = info.tet_count;
    double* x = (double*)xmalloc(sizeof(double) * 3 * (size_t)info.node_count);
    CHECK(sh_mesh_get_nodes(l->mesh, x, info.node_count));
    int32_t tri_count;
    int32_t* tris = bench_surface_triangles(l->mesh, &tri_count);
    double base[3];
    l->normal[2] = 1.0;
    fix_base(x, info.node_count, l, base);
    const int found = press_triangle(x, tris, tri_count, base, l->centroid, l->normal);
    free(x);
    free(tris);
    if (!found) {
        fprintf(stderr, "softhap_bench: %s has no level top triangle to press\n", kMeshFile);
        return 0;
    }
    return 1;
}

/* Frees what load_liver made. */
static void free_liver(liver* l) {
    sh_mesh_destroy(l->mesh);
    free(l->fixed);
}

/* A world without gravity holding the liver as one implicit-Euler body of the given model, its
 * base fixed, and the tool at start (its id in *tool). */
static sh_world* make_world(const liver* l, sh_material_model model, const press_tool* pt, const double start[3],
                            sh_tool_id* tool) {
    sh_world* world = bench_world_create(0);
    sh_fem_body_def def = bench_fem_body_def(l->mesh, model, kYoung, kPoisson, kDensity);
    def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    sh_body_id body;
    CHECK(sh_fem_body_create(world, &def, &body));
    CHECK(sh_body_fix_nodes(world, body, l->fixed, l->fixed_count));
    sh_collider_def td = bench_sphere_def(pt->radius, start);
    td.shape.kind = pt->kind;
    td.shape.half_length = pt->half_length;
    for (int k = 0; k < 4; ++k) td.orientation[k] = pt->orientation[k];
    td.contact.stiffness = pt->stiffness;
    td.contact.exponent = kToolExponent;
    td.contact.static_friction = td.contact.dynamic_friction = kToolFriction;
    CHECK(sh_tool_create(world, &td, tool));
    return world;
}

/* ------------------------------------------------------------------------------------------ */
/* The press                                                                                    */

/* Per-step samples of the press and hold and their totals. */
typedef struct {
    double ns[kSteps]; /* wall time of each sh_world_step (ns) */
    long newton_total, substeps_total;
    int newton_max, substeps_max;
    double force_end_press, force_end_hold; /* |F| on the tool (N) */
    int failed;                             /* steps that did not return SH_OK */
} press_log;

/* |F| of the tool's reaction force after the last step (N). */
static double tool_force(const sh_world* world, sh_tool_id tool) {
    double f[3], torque[3];
    CHECK(sh_tool_get_wrench(world, tool, f, torque));
    return norm3(f);
}

/* Step s, timed and logged; a failure is counted (the first one printed). */
static void logged_step(sh_world* world, int s, const char* name, press_log* log) {
    sh_step_report report;
    memset(&report, 0, sizeof report);
    const double t0 = now_ns();
    const sh_status st = sh_world_step(world, kDt, &report);
    log->ns[s] = now_ns() - t0;
    if (st != SH_OK && !log->failed++)
        fprintf(stderr, "%s: step %d: %s (%s)\n", name, s, sh_status_string(st), sh_last_error_message());
    log->newton_total += report.newton_iterations;
    log->substeps_total += report.substeps;
    if (report.newton_iterations > log->newton_max) log->newton_max = report.newton_iterations;
    if (report.substeps > log->substeps_max) log->substeps_max = report.substeps;
}

/* The press and the hold (see the header), the tool's force after each. */
static void run_press(sh_world* world, sh_tool_id tool, const double start[3], const double orientation[4],
                      const char* name, press_log* log) {
    for (int s = 0; s < kSteps; ++s) {
        const int pressed = s < kPressSteps ? s + 1 : kPressSteps;
        const double pose[3] = {start[0], start[1], start[2] - kPressDepth * pressed / kPressSteps};
        CHECK(sh_tool_set_pose(world, tool, pose, orientation));
        logged_step(world, s, name, log);
        if (s + 1 == kPressSteps) log->force_end_press = tool_force(world, tool);
    }
    log->force_end_hold = tool_force(world, tool);
}

/* ------------------------------------------------------------------------------------------ */
/* Report                                                                                       */

/* The case's JSON line (sorts the log's times) and a summary on stderr. */
static void print_case(const char* name, sh_material_model model, const press_tool* pt, const liver* l,
                       press_log* log, const uint64_t warnings[SH_WARN_COUNT]) {
    const double first_ns = log->ns[0];
    const stats t = summarize(log->ns, kSteps);
    printf("{\"case\":\"palpation\",\"material\":\"%s\",\"tool\":\"%s\",\"mesh\":\"%s\",\"tets\":%d,\"nodes\":%d,\"fixed_nodes\":%d,"
           "\"dt\":%.6g,\"steps\":%d,\"step_median_ms\":%.3f,\"step_p99_ms\":%.3f,\"step_max_ms\":%.3f,"
           "\"first_step_ms\":%.3f,\"newton_iterations_total\":%ld,\"newton_iterations_max\":%d,"
           "\"substeps_total\":%ld,\"substeps_max\":%d,\"warnings\":{",
           material_name(model), pt->kind == SH_SHAPE_CAPSULE ? "capsule" : "sphere", kMeshName, l->tet_count, l->node_count, l->fixed_count, kDt, kSteps, t.median * 1e-6,
           t.p99 * 1e-6, t.max * 1e-6, first_ns * 1e-6, log->newton_total, log->newton_max, log->substeps_total,
           log->substeps_max);
    for (int w = 0; w < SH_WARN_COUNT; ++w)
        printf("%s\"%s\":%llu", w ? "," : "", kWarningNames[w], (unsigned long long)warnings[w]);
    printf("},\"force_end_press_N\":%.6g,\"force_end_hold_N\":%.6g,\"failed_steps\":%d}\n", log->force_end_press,
           log->force_end_hold, log->failed);
    fflush(stdout);
    fprintf(stderr, "%s: |F| %.4g N after the press, %.4g N after the hold; step median %.2f ms, max %.2f ms\n",
            name, log->force_end_press, log->force_end_hold, t.median * 1e-6, t.max * 1e-6);
}

/* One material and tool: a fresh world, the press and hold, the JSON line. */
static void run_case(const liver* l, sh_material_model model, const press_tool* pt, const char* filter) {
    char name[128];
    snprintf(name, sizeof name, "palpation/%s%s", material_name(model), pt->suffix);
    if (!name_matches(name, filter)) return;
    double start[3];
    tool_start(l, pt, start);
    sh_tool_id tool;
    sh_world* world = make_world(l, model, pt, start, &tool);
    press_log log;
    memset(&log, 0, sizeof log);
    run_press(world, tool, start, pt->orientation, name, &log);
    uint64_t warnings[SH_WARN_COUNT];
    CHECK(sh_world_get_warnings(world, warnings));
    print_case(name, model, pt, l, &log, warnings);
    CHECK(sh_world_destroy(world));
}

/* ------------------------------------------------------------------------------------------ */

/* The subcommand's usage on stderr. */
static void usage(void) {
    fprintf(stderr, "usage: softhap_bench palpation [FILTER] [--meshes DIR]\n"
                    "  FILTER  keep the cases whose name contains it (palpation/<material>[/capsule])\n"
                    "  --meshes DIR  mesh folder holding liver2.msh\n");
}

/* The command line, then every wanted material's case on the one loaded liver. */
int run_palpation(int argc, char** argv) {
    const char* filter = NULL;
    const char* given_dir = NULL;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--meshes") == 0 && i + 1 < argc) {
            given_dir = argv[++i];
        } else {
            const int code = bench_filter_arg(argv[i], &filter, usage);
            if (code >= 0) return code;
        }
    }
    const char* dir = bench_find_mesh_dir(given_dir, kMeshFile);
    if (!dir) return 1;
    liver l;
    if (!load_liver(dir, &l)) return 1;
    fprintf(stderr, "palpation: %s/%s: %d nodes, %d tets, %d fixed; press triangle at (%.4f, %.4f, %.4f) m\n", dir,
            kMeshFile, l.node_count, l.tet_count, l.fixed_count, l.centroid[0], l.centroid[1], l.centroid[2]);
    for (size_t t = 0; t < sizeof kTools / sizeof kTools[0]; ++t)
        for (size_t k = 0; k < sizeof kModels / sizeof kModels[0]; ++k) run_case(&l, kModels[k], &kTools[t], filter);
    free_liver(&l);
    return 0;
}
