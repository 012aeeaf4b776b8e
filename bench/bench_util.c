#define _GNU_SOURCE /* sched_getcpu, sched_setaffinity */
#include "bench_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#ifdef __linux__
#include <sched.h>
#endif

#ifndef SOFTHAP_BENCH_MESH_DIR
#define SOFTHAP_BENCH_MESH_DIR "../shared/meshes"
#endif

void bench_check(sh_status status, const char* expr) {
    if (status == SH_OK) return;
    fprintf(stderr, "softhap_bench: %s failed: %s (%s)\n", expr, sh_status_string(status), sh_last_error_message());
    exit(1);
}

double now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}

void* xmalloc(size_t size) {
    void* p = malloc(size ? size : 1);
    if (!p) {
        fprintf(stderr, "softhap_bench: out of memory\n");
        exit(1);
    }
    return p;
}

int cmp_double(const void* a, const void* b) {
    const double x = *(const double*)a, y = *(const double*)b;
    return x < y ? -1 : x > y;
}

double quantile(const double* sorted, int n, double q) {
    int k = (int)ceil(q * n) - 1;
    if (k < 0) k = 0;
    if (k > n - 1) k = n - 1;
    return sorted[k];
}

double median(const double* sorted, int n) {
    return n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
}

stats summarize(double* v, int n) {
    stats s = {0, 0.0, 0.0, 0.0, 0.0, 0.0};
    if (n <= 0) return s;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += v[i];
    qsort(v, (size_t)n, sizeof(double), cmp_double);
    s.count = n;
    s.median = median(v, n);
    s.p99 = quantile(v, n, 0.99);
    s.p999 = quantile(v, n, 0.999);
    s.max = v[n - 1];
    s.mean = sum / n;
    return s;
}

double norm3(const double* a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

double distance3(const double* a, const double* b) {
    const double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return norm3(d);
}

void triangle_cross(const double* a, const double* b, const double* c, double n[3]) {
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
}

int name_matches(const char* name, const char* filter) { return !filter || strstr(name, filter) != NULL; }

int bench_filter_arg(const char* arg, const char** filter, void (*usage)(void)) {
    if (!*filter && arg[0] != '-') {
        *filter = arg;
        return -1;
    }
    usage();
    return strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0 ? 0 : 2;
}

const char* material_name(sh_material_model model) {
    static const char* const kNames[SH_MATERIAL_COUNT] = {"linear", "stvk", "corotational", "neohookean"};
    return (int)model >= 0 && model < SH_MATERIAL_COUNT ? kNames[model] : "?";
}

static int file_exists(const char* dir, const char* name) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE* f = fopen(path, "r");
    if (f) fclose(f);
    return f != NULL;
}

const char* bench_find_mesh_dir(const char* given, const char* probe) {
    if (given) return given;
    const char* candidates[] = {getenv("SOFTHAP_MESHES"), SOFTHAP_BENCH_MESH_DIR, "../shared/meshes", "../../shared/meshes"};
    for (size_t k = 0; k < sizeof candidates / sizeof candidates[0]; ++k)
        if (candidates[k] && file_exists(candidates[k], probe)) return candidates[k];
    fprintf(stderr, "softhap_bench: meshes not found; pass --meshes DIR\n");
    return NULL;
}

sh_mesh* bench_load_mesh(const char* dir, const char* file) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, file);
    sh_mesh* mesh = NULL;
    if (sh_mesh_load(path, &mesh) != SH_OK) {
        fprintf(stderr, "softhap_bench: cannot load %s: %s\n", path, sh_last_error_message());
        return NULL;
    }
    return mesh;
}

int bench_load_scaled_mesh(const char* dir, const char* file, const double* turn, double size, sh_mesh** out_mesh,
                           double** out_nodes) {
    sh_mesh* raw = bench_load_mesh(dir, file);
    if (!raw) return 0;
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(raw, &info));
    const int32_t n = info.node_count, t = info.tet_count;
    double* nodes = (double*)xmalloc(sizeof(double) * 3 * (size_t)n);
    int32_t* tets = (int32_t*)xmalloc(sizeof(int32_t) * 4 * (size_t)t);
    CHECK(sh_mesh_get_nodes(raw, nodes, n));
    CHECK(sh_mesh_get_tets(raw, tets, t));
    CHECK(sh_mesh_destroy(raw));
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = info.bounds_min[k];
        hi[k] = info.bounds_max[k];
    }
    if (turn) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = INFINITY;
            hi[k] = -INFINITY;
        }
        for (int32_t i = 0; i < n; ++i) {
            double* p = &nodes[3 * i];
            const double q[3] = {p[0], p[1], p[2]};
            for (int r = 0; r < 3; ++r) {
                p[r] = turn[3 * r] * q[0] + turn[3 * r + 1] * q[1] + turn[3 * r + 2] * q[2];
                if (p[r] < lo[r]) lo[r] = p[r];
                if (p[r] > hi[r]) hi[r] = p[r];
            }
        }
    }
    double extent = 0.0;
    for (int k = 0; k < 3; ++k)
        if (hi[k] - lo[k] > extent) extent = hi[k] - lo[k];
    const double scale = size / extent;
    for (int32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) nodes[3 * i + k] = (nodes[3 * i + k] - lo[k]) * scale;
    CHECK(sh_mesh_create(nodes, n, tets, t, out_mesh));
    free(tets);
    *out_nodes = nodes;
    return 1;
}

int32_t* bench_surface_triangles(const sh_mesh* mesh, int32_t* out_count) {
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(mesh, &info));
    int32_t* tris = (int32_t*)xmalloc(sizeof(int32_t) * 3 * (size_t)info.surface_triangle_count);
    CHECK(sh_mesh_get_surface_triangles(mesh, tris, info.surface_triangle_count));
    *out_count = info.surface_triangle_count;
    return tris;
}

sh_world* bench_world_create(int gravity) {
    sh_world_def wd;
    sh_world_def_default(&wd);
    if (!gravity) wd.gravity[0] = wd.gravity[1] = wd.gravity[2] = 0.0;
    sh_world* world = NULL;
    CHECK(sh_world_create(&wd, &world));
    return world;
}

sh_fem_body_def bench_fem_body_def(const sh_mesh* mesh, sh_material_model model, double young, double poisson,
                                   double density) {
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = model;
    def.material.young = young;
    def.material.poisson = poisson;
    def.material.density = density;
    return def;
}

sh_collider_def bench_sphere_def(double radius, const double position[3]) {
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_SPHERE;
    def.shape.radius = radius;
    for (int k = 0; k < 3; ++k) def.position[k] = position[k];
    return def;
}

int bench_current_cpu(void) {
#ifdef __linux__
    return sched_getcpu();
#else
    return -1;
#endif
}

void bench_pin_thread(int cpu) {
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

double bench_load_average(double unknown) {
    double load = unknown;
    FILE* f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &load) != 1) load = unknown;
        fclose(f);
    }
    return load;
}
