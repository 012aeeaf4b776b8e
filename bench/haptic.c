/*
 * softhap_bench haptic | haptic-error | haptic-force: the Volumetric Buffer Model's haptic step
 * (issue 5, item 6: error against run time for haptics). One JSON line per case on stdout,
 * progress on stderr; scripts/haptic_report.py turns them into report/haptic.md and plots.
 *
 *   softhap_bench haptic [FILTER] [--steps N] [--rt] [--meshes DIR]
 *   softhap_bench haptic-error [FILTER] [--meshes DIR]
 *   softhap_bench haptic-force [--csv PATH] [--meshes DIR]
 *
 * FILTER keeps the cases whose name contains it. --rt runs the haptic thread SCHED_FIFO (as a
 * device loop would; "rt" says whether it was granted), so that other processes do not preempt
 * it: on a shared machine that is what separates the step's own tail from the machine's (the
 * kernel still throttles a real-time thread that never sleeps for 50 ms each second, which
 * shows in the back-to-back runs' max, not in their p99.9). Public API only; C99 plus POSIX
 * threads and clocks (C11 atomics, as in the tests), pinned to one CPU on Linux.
 *
 * Tissue. Every body is corotational (unless a case says otherwise), E = 15 kPa, nu = 0.45,
 * rho = 1000 kg/m^3, gravity off (the press is the only load, so the full model's reference is
 * the press force alone), fixed nodes at its base; the tool is a sphere of radius 1 cm with the
 * default Hunt-Crossley law (1e4 N/m^1.5, n = 1.5, alpha = 0.2 s/m) and no friction. The haptic
 * step is 1 ms (1 kHz).
 *
 * haptic: the haptic step's cost against buffer size. A block 6 x 6 x 3 cm (12 x 12 x 6 cubes,
 * 5184 tets, 5 mm cells), base fixed; the sphere is pressed kCostDepth into the top centre over
 * kPressTicks ticks, then circles 1 mm around that point once a second. The buffer holds
 * capacity_tets = N tets (radius 1 m, so the capacity picks the N tets nearest the contact
 * point; capacity_nodes 4 N + 4 never binds). A counting allocator is installed with
 * sh_set_allocator before anything is created; it counts the calls made from the haptic thread
 * while the timed loop runs ("allocations", must be 0). Cases:
 *  - "haptic/frozen/<material>/<N>": the world never steps (the buffer is the one extracted at
 *    creation); after kWarmupTicks, sh_haptic_step back to back, each call timed on its own
 *    (CLOCK_MONOTONIC, a clock read costs "clock_ns"): kTimedTicks for corotational,
 *    kOtherTimedTicks for the other materials (--steps N: N for all).
 *  - "haptic/sim/corotational/<N>": a sim thread (pinned to the other core when there is one,
 *    never real-time) steps the world by 1/60 s (implicit Euler) at most 60 times per second of
 *    wall time, while the haptic thread runs kPacedTicks ticks paced at 1 kHz of wall time; each
 *    sim step moves the full model's tool to the device pose and re-extracts the buffer, which
 *    the haptic side adopts. "sim_rate_hz" is the rate the sim kept.
 *  - "haptic/overhead": the fixed cost: the tool 1 m above the block, so the buffer is empty
 *    and the step renders the (untouched) proxy plane: per-call times, and the median of
 *    kBatches batches of kBatch calls timed together (no clock read per call).
 * Per case: median, p99, p99.9, max and mean of the step time (us), sub-steps per step (median
 * and max), ns per tet and per tet and sub-step (median / buffer tets [/ median sub-steps]).
 *
 * haptic-error: the force error of the VBM against the full model solved at the same instant.
 * SOFA's haptic-demo liver (liver.msh: 181 nodes, 596 tets) and its finer version (liver2.msh,
 * 1493 tets), turned so that the flattest side faces down, scaled to 16 cm, the nodes in the
 * lowest 10 % of the height fixed. The tool presses kErrorDepth into the centroid of the largest
 * nearly level facet of the top (over at least 3 cm of tissue). Reference: sh_world_solve_static
 * with the tool at the pressed pose (tolerance 1e-9), then sh_tool_get_wrench. For each buffer
 * radius (1 cm to 1 m, the whole organ), the haptic context presses over 0.3 s and holds to 3 s
 * (3000 ticks) with mass damping 100 1/s (about critical for the organ's lowest mode),
 * max_force 100 N, no rate limit nor ramp, stale_after 1000 s; then its raw_force is compared
 * with the reference: rel_error = |F_vbm - F_ref| / |F_ref| (rel_error_normal: the z component,
 * signed); settle_change = |F(3 s) - F(2.5 s)| / |F_ref|. Two modes:
 *  - "frozen": the world does not step, so the buffer's boundary stays where the full model was
 *    before the press (the full model has not reacted yet): the VBM's own truncation error;
 *  - "coupled": the world steps by 1/60 s every 1/60 s of haptic time (implicit Euler, same
 *    damping), interleaved on one thread, so the boundary follows the full model, which the
 *    world presses with the device pose; "world_force" is the full model's own tool force.
 * The step time is taken over the last 2000 ticks (the hold).
 *
 * haptic-force: force smoothness, the VBM against a zero-order hold of the full model, on
 * liver2 (same set-up, mass damping 2 1/s). A press-and-slide trajectory: from 5 mm above the
 * touching height down to it (0-0.3 s), 8 mm further (0.3-0.8 s), hold, slide 3 cm at that depth
 * below the touching height along the way (1.0-2.5 s, in the direction, of eight, in which the
 * top's height varies least), hold, lift to 5 mm above (2.7-3.2 s), rest to 3.5 s. One thread,
 * deterministic: a haptic tick every 1 ms of haptic time (radius 3 cm, default force limits:
 * 10 N, 2000 N/s, 50 ms ramp) and a world step (implicit Euler) every 1/60 s of it; after each
 * world step sh_tool_get_wrench gives the full model's force, held until the next (the ZOH).
 * Per signal (VBM rendered, VBM raw, ZOH): max and RMS over ticks of |F(i) - F(i-1)|, over the
 * whole run and over the slide. --csv PATH writes the per-tick trace.
 */
#define _GNU_SOURCE
#include "haptic.h"

#include "bench_util.h"
#include "box_mesh.h"

#include <softhap/softhap.h>

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#ifdef __linux__
#include <sched.h>
#endif

/* ------------------------------------------------------------------------------------------ */
/* Parameters                                                                                   */

static const double kPi = 3.14159265358979323846;
static const double kYoung = 15e3;    /* Pa */
static const double kPoisson = 0.45;
static const double kDensity = 1000.0; /* kg/m^3 */
static const double kToolRadius = 0.01; /* m */
static const double kHapticDt = 1e-3;   /* s: 1 kHz */
static const double kSimDt = 1.0 / 60.0; /* s: the full model at 60 Hz */

