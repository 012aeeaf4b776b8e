/* liver_sag.c: a liver held along one side sags under its own weight and settles.
 *
 *   liver_sag [mesh.msh [frames_dir]]     (defaults: ../shared/meshes/liver.msh, frames)
 *
 * `make demo` runs it from the repository root. It loads the SOFA haptic-demo liver (181 nodes,
 * 596 tets; its coordinates are centimetre-scale numbers, so they are scaled to metres), makes a
 * StVK soft-tissue body (E = 15 kPa, nu = 0.45, rho = 1000 kg/m^3) with mass damping, clamps the
 * 15 % of nodes with the smallest x (the side attached to the diaphragm, say) and lets gravity
 * (-9.81 m/s^2 along z) act for 2 s of simulated time at a fixed 1 ms step. Each step is split
 * into sub-steps below the critical explicit step (SH_UNSTABLE_SUBSTEP).
 *
 * What you see: a table, every 0.1 s, of simulated time, wall time per step, sub-steps per
 * step, kinetic / elastic / gravitational energy and the largest downward displacement (sag).
 * The free lobe drops and rings for about a second: the kinetic energy rises and decays to
 * ~1e-9 J, the elastic energy levels off near 0.23 mJ and the sag settles near 5 mm. Each 1 ms
 * step takes about 23 sub-steps (dt_crit ~0.04 ms: the mesh has a few thin tets). The frames go
 * to frames/liver_NNNN.vtu (every 0.1 s) with a frames/liver.pvd time series: open liver.pvd
 * in ParaView, press Play, and colour by "velocity" to watch the lobe swing down and settle.
 *
 * Exit status: 0 on success; 1 if any call fails or any energy is not finite. */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L /* mkdir */
#endif

#include <softhap/softhap.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#if defined(_WIN32)
#include <direct.h>
#define make_directory(path) _mkdir(path)
#else
#include <sys/stat.h>
#define make_directory(path) mkdir((path), 0755)
#endif

/* Runs call (an expression giving an sh_status); on failure prints it with the library's last
 * error message and jumps to the function's `done` label, which releases what it made. */
#define CHECK(call)                                                                        \
    do {                                                                                   \
        sh_status status_ = (call);                                                        \
        if (status_ != SH_OK) {                                                            \
            fprintf(stderr, "liver_sag: %s failed: %s\n  %s\n", #call,                     \
                    sh_status_string(status_), sh_last_error_message());                   \
            goto done;                                                                     \
        }                                                                                  \
    } while (0)

static const double kCentimetre = 0.01;   /* file unit -> m */
static const double kFixedFraction = 0.15; /* share of nodes clamped, smallest x first */
static const double kDuration = 2.0;       /* simulated time (s) */
static const double kDt = 1e-3;            /* fixed host step (s) */
static const int kStepsPerReport = 100;    /* print and write a frame every 0.1 s */

/* The liver as the simulation sees it. */
typedef struct sag_scene {
    sh_mesh* mesh;      /* in metres */
    sh_world* world;
    sh_body_id body;
    int32_t node_count;
    double* rest;       /* node positions at rest (3 per node, m): the sag is measured from them */
    double* x;          /* node positions now (3 per node, m) */
} sag_scene;

/* Where the frames go: the folder and the ParaView time series (.pvd) that lists them. */
typedef struct frame_series {
    const char* dir;
    FILE* pvd;
    int count;          /* frames written */
} frame_series;

/* What happened since the last table row. */
typedef struct row_stats {
    double wall_sum;        /* s of wall time in sh_world_step */
    int32_t substeps_max;
    sh_step_report last;    /* the last step's report (energies) */
} row_stats;

/* ------------------------------------------------------------------------------------------ */
/* Building the scene                                                                           */

/* Loads mesh_path and scales it from centimetres to metres: sh_mesh_create copies the node
 * array, so the scaled nodes make a new mesh. Prints the mesh's size. 0 on success. */
