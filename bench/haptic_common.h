/* What the softhap_bench haptic studies share (haptic.c describes the studies): the parameters
 * common to all of them, the command's options, the tissues pressed and the scenes built on them,
 * timed runs of haptic ticks, and the thread and allocation-counting helpers. */
#ifndef SOFTHAP_BENCH_HAPTIC_COMMON_H
#define SOFTHAP_BENCH_HAPTIC_COMMON_H

#include "bench_util.h"

#include <softhap/softhap.h>

#include <stdint.h>

/* ------------------------------------------------------------------------------------------ */
/* Parameters of every study                                                                    */

static const double kPi = 3.14159265358979323846;
static const double kToolRadius = 0.01;  /* m */
static const double kHapticDt = 1e-3;    /* s: 1 kHz */
static const double kSimDt = 1.0 / 60.0; /* s: the full model at 60 Hz */
static const double kIdentity[4] = {1.0, 0.0, 0.0, 0.0};

/* The slide of haptic-force: its length, and the samples of the touching height along it (the
 * liver's slide direction is chosen over the same samples). */
static const double kTraceSlide = 0.03; /* m */
enum { kPathSamples = 61 };

/* The command line and the CPUs the threads keep. */
typedef struct {
    const char* mesh_dir; /* haptic-error and haptic-force: the folder of liver.msh */
    const char* filter;   /* keep the cases whose name contains it; NULL: all */
    const char* csv;      /* haptic-force --csv: the per-tick trace; NULL: none */
    int steps;            /* haptic --steps N; 0: each case's default */
    int rt;               /* --rt asked and SCHED_FIFO granted */
    int haptic_cpu;       /* the CPU of the haptic thread (the main one); -1: unknown */
    int sim_cpu;          /* the CPU of the cost study's sim thread */
} haptic_options;

/* The three studies; each returns the exit code. */
int haptic_run_cost(const haptic_options* options);
int haptic_run_error(const haptic_options* options);
int haptic_run_force(const haptic_options* options);

/* ------------------------------------------------------------------------------------------ */
/* Tissues: a mesh with its fixed base and the point the tool presses (haptic_tissue.c)         */

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

/* The cost study's block, pressed at the centre of its top. */
tissue make_block(void);

/* dir/file turned, scaled and fixed as haptic.c describes, with its press point and slide
 * direction. 0, with a message on stderr, if the mesh is missing or has no place to press. */
int make_liver(tissue* t, const char* dir, const char* file, const char* name);

/* Frees what make_block or make_liver made. */
void tissue_free(tissue* t);

/* Height of the tool's centre at which the sphere, lowered vertically over (x, y), first touches
 * the rest surface; -INFINITY if the centre is off the surface. */
double touch_height(const tissue* t, double x, double y);

/* The tool's centre where it first touches above the press point. */
void touch_point(const tissue* t, double out[3]);

/* ------------------------------------------------------------------------------------------ */
/* Scenes: a world with the tissue's body and the tool (haptic_scene.c)                        */

typedef struct {
    sh_world* world;
    sh_body_id body;
    sh_tool_id tool;
} scene;

/* A world without gravity holding the tissue as one body of the given model, integrator and
 * mass damping (1/s), its base fixed, and the sphere tool at tool_position. */
scene scene_create(const tissue* t, sh_material_model model, sh_integrator integrator, double damping,
                   const double tool_position[3]);

/* scene_create with the tool tool (a collider def) instead of the default sphere. */
scene scene_create_with_tool(const tissue* t, sh_material_model model, sh_integrator integrator, double damping,
                             const sh_collider_def* tool);

/* Destroys the scene's world and everything in it. */
void scene_destroy(scene* s);

/* One full-model step of kSimDt; returns 1 if its Newton iteration did not converge (counted by
 * the studies, not fatal), else 0. */
int world_step(sh_world* world);

/* A haptic def for the scene's tool: a buffer of radius (m) and at most capacity_tets tets;
 * exact: no clamp, rate limit nor ramp, so that the output is the raw force. The nominal step is
 * kHapticDt. */
sh_haptic_def haptic_def_for(const scene* s, double radius, int32_t capacity_tets, int exact);

/* ------------------------------------------------------------------------------------------ */
/* Timed haptic ticks (haptic_ticks.c)                                                          */

/* The device's path: the tool centre at tick i (the pose the step takes it to). */
typedef void (*path_fn)(const void* path, long tick, double out[3]);

/* What a run of ticks saw. */
typedef struct {
    double* ns;       /* per timed tick */
    double* substeps; /* per timed tick */
    int timed;
    long contact, fresh;
    uint32_t faults;
    long allocations;
    sh_haptic_output last;
} tick_log;

/* A log with room for count timed ticks. */
void tick_log_alloc(tick_log* log, int count);

/* Frees what tick_log_alloc allocated. */
void tick_log_free(tick_log* log);

/* Steps haptic by dt (s) from tick `first` for count ticks along path; paced: one tick per dt
 * of wall time. Timed ticks (if log->ns) are recorded, and calls of the allocator from this
 * thread during the loop counted. */
void run_ticks(sh_haptic* haptic, path_fn path, const void* ctx, long first, long count, double dt, int paced,
               tick_log* log);

/* Prints "<prefix>median_us":..,... (median, p99, p99.9, max, mean) for times in ns. */
void print_times_us(const char* prefix, const stats* s);

/* ------------------------------------------------------------------------------------------ */
/* Threads and allocation counting (haptic_thread.c)                                            */

/* Installs the allocator that counts the calls made while counting is on (see alloc_count_on);
 * the library's allocator can only change while no softhap object lives. */
void install_counting_allocator(void);

/* Puts the library's default allocator back. */
void remove_counting_allocator(void);

/* Starts counting the calling thread's allocations and frees from zero. */
void alloc_count_on(void);

/* Stops counting; returns the calls counted since alloc_count_on. */
long alloc_count_off(void);

/* Pins the calling thread to the CPU it runs on and picks another allowed CPU for the sim
 * thread (the same one if there is no other): options->haptic_cpu and sim_cpu. */
void choose_cpus(haptic_options* options);

/* Asks SCHED_FIFO for the calling thread; 1 if granted. */
int make_realtime(void);

/* Puts the calling thread back to the ordinary policy (threads inherit their creator's). */
void make_ordinary(void);

/* Sleeps until the absolute CLOCK_MONOTONIC time deadline_ns. */
void sleep_until(double deadline_ns);

#endif
