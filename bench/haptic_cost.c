/* softhap_bench haptic: the haptic step's cost against buffer size, with the world frozen or
 * stepped by a sim thread beside it, and the step's fixed cost (haptic.c describes the cases). */
#include "haptic_common.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const int kCostSizes[] = {50, 100, 200, 500, 1000, 2000};
static const int kConcurrentSizes[] = {50, 200, 500, 2000};
/* The rate cases: buffer sizes, device rates (Hz), and the tools' Hunt-Crossley stiffness
 * (N/m^1.5): the default sphere and one 20 times stiffer (as examples/haptic_loop uses). */
static const int kRateSizes[] = {50, 200, 500, 2000};
static const int kRates[] = {1000, 10000};
static const struct {
    const char* name;
    double stiffness;
} kRateTools[] = {{"soft", 1e4}, {"stiff", 2e5}};
static const double kCostDepth = 0.003;  /* m */
static const double kCostCircle = 0.001; /* m, once a second */
static const double kCostDamping = 5.0;  /* 1/s */
static const double kPressTime = 0.3, kWarmupTime = 2.0; /* s */
static const int kWarmupTicks = 2000, kPacedTicks = 5000;
/* Timed ticks: corotational (the headline), the other materials (for their kernels' cost). */
static const int kTimedTicks = 20000, kOtherTimedTicks = 5000;
enum { kBatch = 100, kBatches = 200, kClockReads = 2000 };
enum { kSimCapacity = 4096 }; /* sim step times kept */

/* ------------------------------------------------------------------------------------------ */
/* The device's path                                                                            */

typedef struct {
    double touch[3];
    double dt; /* s per tick */
} cost_path;

/* Pressed kCostDepth over kPressTime, then a circle of kCostCircle once a second: the contact
 * keeps moving, so every step solves a changing contact. */
static void cost_pose(const void* ctx, long tick, double out[3]) {
    const cost_path* c = (const cost_path*)ctx;
    const double t = (tick + 1.0) * c->dt;
    const double press = fmin(1.0, t / kPressTime);
    const double a = t > kPressTime ? 2.0 * kPi * (t - kPressTime) : 0.0;
    out[0] = c->touch[0] + kCostCircle * (cos(a) - 1.0);
    out[1] = c->touch[1] + kCostCircle * sin(a);
    out[2] = c->touch[2] - kCostDepth * press;
}

/* ------------------------------------------------------------------------------------------ */
/* The sim thread of the concurrent cases                                                       */

typedef struct {
    sh_world* world;
    int cpu;  /* the CPU it keeps */
    int rt;   /* the haptic thread is real-time: this one must not inherit that */
    atomic_int stop;
    int steps, capacity, failed;
    double* ns;
    pthread_t thread;
} sim_runner;

/* Steps the world by kSimDt at most once per kSimDt of wall time until told to stop; when
 * behind it does not catch up (a host's sim thread drops frames). */
static void* sim_main(void* arg) {
    sim_runner* r = (sim_runner*)arg;
    bench_pin_thread(r->cpu);
    if (r->rt) make_ordinary();
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
            deadline = now;
    }
    return NULL;
}

/* Starts the sim thread on world. */
static void sim_start(sim_runner* sim, sh_world* world, const haptic_options* options) {
    memset(sim, 0, sizeof *sim);
    sim->world = world;
    sim->cpu = options->sim_cpu;
    sim->rt = options->rt;
    sim->capacity = kSimCapacity;
    sim->ns = (double*)xmalloc(sizeof(double) * (size_t)sim->capacity);
    atomic_store(&sim->stop, 0);
    if (pthread_create(&sim->thread, NULL, sim_main, sim) != 0) {
        fprintf(stderr, "softhap_bench: cannot start the sim thread\n");
        exit(1);
    }
}

/* Stops the sim thread and waits for it. */
static void sim_stop(sim_runner* sim) {
    atomic_store(&sim->stop, 1);
    pthread_join(sim->thread, NULL);
}

/* ------------------------------------------------------------------------------------------ */
/* One buffer size                                                                              */

/* One cost case: the buffer's material and capacity, with or without the sim thread, the
 * device's step and the tool's stiffness. */
typedef struct {
    char name[128];
    sh_material_model model;
    int capacity;
    int with_sim;
    double dt;        /* s */
    double stiffness; /* the tool's Hunt-Crossley stiffness (N/m^1.5) */
} cost_setup;

/* How many ticks a cost case times: --steps N (a quarter of it paced beside the sim thread),
 * else the case's default. */
static int cost_ticks(const haptic_options* options, const cost_setup* c) {
    if (c->with_sim) return options->steps > 0 ? options->steps / 4 : kPacedTicks;
    if (options->steps > 0) return options->steps;
    return c->model == SH_MATERIAL_COROTATIONAL && c->dt == kHapticDt ? kTimedTicks : kOtherTimedTicks;
}