static int load_liver_mesh(const char* mesh_path, sh_mesh** out_mesh) {
    sh_mesh* file_mesh = NULL;
    double* nodes = NULL;
    int32_t* tets = NULL;
    sh_mesh_info info;
    int32_t i;
    int ok = 0;

    CHECK(sh_mesh_load(mesh_path, &file_mesh));
    CHECK(sh_mesh_get_info(file_mesh, &info));
    nodes = malloc(sizeof(double) * 3 * (size_t)info.node_count);
    tets = malloc(sizeof(int32_t) * 4 * (size_t)info.tet_count);
    if (!nodes || !tets) {
        fprintf(stderr, "liver_sag: out of memory\n");
        goto done;
    }
    CHECK(sh_mesh_get_nodes(file_mesh, nodes, info.node_count));
    CHECK(sh_mesh_get_tets(file_mesh, tets, info.tet_count));
    for (i = 0; i < 3 * info.node_count; ++i) nodes[i] *= kCentimetre;
    CHECK(sh_mesh_create(nodes, info.node_count, tets, info.tet_count, out_mesh));
    CHECK(sh_mesh_get_info(*out_mesh, &info));
    printf("liver_sag: %s: %d nodes, %d tets, %.1f x %.1f x %.1f cm, %.1f cm^3\n", mesh_path,
           info.node_count, info.tet_count, (info.bounds_max[0] - info.bounds_min[0]) / kCentimetre,
           (info.bounds_max[1] - info.bounds_min[1]) / kCentimetre,
           (info.bounds_max[2] - info.bounds_min[2]) / kCentimetre, info.volume * 1e6);
    ok = 1;

done:
    sh_mesh_destroy(file_mesh); /* NULL is fine */
    free(nodes);
    free(tets);
    return ok ? 0 : 1;
}

/* The world under gravity and the liver as a soft-tissue body in it, with its rest positions.
 * 0 on success. */
static int create_body(sag_scene* s) {
    sh_world_def world_def;
    sh_fem_body_def def;
    sh_mesh_info info;

    CHECK(sh_mesh_get_info(s->mesh, &info));
    s->node_count = info.node_count;
    s->rest = malloc(sizeof(double) * 3 * (size_t)s->node_count);
    s->x = malloc(sizeof(double) * 3 * (size_t)s->node_count);
    if (!s->rest || !s->x) {
        fprintf(stderr, "liver_sag: out of memory\n");
        return 1;
    }
    sh_world_def_default(&world_def); /* gravity (0, 0, -9.81) m/s^2 */
    CHECK(sh_world_create(&world_def, &s->world));
    sh_fem_body_def_default(&def);
    def.mesh = s->mesh;
    def.material.model = SH_MATERIAL_STVK;
    def.material.young = 15e3;    /* Pa: liver parenchyma is a few to tens of kPa */
    def.material.poisson = 0.45;  /* nearly incompressible */
    def.material.density = 1000.0;
    def.damping_mass = 6.0;       /* 1/s: the first mode rings for a few cycles, then settles */
    def.integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
    /* The mesh has a few thin tets, so the critical explicit step is far below kDt: the
     * library splits each step into enough sub-steps rather than blow up. */
    def.on_unstable = SH_UNSTABLE_SUBSTEP;
    CHECK(sh_fem_body_create(s->world, &def, &s->body));
    CHECK(sh_body_get_positions(s->world, s->body, s->rest, s->node_count));
    return 0;

done:
    return 1;
}

/* A node index with its x coordinate, to sort the nodes by x. */
typedef struct node_key {
    double x;
    int32_t index;
} node_key;

/* qsort order of node_key: smallest x first. */
static int by_x(const void* a, const void* b) {
    const double xa = ((const node_key*)a)->x, xb = ((const node_key*)b)->x;
    return (xa > xb) - (xa < xb);
}

/* Clamps the kFixedFraction of the nodes with the smallest x: the side attached to the
 * diaphragm, say, which holds the rest of the liver up. Prints the body's mass, the clamp and the
 * step's sub-stepping. 0 on success. */
