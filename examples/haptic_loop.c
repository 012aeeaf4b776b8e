/* haptic_loop.c: a fixed-timestep haptic host. A simulated device thread renders the liver's
 * force through a haptic context (sh_haptic_step) at 1 kHz and then at 10 kHz, while a sim
 * thread steps the full model at 60 Hz (sh_world_step); it reports the force trace and how well
 * each loop kept its deadlines.
 *
 *   haptic_loop [mesh]   (default ../shared/meshes/liver.msh)
 *
 * `make haptic-loop` runs it from the repository root (about 9 s: the setup, then two runs of 4 s).
 *
 * The scene (liver_scene.h): the 16 cm, 550 g liver (corotational, E = 15 kPa, nu = 0.45)
 * settled on a table, integrated by implicit (backward) Euler at the full-model step of 1/60 s
 * (symplectic Euler would need about 150 sub-steps per 1/60 s, far over a 60 Hz budget).
 * Implicit Euler does not yet converge with friction on the table (see palpation.c), so the
 * table is frictionless and the liver's base (its nodes within 3 mm of the table) is fixed to
 * it instead. The tool is a sphere of radius 1 cm with Coulomb friction (mu_s = 0.3,
 * mu_d = 0.2) and a Hunt-Crossley stiffness of 2e5 N/m^1.5, a fifth of palpation.c's: a sampled
 * haptic loop stays passive only below a stiffness of about 2 b / T (Colgate and Schenkel; b the
 * hand's damping, T the device period: 18 kN/m at 1 kHz), and at 1e6 N/m^1.5 (47 kN/m at 1 mm) a
 * 1 kHz run over a 2.5 cm slide chattered into roll-backs of the buffer past a convex edge of the
 * coarse surface. A haptic context with the default buffer (the tets within 2 cm of the
 * contact, the force clamped to 10 N and 2000 N/s) renders the force; full-model data older than
 * 0.25 s is stale (the default 0.1 s is shorter than the slowest full-model steps here, where
 * Newton iterates up to 40 times in contact). The full model's steps that fail
 * (SH_ERR_NOT_CONVERGED: the body stays as it was) are counted, not fatal.
 *
 * The device. A hand of 0.1 kg holding the device follows a scripted target through a spring
 * of 200 N/m and a damper of 8.9 N s/m (critical for the hand's mass), and feels the rendered
 * force: m a = k (target - x) + c (target' - x') + force. The device position handed to
 * sh_haptic_step is the hand's position; the hand is integrated by symplectic Euler at the
 * device rate. The target (t from the start of a run, along the path of liver_scene.h):
 *
 *   approach  0.0 - 0.3 s   from 1 cm above the height where the tool would touch the
 *                           settled surface down to it
 *   press     0.3 - 1.3 s   10 mm further down at constant speed
 *   slide     1.3 - 3.3 s   2 cm sideways at constant speed, 10 mm below the touching height
 *   lift      3.3 - 3.7 s   back up to 1 cm above the touching height
 *   rest      3.7 - 4.0 s
 *
 * The tissue pushes back, so the hand lags its target and goes less deep than 10 mm (about 4 mm
 * at the end of the press, with 1.3 N).
 *
 * Timing. Each loop runs on absolute deadlines (CLOCK_MONOTONIC): the device thread sleeps with
 * clock_nanosleep(TIMER_ABSTIME) until 50 us before its next deadline (waking up takes tens of
 * microseconds on a loaded machine) and spins for the rest; the sim thread only sleeps. A loop
 * that falls more than two periods behind drops the deadlines it missed (counted) instead of
 * running a burst of late steps: the device's time stays the wall clock's, the hand moves on
 * through the dropped ticks holding the last force (as a device holds its last command) and the
 * next haptic step covers up to four ticks' time with a longer dt. A longer stall's time is not
 * simulated (counted): a step covering all of it would sub-step for as long as the stall was
 * long, run past its own deadline and make the next tick late too. The full model only falls
 * behind (its data ages). The device thread asks for SCHED_FIFO and a 1 ns timer slack; without the privilege
 * (CAP_SYS_NICE or an rtprio limit) it says so on stderr and runs at normal priority. Everything
 * the device thread writes is allocated and touched before the run, and it never prints (the
 * trace is kept in memory and written after each run). A production host would also lock its
 * memory (mlockall), pin the device thread to an isolated core and keep CHOLMOD's OpenMP on the
 * sim thread (OMP_THREAD_LIMIT=1).
 *
 * Output. stdout: CSV with the header
 *   rate_hz,t,x,y,z,force_x,force_y,force_z,contact,buffer_tets,data_age,faults
 * one row per tick at 1 kHz and per 10th tick at 10 kHz: the device rate; t in s from the
 * start of the run (ticks times the period); the device position in m; the rendered force on
 * the device in N (world frame, +z up); 1 while the tool touches; the tets in the buffer; the
 * age of the newest full-model data in s; the sh_haptic_fault bits. stderr: the setup, then per
 * rate a summary: the lateness of each tick's start after its deadline (p50, p99, p99.9, max),
 * the time of sh_haptic_step (p50, p99.9, max), the full model's step time (p50, p99, max), the
 * buffer's size, the force and the hand's depth, the ticks with each fault and the context's
 * warning counters. The figures are informational: this is a shared machine, not a real-time
 * one.
 *
 * What you see (2 shared cores, SCHED_FIFO permitted): the force is 0 until the tool touches
 * at about 0.27 s and grows to 1.3 N by the end of the press, the hand 3.7 mm into the tissue;
 * while sliding it is about 0.6 N against the motion (friction and the rising slope) and 1.1 N
 * up, at most about 1.6 N; after lift-off it is 0 again. Both rates give the same trace. The
 * lateness is p99 5-80 us and p99.9 0.05-1 ms, sh_haptic_step takes about 20 us (p50, about 7
 * sub-steps) at 1 kHz and 5 us at 10 kHz; the full model takes 2-5 ms a step (p50) but 30-90 ms
 * when Newton iterates in contact, and a few such steps fail. At normal priority the lateness
 * tail grows to milliseconds and 10 kHz drops 10-15% of its deadlines.
 *
 * Exit status: 0 on success; 1 if a call fails or a force is not finite. */