/* The sim thread's fields of a concurrent case's JSON line. */
static void print_sim_fields(const sim_runner* sim, double wall, long fresh) {
    const int kept = sim->steps < sim->capacity ? sim->steps : sim->capacity;
    const stats w = summarize(sim->ns, kept);
    printf(",\"sim_target_hz\":%g,\"sim_steps\":%d,\"sim_rate_hz\":%.2f,\"sim_step_median_ms\":%.3f,\"sim_step_max_ms\":%.3f,"
           "\"sim_failed\":%d,\"fresh_buffers\":%ld",
           1.0 / kSimDt, sim->steps, sim->steps / wall, w.median * 1e-6, w.max * 1e-6, sim->failed, fresh);
}

/* A cost case's JSON line (sorts the log's samples; sim NULL: frozen) and its summary on
 * stderr. */
static void print_cost(const cost_setup* c, const tissue* block, tick_log* log, const sim_runner* sim, double wall,
                       int rt) {
    const stats sub = summarize(log->substeps, log->timed);
    const stats t = summarize(log->ns, log->timed);
    const int tets = log->last.buffer_tets;
    printf("{\"study\":\"haptic_cost\",\"case\":\"%s\",\"material\":\"%s\",\"sim\":\"%s\",\"capacity_tets\":%d,"
           "\"buffer_tets\":%d,\"buffer_nodes\":%d,\"mesh_tets\":%d,\"steps\":%d,",
           c->name, material_name(c->model), sim ? "sim" : "frozen", c->capacity, tets, log->last.buffer_nodes,
           block->tet_count, t.count);
    print_times_us("", &t);
    printf(",\"substeps_median\":%g,\"substeps_max\":%g,\"ns_per_tet\":%.2f,\"ns_per_tet_substep\":%.2f,"
           "\"allocations\":%ld,\"contact_ticks\":%ld,\"faults\":%u,\"dt\":%g,\"tool_stiffness\":%g,"
           "\"depth_m\":%g,\"rt\":%d",
           sub.median, sub.max, tets > 0 ? t.median / tets : 0.0,
           tets > 0 && sub.median > 0 ? t.median / (tets * sub.median) : 0.0, log->allocations, log->contact,
           log->faults, c->dt, c->stiffness, kCostDepth, rt);
    if (sim) print_sim_fields(sim, wall, log->fresh);
    printf("}\n");
    fflush(stdout);
    fprintf(stderr, "%s: median %.2f us, p99.9 %.2f us, %d tets, %g sub-steps\n", c->name, t.median * 1e-3,
            t.p999 * 1e-3, tets, sub.median);
}

/* The case's scene and haptic context (the tool at the touch point, path->touch). */
static scene cost_scene(const tissue* block, const cost_setup* c, cost_path* path, sh_haptic** haptic) {
    touch_point(block, path->touch);
    path->dt = c->dt;
    sh_collider_def tool = bench_sphere_def(kToolRadius, path->touch);
    tool.contact.stiffness = c->stiffness;
    scene s = scene_create_with_tool(
        block, c->model, c->with_sim ? SH_INTEGRATOR_IMPLICIT_EULER : SH_INTEGRATOR_SYMPLECTIC_EULER, kCostDamping,
        &tool);
    sh_haptic_def def = haptic_def_for(&s, 1.0, c->capacity, 0);
    def.dt = c->dt;
    CHECK(sh_haptic_create(s.world, &def, haptic));
    if (c->with_sim) world_step(s.world); /* the implicit solver's set-up */
    return s;
}

/* One case: the press and a warm-up untimed, then the timed ticks, back to back with the world
 * frozen, or paced at the device's rate beside the sim thread. */
static void cost_case(const tissue* block, const cost_setup* c, const haptic_options* options) {
    if (!name_matches(c->name, options->filter)) return;
    cost_path path;
    sh_haptic* haptic = NULL;
    scene s = cost_scene(block, c, &path, &haptic);
    tick_log warm, log;
    memset(&warm, 0, sizeof warm);
    const long untimed = lround((kPressTime + kWarmupTime) / c->dt);
    run_ticks(haptic, cost_pose, &path, 0, untimed, c->dt, 0, &warm);
    const int count = cost_ticks(options, c);
    tick_log_alloc(&log, count);
    sim_runner sim;
    memset(&sim, 0, sizeof sim);
    if (c->with_sim) sim_start(&sim, s.world, options);
    const double t0 = now_ns();
    run_ticks(haptic, cost_pose, &path, untimed, count, c->dt, c->with_sim, &log);
    const double wall = (now_ns() - t0) * 1e-9;
    if (c->with_sim) sim_stop(&sim);
    print_cost(c, block, &log, c->with_sim ? &sim : NULL, wall, options->rt);
    if (c->with_sim) free(sim.ns);
    tick_log_free(&log);
    CHECK(sh_haptic_destroy(haptic));
    scene_destroy(&s);
}

