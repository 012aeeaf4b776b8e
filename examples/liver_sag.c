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

typedef struct node_key {
    double x;
    int32_t index;
} node_key;

static int by_x(const void* a, const void* b) {
    const double xa = ((const node_key*)a)->x, xb = ((const node_key*)b)->x;
    return (xa > xb) - (xa < xb);
}

/* Appends one <DataSet> line to the .pvd time series. */
static int add_to_series(FILE* pvd, double time, const char* file) {
    return fprintf(pvd, "    <DataSet timestep=\"%g\" file=\"%s\"/>\n", time, file) > 0;
}

int main(int argc, char** argv) {
    const char* mesh_path = argc > 1 ? argv[1] : "../shared/meshes/liver.msh";
    const char* frames_dir = argc > 2 ? argv[2] : "frames";
    sh_mesh* file_mesh = NULL;
    sh_mesh* mesh = NULL;
    sh_world* world = NULL;
    double* nodes = NULL;
    double* rest = NULL;
    double* x = NULL;
    int32_t* tets = NULL;
    int32_t* fixed = NULL;
    node_key* keys = NULL;
    FILE* pvd = NULL;
    char path[4096];
    int exit_code = 1;
    int32_t i, node_count, fixed_count;
    sh_mesh_info info;
    sh_world_def world_def;
    sh_fem_body_def def;
    sh_body_id body;
    sh_body_info body_info;
    sh_step_report report;
    int step, steps, frame = 0;
    double wall_sum = 0.0;
    int32_t substeps_max = 0;
    clock_t start;

    /* 1. The mesh, scaled from centimetres to metres. */
    CHECK(sh_mesh_load(mesh_path, &file_mesh));
    CHECK(sh_mesh_get_info(file_mesh, &info));
    node_count = info.node_count;
    nodes = malloc(sizeof(double) * 3 * (size_t)node_count);
    rest = malloc(sizeof(double) * 3 * (size_t)node_count);
    x = malloc(sizeof(double) * 3 * (size_t)node_count);
    tets = malloc(sizeof(int32_t) * 4 * (size_t)info.tet_count);
    keys = malloc(sizeof(node_key) * (size_t)node_count);
    fixed = malloc(sizeof(int32_t) * (size_t)node_count);
    if (!nodes || !rest || !x || !tets || !keys || !fixed) {
        fprintf(stderr, "liver_sag: out of memory\n");
        goto done;
    }
    CHECK(sh_mesh_get_nodes(file_mesh, nodes, node_count));
    CHECK(sh_mesh_get_tets(file_mesh, tets, info.tet_count));
    for (i = 0; i < 3 * node_count; ++i) nodes[i] *= kCentimetre;
    CHECK(sh_mesh_create(nodes, node_count, tets, info.tet_count, &mesh));
    CHECK(sh_mesh_get_info(mesh, &info));
    printf("liver_sag: %s: %d nodes, %d tets, %.1f x %.1f x %.1f cm, %.1f cm^3\n", mesh_path,
           info.node_count, info.tet_count, (info.bounds_max[0] - info.bounds_min[0]) / kCentimetre,
           (info.bounds_max[1] - info.bounds_min[1]) / kCentimetre,
           (info.bounds_max[2] - info.bounds_min[2]) / kCentimetre, info.volume * 1e6);

    /* 2. The world and the body. */
    sh_world_def_default(&world_def); /* gravity (0, 0, -9.81) m/s^2 */
    CHECK(sh_world_create(&world_def, &world));
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = SH_MATERIAL_STVK;
    def.material.young = 15e3;    /* Pa: liver parenchyma is a few to tens of kPa */
    def.material.poisson = 0.45;  /* nearly incompressible */
    def.material.density = 1000.0;
    def.damping_mass = 6.0;       /* 1/s: the first mode rings for a few cycles, then settles */
    def.integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
    def.on_unstable = SH_UNSTABLE_SUBSTEP;
    CHECK(sh_fem_body_create(world, &def, &body));

    /* 3. Clamp the side with the smallest x. */
    for (i = 0; i < node_count; ++i) {
        keys[i].x = nodes[3 * i];
        keys[i].index = i;
    }
    qsort(keys, (size_t)node_count, sizeof *keys, by_x);
    fixed_count = (int32_t)ceil(kFixedFraction * node_count);
    for (i = 0; i < fixed_count; ++i) fixed[i] = keys[i].index;
    CHECK(sh_body_fix_nodes(world, body, fixed, fixed_count));
    CHECK(sh_body_get_info(world, body, &body_info));
    CHECK(sh_body_get_positions(world, body, rest, node_count));
    printf("liver_sag: mass %.1f g, %d nodes fixed (x <= %.2f cm), dt %.1f ms, dt_crit %.3f ms "
           "(about %d sub-steps per step)\n",
           body_info.total_mass * 1e3, body_info.fixed_node_count, keys[fixed_count - 1].x / kCentimetre,
           kDt * 1e3, body_info.dt_critical * 1e3, (int)ceil(kDt / body_info.dt_critical));

    /* 4. Frames: the folder and a ParaView time series. */
    if (make_directory(frames_dir) != 0 && errno != EEXIST) {
        fprintf(stderr, "liver_sag: cannot create '%s': %s\n", frames_dir, strerror(errno));
        goto done;
    }
    snprintf(path, sizeof path, "%s/liver.pvd", frames_dir);
    pvd = fopen(path, "w");
    if (!pvd) {
        fprintf(stderr, "liver_sag: cannot write '%s': %s\n", path, strerror(errno));
        goto done;
    }
    fprintf(pvd, "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n");

    /* 5. Step. */
    printf("%8s %12s %9s %12s %12s %12s %10s\n", "t (s)", "wall/step", "substeps", "kinetic (J)",
           "elastic (J)", "potential (J)", "sag (mm)");
    steps = (int)(kDuration / kDt + 0.5);
    start = clock();
    for (step = 0; step <= steps; ++step) {
        if (step > 0) {
            CHECK(sh_world_step(world, kDt, &report));
            wall_sum += report.wall_seconds;
            if (report.substeps > substeps_max) substeps_max = report.substeps;
            if (!isfinite(report.kinetic_energy) || !isfinite(report.elastic_energy) ||
                !isfinite(report.potential_energy)) {
                fprintf(stderr, "liver_sag: non-finite energy at t = %g s\n", step * kDt);
                goto done;
            }
        }
        if (step % kStepsPerReport != 0) continue;
        {
            double sag = 0.0;
            char name[64];
            CHECK(sh_body_get_positions(world, body, x, node_count));
            for (i = 0; i < node_count; ++i)
                if (rest[3 * i + 2] - x[3 * i + 2] > sag) sag = rest[3 * i + 2] - x[3 * i + 2];
            if (step == 0) {
                printf("%8.3f %12s %9s %12s %12s %12s %10.3f\n", 0.0, "-", "-", "-", "-", "-", sag * 1e3);
            } else {
                printf("%8.3f %9.1f us %9d %12.4e %12.4e %12.4e %10.3f\n", step * kDt,
                       wall_sum / kStepsPerReport * 1e6, substeps_max, report.kinetic_energy,
                       report.elastic_energy, report.potential_energy, sag * 1e3);
            }
            wall_sum = 0.0;
            substeps_max = 0;
            snprintf(name, sizeof name, "liver_%04d.vtu", frame++);
            snprintf(path, sizeof path, "%s/%s", frames_dir, name);
            CHECK(sh_body_write_vtu(world, body, path));
            if (!add_to_series(pvd, step * kDt, name)) {
                fprintf(stderr, "liver_sag: cannot write %s/liver.pvd\n", frames_dir);
                goto done;
            }
        }
    }
    fprintf(pvd, "  </Collection>\n</VTKFile>\n");
    if (fclose(pvd) != 0) {
        pvd = NULL;
        fprintf(stderr, "liver_sag: cannot write %s/liver.pvd\n", frames_dir);
        goto done;
    }
    pvd = NULL;
    printf("liver_sag: %d steps in %.2f s of CPU time; %d frames in %s/ (open %s/liver.pvd in ParaView)\n",
           steps, (double)(clock() - start) / CLOCKS_PER_SEC, frame, frames_dir, frames_dir);
    exit_code = 0;

done:
    if (pvd) fclose(pvd);
    sh_world_destroy(world); /* NULL is fine */
    sh_mesh_destroy(mesh);
    sh_mesh_destroy(file_mesh);
    free(nodes);
    free(rest);
    free(x);
    free(tets);
    free(keys);
    free(fixed);
    return exit_code;
}