/* haptic (cost) */
static const double kBlock[3] = {0.06, 0.06, 0.03}; /* m */
static const int kBlockCells[3] = {12, 12, 6};
static const int kCostSizes[] = {50, 100, 200, 500, 1000, 2000};
static const double kCostDepth = 0.003;   /* m */
static const double kCostCircle = 0.001;  /* m, once a second */
static const double kCostDamping = 5.0;   /* 1/s */
static const int kConcurrentSizes[] = {50, 200, 500, 2000};
static const int kPressTicks = 300, kWarmupTicks = 2000, kPacedTicks = 5000;
/* Timed ticks: corotational (the headline), the other materials (for their kernels' cost). */
static const int kTimedTicks = 20000, kOtherTimedTicks = 5000;
static const int kBatch = 100, kBatches = 200;

/* haptic-error */
static const double kLiverSize = 0.16;          /* m */
static const double kLiverFixedFraction = 0.10; /* of its height */
static const double kMinThickness = 0.03;       /* m of tissue under the press point */
static const double kErrorDepth = 0.008;        /* m */
static const double kErrorDamping = 100.0;      /* 1/s */
static const double kErrorRadii[] = {0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.1, 1.0}; /* m */
static const double kErrorPressTime = 0.3, kErrorTime = 3.0; /* s */
static const int kErrorTimedTicks = 2000;
static const int kSettleTicks = 500; /* settled: the force's change over the last 0.5 s */

/* The livers: SOFA's haptic-demo liver and its finer version. */
typedef struct {
    const char* file;
    const char* name;
} liver_file;
static const liver_file kLivers[] = {{"liver.msh", "liver"}, {"liver2.msh", "liver2"}};

/* haptic-force: liver2, whose finer top keeps a sliding sphere in contact (on liver.msh's 2-3 cm
 * facets it loses its support where it straddles an edge between two facets) */
static const liver_file kTraceLiver = {"liver2.msh", "liver2"};
static const double kTraceDamping = 2.0; /* 1/s */
static const double kTraceRadius = 0.03; /* m */
static const double kTraceGap = 0.005, kTraceDepth = 0.008, kTraceSlide = 0.03; /* m */
static const double kApproachEnd = 0.3, kPressEnd = 0.8, kSlideStart = 1.0, kSlideEnd = 2.5, kLiftStart = 2.7,
                    kLiftEnd = 3.2, kTraceEnd = 3.5; /* s */
enum { kPathSamples = 61 };

static const char* g_mesh_dir = NULL;
static const char* g_filter = NULL;
static const char* g_csv = NULL;
static int g_steps = 0;
static int g_rt = 0; /* --rt: the haptic thread runs SCHED_FIFO (1 if granted) */

static int matches(const char* name) { return name_matches(name, g_filter); }

/* ------------------------------------------------------------------------------------------ */
/* Allocation counting and threads                                                              */

static _Thread_local int tl_counting;
static atomic_long g_allocations;

static void* counting_alloc(size_t size, size_t alignment, void* user) {
    (void)user;
    if (tl_counting) atomic_fetch_add(&g_allocations, 1);
    void* p = NULL;
    return posix_memalign(&p, alignment < sizeof(void*) ? sizeof(void*) : alignment, size ? size : 1) == 0 ? p : NULL;
}

static void counting_free(void* ptr, void* user) {
    (void)user;
    if (ptr && tl_counting) atomic_fetch_add(&g_allocations, 1);
    free(ptr);
}

/* The CPUs the process may run on (set at start), and the one the haptic thread keeps. */
static int g_haptic_cpu = -1, g_other_cpu = -1;

static void pin_self(int cpu) {
#ifdef __linux__
    if (cpu < 0) return;
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    sched_setaffinity(0, sizeof set, &set); /* 0: the calling thread */
#else
    (void)cpu;
#endif
}

static void choose_cpus(void) {
#ifdef __linux__
    cpu_set_t set;
    g_haptic_cpu = sched_getcpu();
    if (sched_getaffinity(0, sizeof set, &set) == 0)
        for (int c = 0; c < CPU_SETSIZE && g_other_cpu < 0; ++c)
            if (c != g_haptic_cpu && CPU_ISSET(c, &set)) g_other_cpu = c;
#endif
    if (g_other_cpu < 0) g_other_cpu = g_haptic_cpu;
}

static void sleep_until(double deadline_ns) {
    struct timespec t;
    t.tv_sec = (time_t)(deadline_ns * 1e-9);
    t.tv_nsec = (long)(deadline_ns - (double)t.tv_sec * 1e9);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, NULL) != 0) {
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Statistics                                                                                   */

/* Prints "<prefix>median_us":..,... for times in ns. */
static void print_times_us(const char* prefix, const stats* s) {
    printf("\"%smedian_us\":%.3f,\"%sp99_us\":%.3f,\"%sp999_us\":%.3f,\"%smax_us\":%.3f,\"%smean_us\":%.3f", prefix,
           s->median * 1e-3, prefix, s->p99 * 1e-3, prefix, s->p999 * 1e-3, prefix, s->max * 1e-3, prefix,
           s->mean * 1e-3);
}

static double distance3(const double* a, const double* b) {
    const double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return norm3(d);
}

static double clamp01(double s) { return s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s; }

/* Smooth 0 -> 1 over [0, 1] with zero slope at both ends. */
static double ease(double s) { return 0.5 - 0.5 * cos(kPi * clamp01(s)); }

/* ------------------------------------------------------------------------------------------ */
/* Tissues: a mesh with its fixed base and the point the tool presses                           */

typedef struct {
    const char* name;
    sh_mesh* mesh;
    double* nodes; /* rest positions (3 per node) */
    int32_t node_count, tet_count;
    int32_t* tris; /* surface triangles, outward */
    int32_t tri_count;
    int32_t* fixed;
    int32_t fixed_count;
    double press[2]; /* (x, y) of the press point, seen from above */
    double slide[2]; /* unit direction of the slide (haptic-force) */
} tissue;

/* Fills t's arrays from t->mesh and fixes the nodes at or below base_height. */
static void tissue_finish(tissue* t, double base_height) {
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(t->mesh, &info));
    t->node_count = info.node_count;
    t->tet_count = info.tet_count;
    t->tri_count = info.surface_triangle_count;
    t->tris = (int32_t*)xmalloc(sizeof(int32_t) * 3 * (size_t)t->tri_count);
    CHECK(sh_mesh_get_surface_triangles(t->mesh, t->tris, t->tri_count));
    t->fixed = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)t->node_count);
    t->fixed_count = 0;
    for (int32_t i = 0; i < t->node_count; ++i)
        if (t->nodes[3 * i + 2] <= base_height) t->fixed[t->fixed_count++] = i;
}

static void tissue_free(tissue* t) {
    sh_mesh_destroy(t->mesh);
    free(t->nodes);
    free(t->tris);
    free(t->fixed);
}

/* The highest and lowest crossings of the vertical line through (x, y) with the surface; 0 if
 * it misses. */
