/* The softhap_bench cut study's scene (cut_scene.h): meshes, bodies, blade quads, timed calls. */
#include "cut_scene.h"

#include "bench_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double kBaseFraction = 0.1; /* nodes this fraction of the height above the lowest are fixed */
static const double kYoung = 3.0e4;      /* Pa: soft tissue, as the step benches */
static const double kPoisson = 0.45;
static const double kDensity = 1000.0;   /* kg/m^3 */
static const double kBladePlane = 0.47;  /* the blade's plane, as a fraction of the box along its normal */
static const double kBladeReach = 0.2;   /* past the box along span, as a fraction of the box there */

/* The mesh's bounding box from its nodes x[0..3n) into m. */
static void set_bounds(const double* x, int32_t n, cut_mesh* m) {
    for (int k = 0; k < 3; ++k) {
        m->lo[k] = INFINITY;
        m->hi[k] = -INFINITY;
    }
    for (int32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            if (x[3 * i + k] < m->lo[k]) m->lo[k] = x[3 * i + k];
            if (x[3 * i + k] > m->hi[k]) m->hi[k] = x[3 * i + k];
        }
}

/* The box's axes, longest first, into m->run, m->span and m->normal. */
static void set_axes(cut_mesh* m) {
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j)
            if (m->hi[order[j]] - m->lo[order[j]] > m->hi[order[i]] - m->lo[order[i]]) {
                const int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    m->run = order[0];
    m->span = order[1];
    m->normal = order[2];
}

/* The nodes of x[0..3n) less than kBaseFraction of the height above the lowest into m->fixed. */
static void set_base(const double* x, int32_t n, cut_mesh* m) {
    const double top = m->lo[2] + kBaseFraction * (m->hi[2] - m->lo[2]);
    m->fixed = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)n);
    m->fixed_count = 0;
    for (int32_t i = 0; i < n; ++i)
        if (x[3 * i + 2] < top) m->fixed[m->fixed_count++] = i;
}

/* The mean length of the mesh's edges over its nodes x (m). */
static double mean_edge(const sh_mesh* mesh, const double* x) {
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(mesh, &info));
    int32_t* edges = (int32_t*)xmalloc(sizeof(int32_t) * 2 * (size_t)info.edge_count);
    CHECK(sh_mesh_get_edges(mesh, edges, info.edge_count));
    double sum = 0.0;
    for (int32_t e = 0; e < info.edge_count; ++e) sum += distance3(&x[3 * edges[2 * e]], &x[3 * edges[2 * e + 1]]);
    free(edges);
    return sum / info.edge_count;
}

int cut_mesh_load(const char* dir, const char* file, const char* name, double scale, double size, cut_mesh* m) {
    memset(m, 0, sizeof *m);
    m->name = name;
    double* x = NULL;
    if (scale > 0.0) {
        sh_mesh* raw = bench_load_mesh(dir, file);
        if (!raw) return 0;
        CHECK(sh_mesh_transform(raw, scale, NULL, &m->mesh));
        CHECK(sh_mesh_destroy(raw));
    } else if (!bench_load_scaled_mesh(dir, file, NULL, size, &m->mesh, &x)) {
        return 0;
    }
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(m->mesh, &info));
    m->node_count = info.node_count;
    m->tet_count = info.tet_count;
    if (!x) {
        x = (double*)xmalloc(sizeof(double) * 3 * (size_t)info.node_count);
        CHECK(sh_mesh_get_nodes(m->mesh, x, info.node_count));
    }
    set_bounds(x, info.node_count, m);
    set_axes(m);
    set_base(x, info.node_count, m);
    m->edge = mean_edge(m->mesh, x);
    free(x);
    return 1;
}

void cut_mesh_free(cut_mesh* m) {
    sh_mesh_destroy(m->mesh);
    free(m->fixed);
}

sh_world* cut_world(const cut_mesh* m, double factor_reuse, sh_body_id* body) {
    sh_world* world = bench_world_create(0);
    sh_fem_body_def def = bench_fem_body_def(m->mesh, SH_MATERIAL_STVK, kYoung, kPoisson, kDensity);
    def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    def.implicit.factor_reuse = factor_reuse;
    CHECK(sh_fem_body_create(world, &def, body));
    CHECK(sh_body_fix_nodes(world, *body, m->fixed, m->fixed_count));
    return world;
}

double blade_at(const cut_mesh* m, double fraction) {
    const double start = m->lo[m->run] - m->edge, end = m->hi[m->run] + m->edge;
    return start + fraction * (end - start);
}

int blade_increments(const cut_mesh* m, int elements) {
    return (int)ceil((blade_at(m, 1.0) - blade_at(m, 0.0)) / (elements * m->edge));
}

void blade_quad(const cut_mesh* m, double s0, double s1, double tris[18]) {
    const double plane = m->lo[m->normal] + kBladePlane * (m->hi[m->normal] - m->lo[m->normal]);
    const double reach = kBladeReach * (m->hi[m->span] - m->lo[m->span]);
    const double run[4] = {s0, s1, s1, s0};
    const double span[4] = {m->lo[m->span] - reach, m->lo[m->span] - reach, m->hi[m->span] + reach, m->hi[m->span] + reach};
    double corners[4][3];
    for (int c = 0; c < 4; ++c) {
        corners[c][m->run] = run[c];
        corners[c][m->span] = span[c];
        corners[c][m->normal] = plane;
    }
    static const int kHalves[6] = {0, 1, 2, 0, 2, 3};
    for (int c = 0; c < 6; ++c) memcpy(&tris[3 * c], corners[kHalves[c]], sizeof corners[0]);
}

timed_cut cut_timed(sh_world* world, sh_body_id body, const double* tris, int32_t count) {
    timed_cut t;
    const double t0 = now_ns();
    CHECK(sh_body_cut(world, body, tris, count, &t.report));
    t.wall = (now_ns() - t0) * 1e-9;
    return t;
}

double step_timed(sh_world* world, double dt, sh_step_report* report, int* failed) {
    const double t0 = now_ns();
    const sh_status status = sh_world_step(world, dt, report);
    const double seconds = (now_ns() - t0) * 1e-9;
    if (status != SH_OK && !(*failed)++)
        fprintf(stderr, "softhap_bench cut: a step failed: %s (%s)\n", sh_status_string(status), sh_last_error_message());
    return seconds;
}