static int clamp_side(sag_scene* s) {
    node_key* keys = malloc(sizeof(node_key) * (size_t)s->node_count);
    int32_t* fixed = malloc(sizeof(int32_t) * (size_t)s->node_count);
    sh_body_info body_info;
    int32_t i, fixed_count;
    int ok = 0;

    if (!keys || !fixed) {
        fprintf(stderr, "liver_sag: out of memory\n");
        goto done;
    }
    for (i = 0; i < s->node_count; ++i) {
        keys[i].x = s->rest[3 * i];
        keys[i].index = i;
    }
    qsort(keys, (size_t)s->node_count, sizeof *keys, by_x);
    fixed_count = (int32_t)ceil(kFixedFraction * s->node_count);
    for (i = 0; i < fixed_count; ++i) fixed[i] = keys[i].index;
    CHECK(sh_body_fix_nodes(s->world, s->body, fixed, fixed_count));
    CHECK(sh_body_get_info(s->world, s->body, &body_info));
    printf("liver_sag: mass %.1f g, %d nodes fixed (x <= %.2f cm), dt %.1f ms, dt_crit %.3f ms "
           "(about %d sub-steps per step)\n",
           body_info.total_mass * 1e3, body_info.fixed_node_count, keys[fixed_count - 1].x / kCentimetre,
           kDt * 1e3, body_info.dt_critical * 1e3, (int)ceil(kDt / body_info.dt_critical));
    ok = 1;

done:
    free(keys);
    free(fixed);
    return ok ? 0 : 1;
}

/* Releases everything the scene holds. */
static void destroy_scene(sag_scene* s) {
    sh_world_destroy(s->world); /* NULL is fine */
    sh_mesh_destroy(s->mesh);
    free(s->rest);
    free(s->x);
}

/* ------------------------------------------------------------------------------------------ */
/* Frames for ParaView                                                                          */

/* Creates the folder (if need be) and starts the time series in it. 0 on success. */
static int open_series(frame_series* series, const char* dir) {
    char path[4096];
    series->dir = dir;
    series->count = 0;
    if (make_directory(dir) != 0 && errno != EEXIST) {
        fprintf(stderr, "liver_sag: cannot create '%s': %s\n", dir, strerror(errno));
        return 1;
    }
    snprintf(path, sizeof path, "%s/liver.pvd", dir);
    series->pvd = fopen(path, "w");
    if (!series->pvd) {
        fprintf(stderr, "liver_sag: cannot write '%s': %s\n", path, strerror(errno));
        return 1;
    }
    fprintf(series->pvd, "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n");
    return 0;
}

/* Writes the body as the next frame (liver_NNNN.vtu) and lists it in the series at time t (s).
 * 0 on success. */
static int write_frame(const sag_scene* s, frame_series* series, double t) {
    char name[64], path[4096];
    snprintf(name, sizeof name, "liver_%04d.vtu", series->count++);
    snprintf(path, sizeof path, "%s/%s", series->dir, name);
    CHECK(sh_body_write_vtu(s->world, s->body, path));
    if (fprintf(series->pvd, "    <DataSet timestep=\"%g\" file=\"%s\"/>\n", t, name) <= 0) {
        fprintf(stderr, "liver_sag: cannot write %s/liver.pvd\n", series->dir);
        return 1;
    }
    return 0;

done:
    return 1;
}