#define _GNU_SOURCE
#include "liver_scene.h"
#include "simulated_hand.h"

#include <softhap/softhap.h>

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <time.h>
#include <unistd.h>

#define CHECK(call) EXAMPLE_CHECK("haptic_loop", call)

static const double kModelRate = 60.0;     /* full-model steps per second */
static const double kRunTime = 4.0;        /* s per device rate */
static const double kToolRadius = 0.01;    /* m */
static const double kGap = 0.01;           /* start and end height above touching (m) */
static const double kPressDepth = 0.010;   /* target depth below touching (m) */
static const double kSlide = 0.020;        /* slide length (m) */
static const double kBaseHeight = 0.003;   /* the liver's nodes this close to the table are fixed (m) */
static const double kStaleAfter = 0.25;    /* full-model data this old is stale (s) */
static const double kHandMass = 0.1;       /* kg */
static const double kHandStiffness = 200.0; /* N/m */
static const double kContactStiffness = 2e5; /* tool's Hunt-Crossley lambda (N/m^1.5), see the header */
static const int64_t kSpinNs = 50000;      /* spin this long before a device deadline (ns) */
static const long kMaxCoveredTicks = 4;    /* a haptic step covers at most this many ticks' time */
static const int kFifoPriority = 80;       /* SCHED_FIFO priority of the device thread */

/* Phase end times of the target (s from the start of a run). */
static const double kApproachEnd = 0.3, kPressEnd = 1.3, kSlideEnd = 3.3, kLiftEnd = 3.7;

/* ------------------------------------------------------------------------------------------ */
/* Clock                                                                                        */

static int64_t now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

/* Sleeps until the absolute CLOCK_MONOTONIC time t (ns). */
static void sleep_until(int64_t t) {
    struct timespec ts;
    ts.tv_sec = (time_t)(t / 1000000000);
    ts.tv_nsec = (long)(t % 1000000000);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

/* Sleeps until spin ns before the deadline, then spins to it. Returns the time it woke (ns). */
static int64_t wait_for(int64_t deadline, int64_t spin) {
    int64_t t = now_ns();
    if (t < deadline - spin) sleep_until(deadline - spin);
    while ((t = now_ns()) < deadline) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
    }
    return t;
}