static int vertical_crossings(const tissue* t, double x, double y, double* top, double* bottom) {
    int hit = 0;
    *top = -INFINITY;
    *bottom = INFINITY;
    for (int32_t k = 0; k < t->tri_count; ++k) {
        const double* a = &t->nodes[3 * t->tris[3 * k]];
        const double* b = &t->nodes[3 * t->tris[3 * k + 1]];
        const double* c = &t->nodes[3 * t->tris[3 * k + 2]];
        const double det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        if (fabs(det) < 1e-18) continue;
        const double u = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / det;
        const double v = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / det;
        if (u < 0.0 || v < 0.0 || u + v > 1.0) continue;
        const double z = a[2] + u * (b[2] - a[2]) + v * (c[2] - a[2]);
        if (z > *top) *top = z;
        if (z < *bottom) *bottom = z;
        hit = 1;
    }
    return hit;
}

/* Height of the tool's centre at which the sphere, lowered vertically over (x, y), first
 * touches the rest surface: the highest h(p) + sqrt(r^2 - |p - (x, y)|^2) over points p on
 * rings of the disc under it; -INFINITY if the centre is off the surface. */
static double touch_height(const tissue* t, double x, double y) {
    double top, bottom;
    if (!vertical_crossings(t, x, y, &top, &bottom)) return -INFINITY;
    double best = top + kToolRadius;
    for (int ring = 1; ring <= 4; ++ring)
        for (int k = 0; k < 16; ++k) {
            const double d = 0.25 * ring * kToolRadius, a = 2.0 * kPi * k / 16.0;
            if (!vertical_crossings(t, x + d * cos(a), y + d * sin(a), &top, &bottom)) continue;
            const double z = top + sqrt(kToolRadius * kToolRadius - d * d);
            if (z > best) best = z;
        }
    return best;
}

/* The tool's centre where it first touches above the press point. */
static void touch_point(const tissue* t, double out[3]) {
    out[0] = t->press[0];
    out[1] = t->press[1];
    out[2] = touch_height(t, t->press[0], t->press[1]);
}

/* The block of the cost study. */
static tissue make_block(void) {
    tissue t;
    memset(&t, 0, sizeof t);
    t.name = "block";
    int32_t* tets = NULL;
    sh_test_box_arrays(kBlock[0], kBlock[1], kBlock[2], kBlockCells[0], kBlockCells[1], kBlockCells[2], &t.nodes,
                       &t.node_count, &tets, &t.tet_count);
    if (!t.nodes || !tets) {
        fprintf(stderr, "softhap_bench: out of memory\n");
        exit(1);
    }
    CHECK(sh_mesh_create(t.nodes, t.node_count, tets, t.tet_count, &t.mesh));
    free(tets);
    tissue_finish(&t, 0.0);
    t.press[0] = 0.5 * kBlock[0];
    t.press[1] = 0.5 * kBlock[1];
    t.slide[0] = 1.0;
    return t;
}

/* The liver (see the header): the press point is the centroid of the largest facet of its
 * top that is nearly level (normal within 25 degrees of +z), seen from above, over at least
 * kMinThickness of tissue; the slide goes the way, of eight, along which the touching height
 * varies least over kTraceSlide. Returns 0 if the mesh is missing or has no such facet. */