/* The default tool at 1 kHz: "haptic/<frozen|sim>/<material>/<capacity>". */
static cost_setup material_setup(sh_material_model model, int capacity, int with_sim) {
    cost_setup c;
    sh_collider_def tool;
    sh_collider_def_default(&tool);
    snprintf(c.name, sizeof c.name, "haptic/%s/%s/%d", with_sim ? "sim" : "frozen", material_name(model), capacity);
    c.model = model;
    c.capacity = capacity;
    c.with_sim = with_sim;
    c.dt = kHapticDt;
    c.stiffness = tool.contact.stiffness;
    return c;
}

/* Corotational, frozen, at rate_hz under the tool named tool (kRateTools):
 * "haptic/rate/<rate_hz>hz/<tool>/<capacity>". */
static cost_setup rate_setup(int rate_hz, int tool, int capacity) {
    cost_setup c = material_setup(SH_MATERIAL_COROTATIONAL, capacity, 0);
    snprintf(c.name, sizeof c.name, "haptic/rate/%dhz/%s/%d", rate_hz, kRateTools[tool].name, capacity);
    c.dt = 1.0 / rate_hz;
    c.stiffness = kRateTools[tool].stiffness;
    return c;
}

/* ------------------------------------------------------------------------------------------ */
/* The fixed cost                                                                               */

/* kBatches batches of kBatch steps at the pose p, each batch timed as a whole (no clock read
 * per call): each batch's mean per call into batch[]; the allocations counted. */
static long time_batches(sh_haptic* haptic, const double p[3], double batch[kBatches]) {
    sh_haptic_output out;
    alloc_count_on();
    for (int b = 0; b < kBatches; ++b) {
        const double t0 = now_ns();
        for (int i = 0; i < kBatch; ++i) sh_haptic_step(haptic, p, kIdentity, kHapticDt, &out);
        batch[b] = (now_ns() - t0) / kBatch;
    }
    return alloc_count_off();
}

/* The median time of one clock read (ns), which every per-call time includes. */
static double clock_read_ns(void) {
    double clock[kClockReads];
    for (int i = 0; i < kClockReads; ++i) {
        const double t0 = now_ns();
        clock[i] = now_ns() - t0;
    }
    return summarize(clock, kClockReads).median;
}

/* The fixed cost: the tool 1 m above the block, so the buffer is empty and the step renders the
 * untouched proxy plane; per-call times, then batches. */
static void overhead_case(const tissue* block, const haptic_options* options) {
    const char* name = "haptic/overhead";
    if (!name_matches(name, options->filter)) return;
    cost_path path;
    touch_point(block, path.touch);
    path.touch[2] += 1.0;
    path.dt = kHapticDt;
    scene s = scene_create(block, SH_MATERIAL_COROTATIONAL, SH_INTEGRATOR_SYMPLECTIC_EULER, kCostDamping, path.touch);
    const sh_haptic_def def = haptic_def_for(&s, 0.02, 2000, 0);
    sh_haptic* haptic = NULL;
    CHECK(sh_haptic_create(s.world, &def, &haptic));
    tick_log warm, log;
    memset(&warm, 0, sizeof warm);
    run_ticks(haptic, cost_pose, &path, 0, kWarmupTicks, kHapticDt, 0, &warm);
    const int count = options->steps > 0 ? options->steps : kTimedTicks;
    tick_log_alloc(&log, count);
    run_ticks(haptic, cost_pose, &path, kWarmupTicks, count, kHapticDt, 0, &log);
    const stats t = summarize(log.ns, log.timed);
    double batch[kBatches], p[3];
    cost_pose(&path, kWarmupTicks, p);
    const long batch_allocations = time_batches(haptic, p, batch);
    const stats bt = summarize(batch, kBatches);
    const double clock_ns = clock_read_ns();
    printf("{\"study\":\"haptic_overhead\",\"case\":\"%s\",\"buffer_tets\":%d,\"contact_ticks\":%ld,\"steps\":%d,"
           "\"median_ns\":%.1f,\"p99_ns\":%.1f,\"p999_ns\":%.1f,\"max_ns\":%.1f,\"mean_ns\":%.1f,"
           "\"batch_median_ns\":%.1f,\"batch_min_ns\":%.1f,\"batch\":%d,\"batches\":%d,\"clock_ns\":%.1f,"
           "\"allocations\":%ld,\"faults\":%u,\"rt\":%d}\n",
           name, log.last.buffer_tets, log.contact, t.count, t.median, t.p99, t.p999, t.max, t.mean, bt.median,
           batch[0], kBatch, kBatches, clock_ns, log.allocations + batch_allocations, log.faults, options->rt);
    fflush(stdout);
    fprintf(stderr, "%s: median %.0f ns per call (%.0f ns in batches of %d)\n", name, t.median, bt.median, kBatch);
    tick_log_free(&log);
    CHECK(sh_haptic_destroy(haptic));
    scene_destroy(&s);
}