/* Writes to every page of the block, so that the first real write to it does not fault (a large
 * calloc maps pages only when they are first written). */
static void touch_pages(void* block, size_t bytes) {
    volatile unsigned char* p = (volatile unsigned char*)block;
    size_t i;
    for (i = 0; i < bytes; i += 4096) p[i] = 0;
}

/* ------------------------------------------------------------------------------------------ */
/* The scripted target                                                                          */

/* Where along the path (fraction) and how deep below the touching height (m) the target is at
 * time t. */
static void target_at(double t, double* along, double* below) {
    *along = 0.0;
    if (t < kApproachEnd) {
        *below = -kGap * (1.0 - liver_ease(liver_progress(t, 0.0, kApproachEnd)));
    } else if (t < kPressEnd) {
        *below = kPressDepth * liver_progress(t, kApproachEnd, kPressEnd);
    } else if (t < kSlideEnd) {
        *below = kPressDepth;
        *along = liver_progress(t, kPressEnd, kSlideEnd);
    } else {
        *along = 1.0;
        *below = kPressDepth - (kPressDepth + kGap) * liver_ease(liver_progress(t, kSlideEnd, kLiftEnd));
    }
}

/* ------------------------------------------------------------------------------------------ */
/* One run: a device thread and a sim thread                                                    */

/* One CSV row. */
typedef struct trace_row {
    double t, position[3], force[3], data_age;
    int32_t contact, buffer_tets;
    uint32_t faults;
} trace_row;

typedef struct run {
    /* set up by create_run and create_tool_and_haptic */
    sh_world* world;
    sh_haptic* haptic;
    const liver_path* path;
    double rate;          /* Hz */
    int64_t period_ns;
    long ticks;           /* deadlines in the run */
    int decimate;         /* a CSV row every decimate ticks */
    int64_t start_ns;     /* the first deadline of both loops */
    atomic_int device_done;

    /* device thread */
    double* lateness;     /* per tick run (s) */
    double* step_time;    /* per tick run, of sh_haptic_step (s) */
    long executed;        /* ticks run (the others were dropped) */
    trace_row* rows;
    long row_count;
    long device_missed;   /* deadlines dropped */
    long skipped_ticks;   /* dropped ticks whose time no haptic step covered (kMaxCoveredTicks) */
    int fifo_error;       /* errno of pthread_setschedparam, 0 if SCHED_FIFO */
    int bad_force;
    double largest_force, deepest;
    double press_depth, press_force;  /* the hand's depth (m) and force (N) at the end of the press */
    int32_t most_tets, most_nodes, most_substeps;
    long contact_ticks, fault_ticks[5];
    sh_status step_status;

    /* sim thread */
    double* model_time;   /* per full-model step (s) */
    long model_capacity, model_steps, model_missed, model_failures;
    sh_status model_status;
    char model_message[256];
} run;

/* Moves the hand from tick to tick + 1 (of dt seconds) towards the path's next point, under
 * the device's force (N). */
static void move_hand(simulated_hand* h, const liver_path* path, long tick, double dt, const double force[3]) {
    double along, below, next[3];
    target_at((tick + 1) * dt, &along, &below);
    liver_path_point(path, along, below, next);
    simulated_hand_move(h, next, dt, force);
}

/* Asks for SCHED_FIFO (the error, if refused, goes to r->fifo_error) and a 1 ns timer slack,
 * so that the thread wakes as close to the time asked as it can. */
static void enter_realtime(run* r) {
    struct sched_param param;
    memset(&param, 0, sizeof param);
    param.sched_priority = kFifoPriority;
    r->fifo_error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
}

/* More than two periods late: drops the deadlines passed (counted). The hand moves on through
 * them holding the last force, as a device holds its last command; the next step covers up to
 * kMaxCoveredTicks of them (with its own tick).
 * Returns the ticks dropped. */
static long drop_missed(run* r, simulated_hand* h, long* tick, int64_t late, double dt, const double force[3]) {
    long missed, j;
    if (late <= 2 * r->period_ns) return 0;
    missed = (long)(late / r->period_ns);
    if (missed > r->ticks - 1 - *tick) missed = r->ticks - 1 - *tick;
    for (j = 0; j < missed; ++j) move_hand(h, r->path, (*tick)++, dt, force);
    r->device_missed += missed;
    return missed;
}