static int make_liver(tissue* t, const char* file, const char* name) {
    /* File +y (the flattest side) down: (x, y, z) -> (x, z, -y). */
    static const double kTurn[9] = {1, 0, 0, 0, 0, 1, 0, -1, 0};
    memset(t, 0, sizeof *t);
    t->name = name;
    if (!bench_load_scaled_mesh(g_mesh_dir, file, kTurn, kLiverSize, &t->mesh, &t->nodes)) return 0;
    double height = 0.0;
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(t->mesh, &info));
    for (int32_t i = 0; i < info.node_count; ++i)
        if (t->nodes[3 * i + 2] > height) height = t->nodes[3 * i + 2];
    tissue_finish(t, kLiverFixedFraction * height);

    double best_area = 0.0;
    for (int32_t k = 0; k < t->tri_count; ++k) {
        const double* a = &t->nodes[3 * t->tris[3 * k]];
        const double* b = &t->nodes[3 * t->tris[3 * k + 1]];
        const double* c = &t->nodes[3 * t->tris[3 * k + 2]];
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        const double area = 0.5 * norm3(n);
        if (area <= best_area || n[2] < cos(25.0 * kPi / 180.0) * 2.0 * area) continue;
        const double cx = (a[0] + b[0] + c[0]) / 3.0, cy = (a[1] + b[1] + c[1]) / 3.0, cz = (a[2] + b[2] + c[2]) / 3.0;
        double top, bottom;
        if (!vertical_crossings(t, cx, cy, &top, &bottom) || top > cz + 1e-9 || top - bottom < kMinThickness) continue;
        best_area = area;
        t->press[0] = cx;
        t->press[1] = cy;
    }
    if (best_area == 0.0) {
        fprintf(stderr, "softhap_bench: the liver has no level top facet to press\n");
        return 0;
    }
    double best_range = INFINITY;
    for (int d = 0; d < 8; ++d) {
        const double dir[2] = {cos(d * kPi / 4.0), sin(d * kPi / 4.0)};
        double lo = INFINITY, hi = -INFINITY;
        for (int s = 0; s < kPathSamples; ++s) {
            const double along = kTraceSlide * s / (kPathSamples - 1);
            const double h = touch_height(t, t->press[0] + along * dir[0], t->press[1] + along * dir[1]);
            if (h < lo) lo = h;
            if (h > hi) hi = h;
        }
        if (isfinite(lo) && hi - lo < best_range) {
            best_range = hi - lo;
            t->slide[0] = dir[0];
            t->slide[1] = dir[1];
        }
    }
    if (!isfinite(best_range)) {
        fprintf(stderr, "softhap_bench: no slide path on the liver's top\n");
        return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------------------------------ */
/* Scenes: a world with the tissue's body and the tool                                          */

typedef struct {
    sh_world* world;
    sh_body_id body;
    sh_tool_id tool;
} scene;

static scene scene_create(const tissue* t, sh_material_model model, sh_integrator integrator, double damping,
                          const double tool_position[3]) {
    scene s;
    sh_world_def wd;
    sh_world_def_default(&wd);
    wd.gravity[0] = wd.gravity[1] = wd.gravity[2] = 0.0;
    CHECK(sh_world_create(&wd, &s.world));
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = t->mesh;
    def.material.model = model;
    def.material.young = kYoung;
    def.material.poisson = kPoisson;
    def.material.density = kDensity;
    def.integrator = integrator;
    def.damping_mass = damping;
    CHECK(sh_fem_body_create(s.world, &def, &s.body));
    CHECK(sh_body_fix_nodes(s.world, s.body, t->fixed, t->fixed_count));
    sh_collider_def tool;
    sh_collider_def_default(&tool);
    tool.shape.kind = SH_SHAPE_SPHERE;
    tool.shape.radius = kToolRadius;
    for (int k = 0; k < 3; ++k) tool.position[k] = tool_position[k];
    CHECK(sh_tool_create(s.world, &tool, &s.tool));
    return s;
}

static void scene_destroy(scene* s) { CHECK(sh_world_destroy(s->world)); }

/* One full-model step of kSimDt. An implicit step whose Newton iteration does not converge
 * leaves the body as it was (SH_ERR_NOT_CONVERGED): counted (returns 1), not fatal. */
static int world_step(sh_world* world) {
    const sh_status st = sh_world_step(world, kSimDt, NULL);
    if (st == SH_ERR_NOT_CONVERGED) return 1;
    CHECK(st);
    return 0;
}

/* A haptic def for the scene's tool: a buffer of radius and at most capacity_tets tets (nodes
 * never bind), stale data never (the studies step the world themselves or not at all). exact:
 * no clamp, rate limit nor ramp, so that the output is the raw force. */
static sh_haptic_def haptic_def_for(const scene* s, double radius, int32_t capacity_tets, int exact) {
    sh_haptic_def def;
    sh_haptic_def_default(&def);
    def.tool = s->tool;
    def.radius = radius;
    def.capacity_tets = capacity_tets;
    def.capacity_nodes = 4 * capacity_tets + 4;
    def.dt = kHapticDt;
    def.stale_after = 1e3;
    if (exact) {
        def.max_force = 100.0;
        def.max_force_rate = 1e6;
        def.ramp_time = 0.0;
    }
    return def;
}

static const double kIdentity[4] = {1.0, 0.0, 0.0, 0.0};

/* ------------------------------------------------------------------------------------------ */
/* Timed haptic ticks                                                                           */

/* The device's path: the tool centre at tick i (the pose the step takes it to). */
typedef void (*path_fn)(const void* path, long tick, double out[3]);

/* What a run of ticks saw. */
typedef struct {
    double* ns;      /* per timed tick */
    double* substeps;/* per timed tick */
    int timed;
    long contact, fresh;
    uint32_t faults;
    long allocations;
    sh_haptic_output last;
} tick_log;

/* Steps haptic from tick `first` for count ticks along path; paced: one tick per kHapticDt of
 * wall time. Timed ticks (if log->ns) are recorded, and calls of the allocator from this thread
 * during the loop counted. */
static void run_ticks(sh_haptic* haptic, path_fn path, const void* ctx, long first, long count, int paced,
                      tick_log* log) {
    double deadline = now_ns();
    sh_haptic_output out;
    memset(&out, 0, sizeof out);
    atomic_store(&g_allocations, 0);
    tl_counting = log->ns != NULL;
    for (long i = 0; i < count; ++i) {
        double p[3];
        path(ctx, first + i, p);
        if (paced) {
            deadline += kHapticDt * 1e9;
            sleep_until(deadline);
        }
        const double t0 = now_ns();
        const sh_status st = sh_haptic_step(haptic, p, kIdentity, kHapticDt, &out);
        const double t1 = now_ns();
        if (st != SH_OK) log->faults |= 0x80000000u;
        if (log->ns) {
            log->ns[log->timed] = t1 - t0;
            log->substeps[log->timed] = out.substeps;
            ++log->timed;
        }
        log->contact += out.contact;
        log->fresh += out.data_age <= kHapticDt * 1.000001;
        log->faults |= out.faults;
    }
    tl_counting = 0;
    if (log->ns) log->allocations += atomic_load(&g_allocations);
    log->last = out;
}

static void tick_log_alloc(tick_log* log, int count) {
    memset(log, 0, sizeof *log);
    log->ns = (double*)xmalloc(sizeof(double) * (size_t)count);
    log->substeps = (double*)xmalloc(sizeof(double) * (size_t)count);
}

static void tick_log_free(tick_log* log) {
    free(log->ns);
    free(log->substeps);
}

/* ------------------------------------------------------------------------------------------ */
/* haptic: cost against buffer size                                                             */

typedef struct {
    double touch[3];
} cost_path;

/* Pressed kCostDepth over kPressTicks, then a circle of kCostCircle once a second. */
static void cost_pose(const void* ctx, long tick, double out[3]) {
    const cost_path* c = (const cost_path*)ctx;
    const double press = fmin(1.0, (tick + 1.0) / kPressTicks);
    const double a = tick > kPressTicks ? 2.0 * kPi * (tick - kPressTicks) * kHapticDt : 0.0;
    out[0] = c->touch[0] + kCostCircle * (cos(a) - 1.0);
    out[1] = c->touch[1] + kCostCircle * sin(a);
    out[2] = c->touch[2] - kCostDepth * press;
}

/* The sim thread of the concurrent case. */
typedef struct {
    sh_world* world;
    atomic_int stop;
    int steps, capacity, failed;
    double* ns;
} sim_runner;

static void* sim_main(void* arg) {
    sim_runner* r = (sim_runner*)arg;
    pin_self(g_other_cpu);
    if (g_rt) { /* the sim thread is an ordinary one (it inherited the haptic thread's policy) */
        struct sched_param normal;
        memset(&normal, 0, sizeof normal);
        pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal);
    }
    double deadline = now_ns();
    while (!atomic_load(&r->stop)) {
        const double t0 = now_ns();
        r->failed += world_step(r->world);
        if (r->steps < r->capacity) r->ns[r->steps] = now_ns() - t0;
        ++r->steps;
        deadline += kSimDt * 1e9;
        const double now = now_ns();
        if (now < deadline)
            sleep_until(deadline);
        else
            deadline = now; /* behind: no catching up */
    }
    return NULL;
}