/* Ends the series and closes its file (a full disk shows only then). 0 on success. */
static int close_series(frame_series* series) {
    FILE* pvd = series->pvd;
    series->pvd = NULL;
    fprintf(pvd, "  </Collection>\n</VTKFile>\n");
    if (fclose(pvd) != 0) {
        fprintf(stderr, "liver_sag: cannot write %s/liver.pvd\n", series->dir);
        return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* The run                                                                                      */

/* The largest downward displacement of any node from rest (m) into *sag. 0 on success. */
static int measure_sag(sag_scene* s, double* sag) {
    int32_t i;
    *sag = 0.0;
    CHECK(sh_body_get_positions(s->world, s->body, s->x, s->node_count));
    for (i = 0; i < s->node_count; ++i)
        if (s->rest[3 * i + 2] - s->x[3 * i + 2] > *sag) *sag = s->rest[3 * i + 2] - s->x[3 * i + 2];
    return 0;

done:
    return 1;
}

/* One row of the table after `step` steps: the time, the mean wall time and largest sub-step
 * count of the row's steps, the last step's energies, and the sag. Step 0 has no steps yet. */
static void print_row(int step, const row_stats* row, double sag) {
    if (step == 0) {
        printf("%8.3f %12s %9s %12s %12s %12s %10.3f\n", 0.0, "-", "-", "-", "-", "-", sag * 1e3);
        return;
    }
    printf("%8.3f %9.1f us %9d %12.4e %12.4e %12.4e %10.3f\n", step * kDt, row->wall_sum / kStepsPerReport * 1e6,
           row->substeps_max, row->last.kinetic_energy, row->last.elastic_energy, row->last.potential_energy,
           sag * 1e3);
}

/* One host step of kDt, added to the row's statistics. A non-finite energy means the body blew
 * up: that is reported and fails. 0 on success. */
static int step_once(sag_scene* s, int step, row_stats* row) {
    CHECK(sh_world_step(s->world, kDt, &row->last));
    row->wall_sum += row->last.wall_seconds;
    if (row->last.substeps > row->substeps_max) row->substeps_max = row->last.substeps;
    if (!isfinite(row->last.kinetic_energy) || !isfinite(row->last.elastic_energy) ||
        !isfinite(row->last.potential_energy)) {
        fprintf(stderr, "liver_sag: non-finite energy at t = %g s\n", step * kDt);
        return 1;
    }
    return 0;

done:
    return 1;
}

/* Runs for kDuration; every kStepsPerReport steps (and at the start) prints a row of the table
 * and writes a frame. Returns the number of steps taken, or -1 on failure. */
static int simulate(sag_scene* s, frame_series* series) {
    const int steps = (int)(kDuration / kDt + 0.5);
    row_stats row;
    int step;
    memset(&row, 0, sizeof row);
    printf("%8s %12s %9s %12s %12s %12s %10s\n", "t (s)", "wall/step", "substeps", "kinetic (J)",
           "elastic (J)", "potential (J)", "sag (mm)");
    for (step = 0; step <= steps; ++step) {
        double sag;
        if (step > 0 && step_once(s, step, &row) != 0) return -1;
        if (step % kStepsPerReport != 0) continue;
        if (measure_sag(s, &sag) != 0) return -1;
        print_row(step, &row, sag);
        row.wall_sum = 0.0;
        row.substeps_max = 0;
        if (write_frame(s, series, step * kDt) != 0) return -1;
    }
    return steps;
}

int main(int argc, char** argv) {
    const char* mesh_path = argc > 1 ? argv[1] : "../shared/meshes/liver.msh";
    const char* frames_dir = argc > 2 ? argv[2] : "frames";
    sag_scene scene;
    frame_series series;
    clock_t start;
    int steps, exit_code = 1;

    memset(&scene, 0, sizeof scene);
    memset(&series, 0, sizeof series);
    if (load_liver_mesh(mesh_path, &scene.mesh) != 0) goto done;
    if (create_body(&scene) != 0) goto done;
    if (clamp_side(&scene) != 0) goto done;
    if (open_series(&series, frames_dir) != 0) goto done;
    start = clock();
    steps = simulate(&scene, &series);
    if (steps < 0) goto done;
    if (close_series(&series) != 0) goto done;
    printf("liver_sag: %d steps in %.2f s of CPU time; %d frames in %s/ (open %s/liver.pvd in ParaView)\n",
           steps, (double)(clock() - start) / CLOCKS_PER_SEC, series.count, frames_dir, frames_dir);
    exit_code = 0;

done:
    if (series.pvd) fclose(series.pvd);
    destroy_scene(&scene);
    return exit_code;
}