/* Adds the tick's output to the run's statistics: the force, how deep the hand is below the
 * touching height, the buffer, contact and faults. */
static void add_tick_stats(run* r, long tick, double dt, const simulated_hand* h, const sh_haptic_output* out) {
    const double magnitude = sqrt(out->force[0] * out->force[0] + out->force[1] * out->force[1] +
                                  out->force[2] * out->force[2]);
    double along, below, touching[3];
    int k;
    if (!isfinite(magnitude)) r->bad_force = 1;
    if (magnitude > r->largest_force) r->largest_force = magnitude;
    target_at(tick * dt, &along, &below);
    liver_path_point(r->path, along, 0.0, touching);
    if (touching[2] - h->x[2] > r->deepest) r->deepest = touching[2] - h->x[2];
    if (tick * dt <= kPressEnd) {
        r->press_depth = touching[2] - h->x[2];
        r->press_force = magnitude;
    }
    if (out->buffer_tets > r->most_tets) r->most_tets = out->buffer_tets;
    if (out->buffer_nodes > r->most_nodes) r->most_nodes = out->buffer_nodes;
    if (out->substeps > r->most_substeps) r->most_substeps = out->substeps;
    r->contact_ticks += out->contact;
    for (k = 0; k < 5; ++k) r->fault_ticks[k] += (out->faults >> k) & 1u;
}

/* Keeps the tick as a trace row (written after the run: the device thread never prints). */
static void add_trace_row(run* r, long tick, double dt, const simulated_hand* h, const sh_haptic_output* out) {
    trace_row* row = &r->rows[r->row_count++];
    int k;
    row->t = tick * dt;
    for (k = 0; k < 3; ++k) {
        row->position[k] = h->x[k];
        row->force[k] = out->force[k];
    }
    row->contact = out->contact;
    row->buffer_tets = out->buffer_tets;
    row->data_age = out->data_age;
    row->faults = out->faults;
}

/* The device loop: on each deadline, the haptic step renders the force at the hand's position
 * and the hand moves on under it. */
static void* device_thread(void* arg) {
    run* r = (run*)arg;
    const double dt = 1.0 / r->rate, identity[4] = {1.0, 0.0, 0.0, 0.0};
    double force[3] = {0.0, 0.0, 0.0}, along, below;
    long tick = 0, next_row = 0;
    simulated_hand h;
    double start[3];
    int k;

    enter_realtime(r);
    target_at(0.0, &along, &below);
    liver_path_point(r->path, along, below, start);
    simulated_hand_init(&h, start, kHandMass, kHandStiffness);
    while (tick < r->ticks) {
        const int64_t deadline = r->start_ns + tick * r->period_ns;
        const int64_t woke = wait_for(deadline, kSpinNs);
        int64_t before, after;
        sh_haptic_output out;
        sh_status status;
        long missed, covered;

        r->lateness[r->executed] = (double)(woke - deadline) * 1e-9;
        missed = drop_missed(r, &h, &tick, woke - deadline, dt, force);

        /* The device reads the hand's position, the haptic step renders the force. */
        before = now_ns();
        covered = missed + 1 < kMaxCoveredTicks ? missed + 1 : kMaxCoveredTicks;
        r->skipped_ticks += missed + 1 - covered;
        status = sh_haptic_step(r->haptic, h.x, identity, (double)covered * dt, &out);
        after = now_ns();
        r->step_time[r->executed++] = (double)(after - before) * 1e-9;
        if (status != SH_OK && r->step_status == SH_OK) r->step_status = status;
        for (k = 0; k < 3; ++k) force[k] = out.force[k];

        /* Statistics and the trace, at this tick's time. */
        add_tick_stats(r, tick, dt, &h, &out);
        if (tick >= next_row) {
            add_trace_row(r, tick, dt, &h, &out);
            while (next_row <= tick) next_row += r->decimate;
        }

        /* The hand moves on to the next tick under this force. */
        move_hand(&h, r->path, tick++, dt, force);
    }
    atomic_store(&r->device_done, 1);
    return NULL;
}