/* One buffer size: frozen (back to back) or beside the sim thread (paced at 1 kHz). */
static void cost_case(const tissue* block, sh_material_model model, int capacity, int with_sim) {
    char name[128];
    snprintf(name, sizeof name, "haptic/%s/%s/%d", with_sim ? "sim" : "frozen", material_name(model), capacity);
    if (!matches(name)) return;
    cost_path path;
    touch_point(block, path.touch);
    scene s = scene_create(block, model, with_sim ? SH_INTEGRATOR_IMPLICIT_EULER : SH_INTEGRATOR_SYMPLECTIC_EULER,
                           kCostDamping, path.touch);
    const sh_haptic_def def = haptic_def_for(&s, 1.0, capacity, 0);
    sh_haptic* haptic = NULL;
    CHECK(sh_haptic_create(s.world, &def, &haptic));
    if (with_sim) world_step(s.world); /* the implicit solver's set-up */

    tick_log warm, log;
    memset(&warm, 0, sizeof warm);
    run_ticks(haptic, cost_pose, &path, 0, kPressTicks + kWarmupTicks, 0, &warm);
    const int count = with_sim ? (g_steps > 0 ? g_steps / 4 : kPacedTicks)
                               : g_steps > 0 ? g_steps
                               : model == SH_MATERIAL_COROTATIONAL ? kTimedTicks : kOtherTimedTicks;
    tick_log_alloc(&log, count);
    sim_runner sim;
    memset(&sim, 0, sizeof sim);
    pthread_t thread;
    if (with_sim) {
        sim.world = s.world;
        sim.capacity = 4096;
        sim.ns = (double*)xmalloc(sizeof(double) * (size_t)sim.capacity);
        atomic_store(&sim.stop, 0);
        if (pthread_create(&thread, NULL, sim_main, &sim) != 0) {
            fprintf(stderr, "softhap_bench: cannot start the sim thread\n");
            exit(1);
        }
    }
    const double t0 = now_ns();
    run_ticks(haptic, cost_pose, &path, kPressTicks + kWarmupTicks, count, with_sim, &log);
    const double wall = (now_ns() - t0) * 1e-9;
    if (with_sim) {
        atomic_store(&sim.stop, 1);
        pthread_join(thread, NULL);
    }
    const stats sub = summarize(log.substeps, log.timed);
    const stats t = summarize(log.ns, log.timed);
    const int tets = log.last.buffer_tets;
    printf("{\"study\":\"haptic_cost\",\"case\":\"%s\",\"material\":\"%s\",\"sim\":\"%s\",\"capacity_tets\":%d,"
           "\"buffer_tets\":%d,\"buffer_nodes\":%d,\"mesh_tets\":%d,\"steps\":%d,",
           name, material_name(model), with_sim ? "sim" : "frozen", capacity, tets, log.last.buffer_nodes,
           block->tet_count, t.count);
    print_times_us("", &t);
    printf(",\"substeps_median\":%g,\"substeps_max\":%g,\"ns_per_tet\":%.2f,\"ns_per_tet_substep\":%.2f,"
           "\"allocations\":%ld,\"contact_ticks\":%ld,\"faults\":%u,\"dt\":%g,\"depth_m\":%g,\"rt\":%d",
           sub.median, sub.max, tets > 0 ? t.median / tets : 0.0,
           tets > 0 && sub.median > 0 ? t.median / (tets * sub.median) : 0.0, log.allocations, log.contact,
           log.faults, kHapticDt, kCostDepth, g_rt);
    if (with_sim) {
        const int kept = sim.steps < sim.capacity ? sim.steps : sim.capacity;
        const stats w = summarize(sim.ns, kept);
        printf(",\"sim_target_hz\":%g,\"sim_steps\":%d,\"sim_rate_hz\":%.2f,\"sim_step_median_ms\":%.3f,\"sim_step_max_ms\":%.3f,"
               "\"sim_failed\":%d,\"fresh_buffers\":%ld",
               1.0 / kSimDt, sim.steps, sim.steps / wall, w.median * 1e-6, w.max * 1e-6, sim.failed, log.fresh);
        free(sim.ns);
    }
    printf("}\n");
    fflush(stdout);
    fprintf(stderr, "%s: median %.2f us, p99.9 %.2f us, %d tets, %g sub-steps\n", name, t.median * 1e-3,
            t.p999 * 1e-3, tets, sub.median);
    tick_log_free(&log);
    CHECK(sh_haptic_destroy(haptic));
    scene_destroy(&s);
}

/* The fixed cost: the tool 1 m above the block, so the buffer is empty. */
static void overhead_case(const tissue* block) {
    const char* name = "haptic/overhead";
    if (!matches(name)) return;
    cost_path path;
    touch_point(block, path.touch);
    path.touch[2] += 1.0;
    scene s = scene_create(block, SH_MATERIAL_COROTATIONAL, SH_INTEGRATOR_SYMPLECTIC_EULER, kCostDamping, path.touch);
    const sh_haptic_def def = haptic_def_for(&s, 0.02, 2000, 0);
    sh_haptic* haptic = NULL;
    CHECK(sh_haptic_create(s.world, &def, &haptic));
    tick_log warm, log;
    memset(&warm, 0, sizeof warm);
    run_ticks(haptic, cost_pose, &path, 0, kWarmupTicks, 0, &warm);
    const int count = g_steps > 0 ? g_steps : kTimedTicks;
    tick_log_alloc(&log, count);
    run_ticks(haptic, cost_pose, &path, kWarmupTicks, count, 0, &log);
    const stats t = summarize(log.ns, log.timed);

    /* Batches: kBatch calls between two clock reads, at a fixed pose. */
    double batch[kBatches];
    double p[3];
    cost_pose(&path, kWarmupTicks, p);
    sh_haptic_output out;
    atomic_store(&g_allocations, 0);
    tl_counting = 1;
    for (int b = 0; b < kBatches; ++b) {
        const double t0 = now_ns();
        for (int i = 0; i < kBatch; ++i) sh_haptic_step(haptic, p, kIdentity, kHapticDt, &out);
        batch[b] = (now_ns() - t0) / kBatch;
    }
    tl_counting = 0;
    const long batch_allocations = atomic_load(&g_allocations);
    const stats bt = summarize(batch, kBatches);
    /* The clock read the per-call times include. */
    double clock[2000];
    for (int i = 0; i < 2000; ++i) {
        const double t0 = now_ns();
        clock[i] = now_ns() - t0;
    }
    const stats ct = summarize(clock, 2000);
    printf("{\"study\":\"haptic_overhead\",\"case\":\"%s\",\"buffer_tets\":%d,\"contact_ticks\":%ld,\"steps\":%d,"
           "\"median_ns\":%.1f,\"p99_ns\":%.1f,\"p999_ns\":%.1f,\"max_ns\":%.1f,\"mean_ns\":%.1f,"
           "\"batch_median_ns\":%.1f,\"batch_min_ns\":%.1f,\"batch\":%d,\"batches\":%d,\"clock_ns\":%.1f,"
           "\"allocations\":%ld,\"faults\":%u,\"rt\":%d}\n",
           name, log.last.buffer_tets, log.contact, t.count, t.median, t.p99, t.p999, t.max, t.mean, bt.median,
           batch[0], kBatch, kBatches, ct.median, log.allocations + batch_allocations, log.faults, g_rt);
    fflush(stdout);
    fprintf(stderr, "%s: median %.0f ns per call (%.0f ns in batches of %d)\n", name, t.median, bt.median, kBatch);
    tick_log_free(&log);
    CHECK(sh_haptic_destroy(haptic));
    scene_destroy(&s);
}