/* ------------------------------------------------------------------------------------------ */

/* The machine's own tail under a step of a given length: a chain of dependent multiply-adds
 * (no memory, no calls, nothing to vary) timed like a tick, back to back, its length calibrated
 * so that its median is target_us. Its p99.9 and max are what interrupts and other processes
 * add to any step that long on this machine: the floor under a haptic step's tail. */
static volatile double work_sink = 1.0; /* read and written, so the chain is done */

static void fixed_work(long length) {
    double a = work_sink;
    for (long k = 0; k < length; ++k) a = a * 1.0000001 + 1e-9;
    work_sink = a;
}

static double median_of_work(long length, int count, double* ns) {
    for (int i = 0; i < count; ++i) {
        const double t0 = now_ns();
        fixed_work(length);
        ns[i] = now_ns() - t0;
    }
    return summarize(ns, count).median;
}

static void machine_case(double target_us, const haptic_options* options) {
    char name[64];
    snprintf(name, sizeof name, "haptic/machine/%gus", target_us);
    if (!name_matches(name, options->filter)) return;
    const int count = options->steps > 0 ? options->steps : kTimedTicks;
    enum { kCalibration = 2000 }; /* calls per calibration round */
    double* ns = malloc((size_t)(count > kCalibration ? count : kCalibration) * sizeof(double));
    if (!ns) {
        fprintf(stderr, "%s: out of memory\n", name);
        return;
    }
    long length = 10000;
    for (int round = 0; round < 3; ++round)  /* the loop's speed is the machine's: scale to it */
        length = (long)(length * target_us * 1e3 / median_of_work(length, kCalibration, ns));
    median_of_work(length, count, ns);
    const stats t = summarize(ns, count);
    printf("{\"study\":\"haptic_machine\",\"case\":\"%s\",\"steps\":%d,\"multiply_adds\":%ld,", name, t.count, length);
    print_times_us("", &t);
    printf(",\"rt\":%d}\n", options->rt);
    fflush(stdout);
    fprintf(stderr, "%s: a fixed %.1f us of arithmetic: p99.9 %.2f us, max %.2f us\n", name, t.median * 1e-3,
            t.p999 * 1e-3, t.max * 1e-3);
    free(ns);
}

/* The overhead, the machine's tail, every material at every buffer size frozen, the rate
 * cases, then corotational beside the sim thread. */
int haptic_run_cost(const haptic_options* options) {
    static const sh_material_model kModels[] = {SH_MATERIAL_COROTATIONAL, SH_MATERIAL_LINEAR, SH_MATERIAL_STVK,
                                                 SH_MATERIAL_NEOHOOKEAN};
    const int sizes = (int)(sizeof kCostSizes / sizeof kCostSizes[0]);
    tissue block = make_block();
    fprintf(stderr, "haptic: block %d tets, %d nodes (%d fixed); counting allocator installed\n", block.tet_count,
            block.node_count, block.fixed_count);
    overhead_case(&block, options);
    machine_case(15.0, options);
    machine_case(25.0, options);
    for (size_t m = 0; m < sizeof kModels / sizeof kModels[0]; ++m)
        for (int k = 0; k < sizes; ++k) {
            const cost_setup c = material_setup(kModels[m], kCostSizes[k], 0);
            cost_case(&block, &c, options);
        }
    for (size_t r = 0; r < sizeof kRates / sizeof kRates[0]; ++r)
        for (int tool = 0; tool < (int)(sizeof kRateTools / sizeof kRateTools[0]); ++tool)
            for (size_t k = 0; k < sizeof kRateSizes / sizeof kRateSizes[0]; ++k) {
                const cost_setup c = rate_setup(kRates[r], tool, kRateSizes[k]);
                cost_case(&block, &c, options);
            }
    for (size_t k = 0; k < sizeof kConcurrentSizes / sizeof kConcurrentSizes[0]; ++k) {
        const cost_setup c = material_setup(SH_MATERIAL_COROTATIONAL, kConcurrentSizes[k], 1);
        cost_case(&block, &c, options);
    }
    tissue_free(&block);
    return 0;
}