static void* sim_thread(void* arg) {
    run* r = (run*)arg;
    const double dt = 1.0 / kModelRate;
    const int64_t period = (int64_t)(1e9 / kModelRate + 0.5);
    int64_t deadline = r->start_ns;
    sleep_until(deadline);
    while (!atomic_load(&r->device_done)) {
        const int64_t before = now_ns();
        const sh_status status = sh_world_step(r->world, dt, NULL);
        const int64_t after = now_ns();
        if (r->model_steps < r->model_capacity) r->model_time[r->model_steps] = (double)(after - before) * 1e-9;
        ++r->model_steps;
        if (status != SH_OK && r->model_failures++ == 0) {
            r->model_status = status;
            snprintf(r->model_message, sizeof r->model_message, "%s", sh_last_error_message());
        }
        deadline += period;
        if (after - deadline > 2 * period) {
            const int64_t missed = (after - deadline) / period;
            r->model_missed += missed;
            deadline += missed * period;
        }
        sleep_until(deadline);
    }
    return NULL;
}

/* ------------------------------------------------------------------------------------------ */
/* Summary                                                                                      */

static int compare_doubles(const void* a, const void* b) {
    const double x = *(const double*)a, y = *(const double*)b;
    return x < y ? -1 : x > y;
}

/* The p-quantile (nearest rank) of the sorted values. */
static double quantile(const double* sorted, long count, double p) {
    long k = (long)ceil(p * (double)count) - 1;
    if (count == 0) return NAN;
    if (k < 0) k = 0;
    if (k >= count) k = count - 1;
    return sorted[k];
}

static void summarise(run* r) {
    const char* fault_names[5] = {"pose", "dt", "unstable", "stale", "no tool"};
    const long n = r->executed;
    const long models = r->model_steps < r->model_capacity ? r->model_steps : r->model_capacity;
    uint64_t warnings[SH_WARN_COUNT];
    long late = 0, i;
    int k, any_fault = 0;
    if (n == 0) return;
    qsort(r->lateness, (size_t)n, sizeof(double), compare_doubles);
    qsort(r->step_time, (size_t)n, sizeof(double), compare_doubles);
    qsort(r->model_time, (size_t)models, sizeof(double), compare_doubles);
    for (i = 0; i < n; ++i) late += r->lateness[i] * r->rate > 1.0;
    fprintf(stderr, "haptic_loop: %.0f Hz (%s): %ld ticks run, %ld dropped (%ld of them not simulated); lateness "
            "p50 %.1f us, p99 %.1f us, p99.9 %.1f us, max %.1f us; %ld ticks over a period late\n",
            r->rate, r->fifo_error ? "normal priority" : "SCHED_FIFO", n, r->device_missed, r->skipped_ticks,
            quantile(r->lateness, n, 0.5) * 1e6, quantile(r->lateness, n, 0.99) * 1e6,
            quantile(r->lateness, n, 0.999) * 1e6, r->lateness[n - 1] * 1e6, late);
    fprintf(stderr, "haptic_loop: %.0f Hz: haptic step p50 %.1f us, p99.9 %.1f us, max %.1f us (p99.9 is %.0f%% of "
            "the period), up to %d sub-steps\n",
            r->rate, quantile(r->step_time, n, 0.5) * 1e6, quantile(r->step_time, n, 0.999) * 1e6,
            r->step_time[n - 1] * 1e6, quantile(r->step_time, n, 0.999) * r->rate * 100, r->most_substeps);
    fprintf(stderr, "haptic_loop: %.0f Hz: full model: %ld steps of 1/%.0f s, step time p50 %.2f ms, p99 %.2f ms, "
            "max %.2f ms; %ld deadlines dropped, %ld failed steps\n",
            r->rate, r->model_steps, kModelRate, quantile(r->model_time, models, 0.5) * 1e3,
            quantile(r->model_time, models, 0.99) * 1e3, models > 0 ? r->model_time[models - 1] * 1e3 : NAN,
            r->model_missed, r->model_failures);
    if (r->model_failures > 0)
        fprintf(stderr, "haptic_loop: %.0f Hz: the first failed full-model step: %s\n  %s\n", r->rate,
                sh_status_string(r->model_status), r->model_message);
    fprintf(stderr, "haptic_loop: %.0f Hz: buffer up to %d tets and %d nodes; the hand %.1f mm below the touching "
            "height at the end of the press, with %.2f N; largest force %.3f N; the hand at most %.1f mm deep; in "
            "contact %.0f%% of the ticks; ticks with faults:",
            r->rate, r->most_tets, r->most_nodes, r->press_depth * 1e3, r->press_force, r->largest_force,
            r->deepest * 1e3, 100.0 * (double)r->contact_ticks / (double)n);
    for (k = 0; k < 5; ++k)
        if (r->fault_ticks[k] > 0) {
            fprintf(stderr, " %s %ld", fault_names[k], r->fault_ticks[k]);
            any_fault = 1;
        }
    fprintf(stderr, "%s\n", any_fault ? "" : " none");
    if (sh_haptic_get_warnings(r->haptic, warnings) == SH_OK)
        fprintf(stderr, "haptic_loop: %.0f Hz: haptic warnings: force clamped %llu, capacity %llu, unstable %llu\n",
                r->rate, (unsigned long long)warnings[SH_WARN_FORCE_CLAMPED],
                (unsigned long long)warnings[SH_WARN_CAPACITY], (unsigned long long)warnings[SH_WARN_UNSTABLE]);
}