static int run_cost(void) {
    static const sh_material_model kModels[] = {SH_MATERIAL_COROTATIONAL, SH_MATERIAL_LINEAR, SH_MATERIAL_STVK,
                                                 SH_MATERIAL_NEOHOOKEAN};
    const int sizes = (int)(sizeof kCostSizes / sizeof kCostSizes[0]);
    tissue block = make_block();
    fprintf(stderr, "haptic: block %d tets, %d nodes (%d fixed); counting allocator installed\n", block.tet_count,
            block.node_count, block.fixed_count);
    overhead_case(&block);
    for (size_t m = 0; m < sizeof kModels / sizeof kModels[0]; ++m)
        for (int k = 0; k < sizes; ++k) cost_case(&block, kModels[m], kCostSizes[k], 0);
    for (size_t k = 0; k < sizeof kConcurrentSizes / sizeof kConcurrentSizes[0]; ++k)
        cost_case(&block, SH_MATERIAL_COROTATIONAL, kConcurrentSizes[k], 1);
    tissue_free(&block);
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* haptic-error: the VBM's force against the full model's static solve                          */

typedef struct {
    double touch[3];
} press_path;

/* Down kErrorDepth over kErrorPressTime, then held. */
static void error_pose(const void* ctx, long tick, double out[3]) {
    const press_path* c = (const press_path*)ctx;
    const double s = fmin(1.0, (tick + 1) * kHapticDt / kErrorPressTime);
    out[0] = c->touch[0];
    out[1] = c->touch[1];
    out[2] = c->touch[2] - kErrorDepth * s;
}

/* The reference: the full model solved statically with the tool pressed. */
static void error_reference(const tissue* liver, const double touch[3], double force[3]) {
    scene s = scene_create(liver, SH_MATERIAL_COROTATIONAL, SH_INTEGRATOR_SYMPLECTIC_EULER, 0.0, touch);
    const double pressed[3] = {touch[0], touch[1], touch[2] - kErrorDepth};
    CHECK(sh_tool_set_pose(s.world, s.tool, pressed, kIdentity));
    sh_static_def def;
    sh_static_def_default(&def);
    def.tolerance = 1e-9;
    sh_static_report report;
    const double t0 = now_ns();
    const sh_status st = sh_world_solve_static(s.world, &def, &report);
    const double ms = (now_ns() - t0) * 1e-6;
    if (st != SH_OK && st != SH_ERR_NOT_CONVERGED) CHECK(st);
    double torque[3];
    CHECK(sh_tool_get_wrench(s.world, s.tool, force, torque));
    sh_contact_state contact;
    CHECK(sh_tool_get_contact(s.world, s.tool, &contact));
    printf("{\"study\":\"haptic_error_reference\",\"mesh\":\"%s\",\"mesh_tets\":%d,\"fixed_nodes\":%d,"
           "\"depth_m\":%g,\"tool\":[%.6g,%.6g,%.6g],\"force\":[%.9g,%.9g,%.9g],\"contact_count\":%d,"
           "\"max_depth_m\":%.4g,\"converged\":%d,\"iterations\":%d,\"residual\":%.3g,\"solve_ms\":%.1f}\n",
           liver->name, liver->tet_count, liver->fixed_count, kErrorDepth, pressed[0], pressed[1], pressed[2],
           force[0], force[1], force[2], contact.contact_count, contact.max_depth, report.converged,
           report.iterations, report.residual, ms);
    fflush(stdout);
    fprintf(stderr, "haptic-error: static solve %.4g N (%s, %d iterations)\n", force[2],
            report.converged ? "converged" : "NOT converged", report.iterations);
    scene_destroy(&s);
}

static void error_case_name(char* name, size_t size, const char* mesh, int coupled, double radius) {
    snprintf(name, size, "haptic-error/%s/%s/r%.3f", mesh, coupled ? "coupled" : "frozen", radius);
}

static void error_case(const tissue* liver, const double touch[3], const double reference[3], double radius,
                       int coupled) {
    char name[128];
    error_case_name(name, sizeof name, liver->name, coupled, radius);
    if (!matches(name)) return;
    press_path path;
    memcpy(path.touch, touch, sizeof path.touch);
    scene s = scene_create(liver, SH_MATERIAL_COROTATIONAL,
                           coupled ? SH_INTEGRATOR_IMPLICIT_EULER : SH_INTEGRATOR_SYMPLECTIC_EULER, kErrorDamping,
                           touch);
    const sh_haptic_def def = haptic_def_for(&s, radius, liver->tet_count, 1);
    sh_haptic* haptic = NULL;
    CHECK(sh_haptic_create(s.world, &def, &haptic));
    const long ticks = (long)lround(kErrorTime / kHapticDt);
    const long timed_from = ticks - kErrorTimedTicks, settle_at = ticks - kSettleTicks;
    tick_log log, untimed;
    tick_log_alloc(&log, kErrorTimedTicks);
    memset(&untimed, 0, sizeof untimed);
    double settle_force[3] = {0.0, 0.0, 0.0};
    double sim_ns[256];
    int sim_steps = 0, sim_failed = 0;
    long next_sim = 1; /* world step k after tick ceil(k kSimDt / kHapticDt) */
    for (long i = 0; i < ticks; ++i) {
        tick_log* used = i >= timed_from ? &log : &untimed;
        run_ticks(haptic, error_pose, &path, i, 1, 0, used);
        if (i + 1 == settle_at)
            for (int k = 0; k < 3; ++k) settle_force[k] = used->last.raw_force[k];
        if (coupled && (i + 1) * kHapticDt >= next_sim * kSimDt - 1e-9) {
            const double t0 = now_ns();
            sim_failed += world_step(s.world);
            if (sim_steps < 256) sim_ns[sim_steps] = now_ns() - t0;
            ++sim_steps;
            ++next_sim;
        }
    }
    const sh_haptic_output out = log.last;
    double diff[3], change[3];
    for (int k = 0; k < 3; ++k) {
        diff[k] = out.raw_force[k] - reference[k];
        change[k] = out.raw_force[k] - settle_force[k];
    }
    const double ref = norm3(reference);
    const stats t = summarize(log.ns, log.timed);
    const stats sub = summarize(log.substeps, log.timed);
    printf("{\"study\":\"haptic_error\",\"case\":\"%s\",\"mode\":\"%s\",\"mesh\":\"%s\",\"radius_m\":%g,"
           "\"buffer_tets\":%d,\"buffer_nodes\":%d,\"mesh_tets\":%d,\"depth_m\":%g,\"force\":[%.9g,%.9g,%.9g],"
           "\"reference\":[%.9g,%.9g,%.9g],\"rel_error\":%.6g,\"rel_error_normal\":%.6g,\"settle_change\":%.3g,",
           name, coupled ? "coupled" : "frozen", liver->name, radius, out.buffer_tets, out.buffer_nodes,
           liver->tet_count, kErrorDepth, out.raw_force[0], out.raw_force[1], out.raw_force[2], reference[0],
           reference[1], reference[2], norm3(diff) / ref, diff[2] / reference[2], norm3(change) / ref);
    print_times_us("", &t);
    printf(",\"substeps_median\":%g,\"substeps_max\":%g,\"steps\":%d,\"contact\":%d,\"faults\":%u", sub.median,
           sub.max, t.count, out.contact, log.faults | untimed.faults);
    if (coupled) {
        double world_force[3], torque[3];
        CHECK(sh_tool_get_wrench(s.world, s.tool, world_force, torque));
        const stats w = summarize(sim_ns, sim_steps < 256 ? sim_steps : 256);
        printf(",\"world_force\":[%.9g,%.9g,%.9g],\"world_rel_error\":%.6g,\"sim_steps\":%d,\"sim_failed\":%d,"
               "\"sim_step_median_ms\":%.3f",
               world_force[0], world_force[1], world_force[2], distance3(world_force, reference) / ref, sim_steps,
               sim_failed, w.median * 1e-6);
    }
    printf("}\n");
    fflush(stdout);
    fprintf(stderr, "%s: %d tets, %.4g N against %.4g N (error %.3g), median %.2f us\n", name, out.buffer_tets,
            out.raw_force[2], reference[2], norm3(diff) / ref, t.median * 1e-3);
    tick_log_free(&log);
    CHECK(sh_haptic_destroy(haptic));
    scene_destroy(&s);
}

static int run_error(void) {
    for (size_t m = 0; m < sizeof kLivers / sizeof kLivers[0]; ++m) {
        int wanted = 0;
        for (int coupled = 0; coupled < 2; ++coupled)
            for (size_t r = 0; r < sizeof kErrorRadii / sizeof kErrorRadii[0]; ++r) {
                char name[128];
                error_case_name(name, sizeof name, kLivers[m].name, coupled, kErrorRadii[r]);
                wanted |= matches(name);
            }
        if (!wanted) continue;
        tissue liver;
        if (!make_liver(&liver, kLivers[m].file, kLivers[m].name)) return 1;
        double touch[3], reference[3];
        touch_point(&liver, touch);
        fprintf(stderr, "haptic-error: %s %d tets, %d fixed nodes; press at (%.4f, %.4f), touching height %.4f m\n",
                liver.name, liver.tet_count, liver.fixed_count, touch[0], touch[1], touch[2]);
        error_reference(&liver, touch, reference);
        for (int coupled = 0; coupled < 2; ++coupled)
            for (size_t r = 0; r < sizeof kErrorRadii / sizeof kErrorRadii[0]; ++r)
                error_case(&liver, touch, reference, kErrorRadii[r], coupled);
        tissue_free(&liver);
    }
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* haptic-force: the rendered force's smoothness, VBM against a ZOH of the full model           */

typedef struct {
    double start[2], direction[2];
    double heights[kPathSamples]; /* touching height of the tool's centre along the slide */
} slide_path;

static slide_path make_slide_path(const tissue* t) {
    slide_path p;
    for (int k = 0; k < 2; ++k) {
        p.start[k] = t->press[k];
        p.direction[k] = t->slide[k];
    }
    for (int s = 0; s < kPathSamples; ++s) {
        const double along = kTraceSlide * s / (kPathSamples - 1);
        p.heights[s] = touch_height(t, p.start[0] + along * p.direction[0], p.start[1] + along * p.direction[1]);
    }
    return p;
}

/* The trajectory at tick i (time (i + 1) kHapticDt): see the header. */
static void trace_pose(const void* ctx, long tick, double out[3]) {
    const slide_path* p = (const slide_path*)ctx;
    const double t = (tick + 1) * kHapticDt;
    double below;
    if (t < kApproachEnd)
        below = -kTraceGap * (1.0 - ease(t / kApproachEnd));
    else if (t < kLiftStart)
        below = kTraceDepth * ease((t - kApproachEnd) / (kPressEnd - kApproachEnd));
    else
        below = kTraceDepth - (kTraceDepth + kTraceGap) * ease((t - kLiftStart) / (kLiftEnd - kLiftStart));
    const double slide = ease((t - kSlideStart) / (kSlideEnd - kSlideStart));
    const double s = slide * (kPathSamples - 1);
    int k = (int)s;
    if (k > kPathSamples - 2) k = kPathSamples - 2;
    const double h = p->heights[k] + (s - k) * (p->heights[k + 1] - p->heights[k]);
    out[0] = p->start[0] + slide * kTraceSlide * p->direction[0];
    out[1] = p->start[1] + slide * kTraceSlide * p->direction[1];
    out[2] = h - below;
}

/* Max and RMS of |F(i) - F(i-1)| over ticks [begin, end) of f (3 per tick). */
static void force_steps(const double* f, long begin, long end, double* max, double* rms) {
    double sum = 0.0;
    *max = 0.0;
    long n = 0;
    for (long i = begin > 0 ? begin : 1; i < end; ++i, ++n) {
        const double d = distance3(&f[3 * i], &f[3 * (i - 1)]);
        if (d > *max) *max = d;
        sum += d * d;
    }
    *rms = n > 0 ? sqrt(sum / n) : 0.0;
}

static int run_force(void) {
    tissue liver;
    if (!make_liver(&liver, kTraceLiver.file, kTraceLiver.name)) return 1;
    const slide_path path = make_slide_path(&liver);
    double start[3];
    trace_pose(&path, -1, start);
    scene s = scene_create(&liver, SH_MATERIAL_COROTATIONAL, SH_INTEGRATOR_IMPLICIT_EULER, kTraceDamping, start);
    sh_haptic_def def = haptic_def_for(&s, kTraceRadius, 2000, 0);
    def.stale_after = 0.1; /* the default: the world steps every 1/60 s here */
    sh_haptic* haptic = NULL;
    CHECK(sh_haptic_create(s.world, &def, &haptic));
    const long ticks = (long)lround(kTraceEnd / kHapticDt);
    double* pos = (double*)xmalloc(sizeof(double) * 3 * (size_t)ticks);
    double* vbm = (double*)xmalloc(sizeof(double) * 3 * (size_t)ticks);
    double* raw = (double*)xmalloc(sizeof(double) * 3 * (size_t)ticks);
    double* zoh = (double*)xmalloc(sizeof(double) * 3 * (size_t)ticks);
    int32_t* tets = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)ticks);
    int32_t* substeps = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)ticks);
    int32_t* contact = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)ticks);
    double sim_ns[512];
    int sim_steps = 0, sim_failed = 0;
    double held[3] = {0.0, 0.0, 0.0};
    long next_sim = 1;
    tick_log log;
    tick_log_alloc(&log, (int)ticks);
    for (long i = 0; i < ticks; ++i) {
        run_ticks(haptic, trace_pose, &path, i, 1, 0, &log);
        trace_pose(&path, i, &pos[3 * i]);
        for (int k = 0; k < 3; ++k) {
            vbm[3 * i + k] = log.last.force[k];
            raw[3 * i + k] = log.last.raw_force[k];
        }
        tets[i] = log.last.buffer_tets;
        substeps[i] = log.last.substeps;
        contact[i] = log.last.contact;
        if ((i + 1) * kHapticDt >= next_sim * kSimDt - 1e-9) {
            const double t0 = now_ns();
            sim_failed += world_step(s.world);
            if (sim_steps < 512) sim_ns[sim_steps] = now_ns() - t0;
            ++sim_steps;
            ++next_sim;
            double torque[3];
            CHECK(sh_tool_get_wrench(s.world, s.tool, held, torque));
        }
        for (int k = 0; k < 3; ++k) zoh[3 * i + k] = held[k];
    }
    if (g_csv) {
        FILE* f = fopen(g_csv, "w");
        if (!f) {
            fprintf(stderr, "softhap_bench: cannot write %s\n", g_csv);
            return 1;
        }
        fprintf(f, "t,tool_x,tool_y,tool_z,vbm_x,vbm_y,vbm_z,raw_x,raw_y,raw_z,zoh_x,zoh_y,zoh_z,buffer_tets,"
                   "substeps,contact,step_us\n");
        for (long i = 0; i < ticks; ++i)
            fprintf(f, "%.4f,%.6f,%.6f,%.6f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%d,%d,%.2f\n",
                    (i + 1) * kHapticDt, pos[3 * i], pos[3 * i + 1], pos[3 * i + 2], vbm[3 * i], vbm[3 * i + 1],
                    vbm[3 * i + 2], raw[3 * i], raw[3 * i + 1], raw[3 * i + 2], zoh[3 * i], zoh[3 * i + 1],
                    zoh[3 * i + 2], tets[i], substeps[i], contact[i], log.ns[i] * 1e-3);
        fclose(f);
    }
    const long slide_begin = (long)lround(kSlideStart / kHapticDt), slide_end = (long)lround(kSlideEnd / kHapticDt);
    static const char* const kSignals[] = {"vbm", "vbm_raw", "zoh"};
    const double* signals[] = {vbm, raw, zoh};
    for (int k = 0; k < 3; ++k) {
        double max_all, rms_all, max_slide, rms_slide, peak = 0.0;
        force_steps(signals[k], 0, ticks, &max_all, &rms_all);
        force_steps(signals[k], slide_begin, slide_end, &max_slide, &rms_slide);
        for (long i = 0; i < ticks; ++i)
            if (norm3(&signals[k][3 * i]) > peak) peak = norm3(&signals[k][3 * i]);
        printf("{\"study\":\"haptic_force\",\"signal\":\"%s\",\"max_dF_N\":%.6g,\"rms_dF_N\":%.6g,"
               "\"max_dF_slide_N\":%.6g,\"rms_dF_slide_N\":%.6g,\"peak_N\":%.6g,\"ticks\":%ld}\n",
               kSignals[k], max_all, rms_all, max_slide, rms_slide, peak, ticks);
        fprintf(stderr, "haptic-force %s: max |dF| %.4g N, RMS |dF| %.4g N per tick (slide: %.4g, %.4g), peak %.4g N\n",
                kSignals[k], max_all, rms_all, max_slide, rms_slide, peak);
    }
    const stats t = summarize(log.ns, log.timed); /* sorts: the trace is written */
    const stats w = summarize(sim_ns, sim_steps < 512 ? sim_steps : 512);
    long tet_sum = 0, in_contact = 0;
    for (long i = 0; i < ticks; ++i) {
        tet_sum += tets[i];
        in_contact += contact[i];
    }
    printf("{\"study\":\"haptic_force_run\",\"mesh\":\"%s\",\"radius_m\":%g,\"ticks\":%ld,\"sim_steps\":%d,"
           "\"slide\":[%.4f,%.4f],\"press\":[%.5f,%.5f],\"mean_buffer_tets\":%.1f,\"contact_ticks\":%ld,",
           liver.name, kTraceRadius, ticks, sim_steps, path.direction[0], path.direction[1], path.start[0],
           path.start[1], (double)tet_sum / ticks, in_contact);
    print_times_us("", &t);
    printf(",\"sim_step_median_ms\":%.3f,\"sim_step_max_ms\":%.3f,\"sim_failed\":%d,\"allocations\":%ld,\"faults\":%u,"
           "\"csv\":\"%s\"}\n",
           w.median * 1e-6, w.max * 1e-6, sim_failed, log.allocations, log.faults, g_csv ? g_csv : "");
    fflush(stdout);
    free(pos);
    free(vbm);
    free(raw);
    free(zoh);
    free(tets);
    free(substeps);
    free(contact);
    tick_log_free(&log);
    CHECK(sh_haptic_destroy(haptic));
    scene_destroy(&s);
    tissue_free(&liver);
    return 0;
}

