/* The tissues the haptic studies press: the cost study's block and SOFA's livers, each with its
 * fixed base, the point the tool presses and (haptic-force) the direction it slides. */
#include "haptic_common.h"

#include "box_mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The block: 6 x 6 x 3 cm in 12 x 12 x 6 cubes (5 mm cells). */
static const double kBlock[3] = {0.06, 0.06, 0.03}; /* m */
static const int kBlockCells[3] = {12, 12, 6};

/* The livers: scaled to 16 cm, the lowest 10 % of their height fixed, pressed over at least
 * 3 cm of tissue. */
static const double kLiverSize = 0.16;          /* m */
static const double kLiverFixedFraction = 0.10; /* of its height */
static const double kMinThickness = 0.03;       /* m of tissue under the press point */

/* Fills t's arrays from t->mesh and fixes the nodes at or below base_height. */
static void tissue_finish(tissue* t, double base_height) {
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(t->mesh, &info));
    t->node_count = info.node_count;
    t->tet_count = info.tet_count;
    t->tris = bench_surface_triangles(t->mesh, &t->tri_count);
    t->fixed = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)t->node_count);
    t->fixed_count = 0;
    for (int32_t i = 0; i < t->node_count; ++i)
        if (t->nodes[3 * i + 2] <= base_height) t->fixed[t->fixed_count++] = i;
}

void tissue_free(tissue* t) {
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
        /* Barycentric coordinates of (x, y) in the triangle seen from above. */
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

/* The highest h(p) + sqrt(r^2 - |p - (x, y)|^2) over points p on rings of the disc under the
 * sphere: where its lower half first meets the surface, not only its lowest point. */
double touch_height(const tissue* t, double x, double y) {
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

void touch_point(const tissue* t, double out[3]) {
    out[0] = t->press[0];
    out[1] = t->press[1];
    out[2] = touch_height(t, t->press[0], t->press[1]);
}

tissue make_block(void) {
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

/* The press point: the centroid of the largest facet of the top that is nearly level (normal
 * within 25 degrees of +z), seen from above, over at least kMinThickness of tissue, so that the
 * press is into the organ's bulk and not its rim. 0 if there is none. */
static int choose_press_point(tissue* t) {
    double best_area = 0.0;
    for (int32_t k = 0; k < t->tri_count; ++k) {
        const double* a = &t->nodes[3 * t->tris[3 * k]];
        const double* b = &t->nodes[3 * t->tris[3 * k + 1]];
        const double* c = &t->nodes[3 * t->tris[3 * k + 2]];
        double n[3];
        triangle_cross(a, b, c, n);
        const double area = 0.5 * norm3(n);
        if (area <= best_area || n[2] < cos(25.0 * kPi / 180.0) * 2.0 * area) continue;
        const double cx = (a[0] + b[0] + c[0]) / 3.0, cy = (a[1] + b[1] + c[1]) / 3.0, cz = (a[2] + b[2] + c[2]) / 3.0;
        double top, bottom;
        if (!vertical_crossings(t, cx, cy, &top, &bottom) || top > cz + 1e-9 || top - bottom < kMinThickness) continue;
        best_area = area;
        t->press[0] = cx;
        t->press[1] = cy;
    }
    return best_area != 0.0;
}

/* The slide direction: the one of eight along which the touching height varies least over
 * kTraceSlide, so that a slide at a fixed depth stays in contact. 0 if no direction stays on
 * the surface. */
static int choose_slide(tissue* t) {
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
    return isfinite(best_range);
}

int make_liver(tissue* t, const char* dir, const char* file, const char* name) {
    /* File +y (the flattest side) down: (x, y, z) -> (x, z, -y). */
    static const double kTurn[9] = {1, 0, 0, 0, 0, 1, 0, -1, 0};
    memset(t, 0, sizeof *t);
    t->name = name;
    if (!bench_load_scaled_mesh(dir, file, kTurn, kLiverSize, &t->mesh, &t->nodes)) return 0;
    double height = 0.0;
    sh_mesh_info info;
    CHECK(sh_mesh_get_info(t->mesh, &info));
    for (int32_t i = 0; i < info.node_count; ++i)
        if (t->nodes[3 * i + 2] > height) height = t->nodes[3 * i + 2];
    tissue_finish(t, kLiverFixedFraction * height);
    if (!choose_press_point(t)) {
        fprintf(stderr, "softhap_bench: the liver has no level top facet to press\n");
        return 0;
    }
    if (!choose_slide(t)) {
        fprintf(stderr, "softhap_bench: no slide path on the liver's top\n");
        return 0;
    }
    return 1;
}