/* Releases the run and its arrays. */
static void destroy_run(run* r) {
    free(r->lateness);
    free(r->step_time);
    free(r->rows);
    free(r->model_time);
    free(r);
}

/* A run at rate (Hz) on the scene's world, with everything its threads write allocated and
 * touched beforehand, so that the device thread never faults a page in. NULL if out of memory. */
static run* create_run(liver_scene* scene, const liver_path* path, double rate, int decimate) {
    run* r = calloc(1, sizeof *r);
    if (!r) return NULL;
    r->world = scene->world;
    r->path = path;
    r->rate = rate;
    r->period_ns = (int64_t)(1e9 / rate + 0.5);
    r->ticks = (long)(kRunTime * rate + 0.5);
    r->decimate = decimate;
    r->model_capacity = (long)(2.0 * kRunTime * kModelRate) + 16;
    r->lateness = calloc((size_t)r->ticks, sizeof(double));
    r->step_time = calloc((size_t)r->ticks, sizeof(double));
    r->rows = calloc((size_t)(r->ticks / decimate + 1), sizeof(trace_row));
    r->model_time = calloc((size_t)r->model_capacity, sizeof(double));
    atomic_init(&r->device_done, 0);
    if (!r->lateness || !r->step_time || !r->rows || !r->model_time) {
        fprintf(stderr, "haptic_loop: out of memory\n");
        destroy_run(r);
        return NULL;
    }
    touch_pages(r->lateness, (size_t)r->ticks * sizeof(double));
    touch_pages(r->step_time, (size_t)r->ticks * sizeof(double));
    touch_pages(r->rows, (size_t)(r->ticks / decimate + 1) * sizeof(trace_row));
    touch_pages(r->model_time, (size_t)r->model_capacity * sizeof(double));
    return r;
}

/* The tool 1 cm above the path's start and a haptic context on it (into r->haptic). 0 on
 * success. */
static int create_tool_and_haptic(liver_scene* scene, const liver_path* path, run* r, sh_tool_id* tool) {
    sh_collider_def tool_def;
    sh_haptic_def haptic_def;
    double along, below;
    sh_collider_def_default(&tool_def);
    tool_def.shape.kind = SH_SHAPE_SPHERE;
    tool_def.shape.radius = kToolRadius;
    target_at(0.0, &along, &below);
    liver_path_point(path, along, below, tool_def.position);
    tool_def.contact.stiffness = kContactStiffness;
    tool_def.contact.damping = 1.5;   /* s/m */
    tool_def.contact.static_friction = 0.3;
    tool_def.contact.dynamic_friction = 0.2;
    CHECK(sh_tool_create(scene->world, &tool_def, tool));
    sh_haptic_def_default(&haptic_def);
    haptic_def.tool = *tool;
    haptic_def.dt = 1.0 / r->rate;
    haptic_def.stale_after = kStaleAfter;
    CHECK(sh_haptic_create(scene->world, &haptic_def, &r->haptic));
    return 0;

done:
    return 1;
}