/* ------------------------------------------------------------------------------------------ */

/* The 1-minute load average (-1 if unknown). */
static double load_average(void) {
    double load = -1.0;
    FILE* f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &load) != 1) load = -1.0;
        fclose(f);
    }
    return load;
}

int is_haptic_command(const char* name) {
    return strcmp(name, "haptic") == 0 || strcmp(name, "haptic-error") == 0 || strcmp(name, "haptic-force") == 0;
}

static void usage(void) {
    fprintf(stderr, "usage: softhap_bench haptic [FILTER] [--steps N] [--rt] [--meshes DIR]\n"
                    "       softhap_bench haptic-error [FILTER] [--meshes DIR]\n"
                    "       softhap_bench haptic-force [--csv PATH] [--meshes DIR]\n");
}

int run_haptic(int argc, char** argv) {
    const char* command = argv[0];
    const char* given_dir = NULL;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--steps") == 0 && i + 1 < argc) {
            g_steps = atoi(argv[++i]);
            if (g_steps < 1) {
                usage();
                return 2;
            }
        } else if (strcmp(argv[i], "--meshes") == 0 && i + 1 < argc) {
            given_dir = argv[++i];
        } else if (strcmp(argv[i], "--rt") == 0) {
            g_rt = 1;
        } else if (strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
            g_csv = argv[++i];
        } else {
            const int code = bench_filter_arg(argv[i], &g_filter, usage);
            if (code >= 0) return code;
        }
    }
    if (strcmp(command, "haptic") != 0) {
        g_mesh_dir = bench_find_mesh_dir(given_dir, "liver.msh");
        if (!g_mesh_dir) {
            fprintf(stderr, "softhap_bench: meshes not found; pass --meshes DIR\n");
            return 1;
        }
    }
    /* Count from the start: the allocator cannot change while softhap objects live. */
    const sh_allocator allocator = {counting_alloc, counting_free, NULL};
    CHECK(sh_set_allocator(&allocator));
    choose_cpus();
    pin_self(g_haptic_cpu);
    if (g_rt) {
        struct sched_param rt;
        memset(&rt, 0, sizeof rt);
        rt.sched_priority = 10;
        g_rt = pthread_setschedparam(pthread_self(), SCHED_FIFO, &rt) == 0;
        fprintf(stderr, "softhap_bench: --rt: SCHED_FIFO %s\n", g_rt ? "granted" : "refused (timings as usual)");
    }
    const double load_before = load_average(), t0 = now_ns();
    int code;
    if (strcmp(command, "haptic") == 0)
        code = run_cost();
    else if (strcmp(command, "haptic-error") == 0)
        code = run_error();
    else
        code = run_force();
    CHECK(sh_set_allocator(NULL));
    printf("{\"study\":\"haptic_env\",\"command\":\"%s\",\"version\":%d,\"seconds\":%.1f,\"load_before\":%.2f,"
           "\"load_after\":%.2f,\"haptic_cpu\":%d,\"sim_cpu\":%d,\"rt\":%d}\n",
           command, (int)sh_version(), (now_ns() - t0) * 1e-9, load_before, load_average(), g_haptic_cpu, g_other_cpu,
           g_rt);
    return code;
}
