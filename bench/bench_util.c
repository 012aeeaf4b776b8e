#define _POSIX_C_SOURCE 200809L
#include "bench_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

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
