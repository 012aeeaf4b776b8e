/*
 * softhap_bench haptic | haptic-error | haptic-force: the Volumetric Buffer Model's haptic step,
 * its cost and its error against run time. One JSON line per case on stdout, progress on
 * stderr; scripts/haptic_report.py turns them into report/haptic.md and plots.
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
 *  - "haptic/machine/<T>us": no haptic step at all: a chain of dependent multiply-adds whose
 *    median is calibrated to T us (15 and 25), timed like the ticks. Its p99.9 and max are the
 *    tail this machine adds to any computation that long (interrupts, other processes): a
 *    step's p99.9 near it is the machine's, not the step's.
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
 *
 * Files: this one reads the command line and runs a study; haptic_cost.c, haptic_error.c and
 * haptic_force.c are the studies; haptic_tissue.c makes the block and the livers, haptic_scene.c
 * the worlds on them, haptic_ticks.c runs and logs haptic ticks, haptic_thread.c holds the
 * allocation counting, CPU pinning and real-time helpers; haptic_common.h declares what they
 * share.
 */
#include "haptic.h"

#include "haptic_common.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int is_haptic_command(const char* name) {
    return strcmp(name, "haptic") == 0 || strcmp(name, "haptic-error") == 0 || strcmp(name, "haptic-force") == 0;
}

/* The subcommands' usage on stderr. */
static void usage(void) {
    fprintf(stderr, "usage: softhap_bench haptic [FILTER] [--steps N] [--rt] [--meshes DIR]\n"
                    "       softhap_bench haptic-error [FILTER] [--meshes DIR]\n"
                    "       softhap_bench haptic-force [--csv PATH] [--meshes DIR]\n");
}

/* Reads the options after the subcommand into *o (the mesh folder given, if any, into
 * *given_dir). Returns -1 to go on, else the exit code (--help: 0, a bad option: 2). */
static int parse_options(int argc, char** argv, haptic_options* o, const char** given_dir) {
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--steps") == 0 && i + 1 < argc) {
            o->steps = atoi(argv[++i]);
            if (o->steps < 1) {
                usage();
                return 2;
            }
        } else if (strcmp(argv[i], "--meshes") == 0 && i + 1 < argc) {
            *given_dir = argv[++i];
        } else if (strcmp(argv[i], "--rt") == 0) {
            o->rt = 1;
        } else if (strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
            o->csv = argv[++i];
        } else {
            const int code = bench_filter_arg(argv[i], &o->filter, usage);
            if (code >= 0) return code;
        }
    }
    return -1;
}

/* The haptic thread (this one) pinned, and real-time if --rt asked and the system grants it. */
static void set_up_threads(haptic_options* o) {
    choose_cpus(o);
    if (o->rt) {
        o->rt = make_realtime();
        fprintf(stderr, "softhap_bench: --rt: SCHED_FIFO %s\n", o->rt ? "granted" : "refused (timings as usual)");
    }
}

/* The run's environment line: how long it took, the machine's load around it, the CPUs. */
static void print_env(const char* command, const haptic_options* o, double seconds, double load_before) {
    printf("{\"study\":\"haptic_env\",\"command\":\"%s\",\"version\":%d,\"seconds\":%.1f,\"load_before\":%.2f,"
           "\"load_after\":%.2f,\"haptic_cpu\":%d,\"sim_cpu\":%d,\"rt\":%d}\n",
           command, (int)sh_version(), seconds, load_before, bench_load_average(-1.0), o->haptic_cpu, o->sim_cpu,
           o->rt);
}

int run_haptic(int argc, char** argv) {
    const char* command = argv[0];
    const char* given_dir = NULL;
    haptic_options o;
    memset(&o, 0, sizeof o);
    o.haptic_cpu = o.sim_cpu = -1;
    const int parsed = parse_options(argc, argv, &o, &given_dir);
    if (parsed >= 0) return parsed;
    if (strcmp(command, "haptic") != 0) { /* the block needs no mesh file */
        o.mesh_dir = bench_find_mesh_dir(given_dir, "liver.msh");
        if (!o.mesh_dir) return 1;
    }
    /* Count from the start: the allocator cannot change while softhap objects live. */
    install_counting_allocator();
    set_up_threads(&o);
    const double load_before = bench_load_average(-1.0), t0 = now_ns();
    int code;
    if (strcmp(command, "haptic") == 0)
        code = haptic_run_cost(&o);
    else if (strcmp(command, "haptic-error") == 0)
        code = haptic_run_error(&o);
    else
        code = haptic_run_force(&o);
    remove_counting_allocator();
    print_env(command, &o, (now_ns() - t0) * 1e-9, load_before);
    return code;
}