/* Runs the sim and device threads until the device's last deadline; both loops start on the
 * same deadline, once both threads exist. 0 on success. */
static int run_threads(run* r) {
    pthread_t device, sim;
    r->start_ns = now_ns() + 20000000;
    if (pthread_create(&sim, NULL, sim_thread, r) != 0) {
        fprintf(stderr, "haptic_loop: cannot start the sim thread\n");
        return 1;
    }
    if (pthread_create(&device, NULL, device_thread, r) != 0) {
        fprintf(stderr, "haptic_loop: cannot start the device thread\n");
        atomic_store(&r->device_done, 1);
        pthread_join(sim, NULL);
        return 1;
    }
    pthread_join(device, NULL);
    pthread_join(sim, NULL);
    return 0;
}

/* The run's trace rows as CSV on stdout. */
static void print_trace(const run* r) {
    long i;
    for (i = 0; i < r->row_count; ++i) {
        const trace_row* row = &r->rows[i];
        printf("%.0f,%.5f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f,%d,%d,%.5f,%u\n", r->rate, row->t, row->position[0],
               row->position[1], row->position[2], row->force[0], row->force[1], row->force[2], row->contact,
               row->buffer_tets, row->data_age, row->faults);
    }
    fflush(stdout);
}

/* Runs the device at rate (Hz) beside the sim thread for kRunTime, appends the trace to stdout
 * and the summary to stderr. Returns 0 on success. */
static int run_at(liver_scene* scene, const liver_path* path, double rate, int decimate, int* fifo_noticed) {
    run* r = create_run(scene, path, rate, decimate);
    sh_tool_id tool = SH_NULL_ID;
    int ok = 0;
    if (!r) return 1;

    /* The liver back to rest, the tool 1 cm above the start, a haptic context on it. */
    if (liver_scene_reset(scene) != 0) goto done;
    if (create_tool_and_haptic(scene, path, r, &tool) != 0) goto done;
    if (run_threads(r) != 0) goto done;

    if (r->fifo_error && !*fifo_noticed) {
        fprintf(stderr, "haptic_loop: notice: SCHED_FIFO not permitted (%s): the device thread ran at normal "
                "priority\n", strerror(r->fifo_error));
        *fifo_noticed = 1;
    }
    print_trace(r);
    summarise(r);
    if (r->step_status != SH_OK)
        fprintf(stderr, "haptic_loop: %.0f Hz: sh_haptic_step returned %s\n", rate, sh_status_string(r->step_status));
    if (r->bad_force) fprintf(stderr, "haptic_loop: %.0f Hz: a force was not finite\n", rate);
    ok = r->step_status == SH_OK && !r->bad_force;

done:
    sh_haptic_destroy(r->haptic); /* NULL is fine */
    if (!SH_ID_IS_NULL(tool)) sh_tool_destroy(scene->world, tool);
    destroy_run(r);
    return ok ? 0 : 1;
}

int main(int argc, char** argv) {
    liver_scene_def scene_def;
    liver_scene scene;
    liver_path path;
    int exit_code = 1, fifo_noticed = 0;

    memset(&scene, 0, sizeof scene);
    scene_def.program = "haptic_loop";
    scene_def.mesh_path = argc > 1 ? argv[1] : "../shared/meshes/liver.msh";
    scene_def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    scene_def.dt = 1.0 / kModelRate;
    scene_def.table_friction = 0.0;
    scene_def.base_height = kBaseHeight;
    if (liver_scene_create(&scene_def, &scene) != 0) goto done;
    if (liver_scene_find_path(&scene, kToolRadius, kSlide, &path) != 0) goto done;

    printf("rate_hz,t,x,y,z,force_x,force_y,force_z,contact,buffer_tets,data_age,faults\n");
    if (run_at(&scene, &path, 1000.0, 1, &fifo_noticed) != 0) goto done;
    if (run_at(&scene, &path, 10000.0, 10, &fifo_noticed) != 0) goto done;
    fprintf(stderr, "haptic_loop: on %ld online CPUs; the figures above are informational, not a test\n",
            sysconf(_SC_NPROCESSORS_ONLN));
    exit_code = 0;

done:
    liver_scene_destroy(&scene);
    return exit_code;
}
