/* sh_mesh_create validation and the derived topology through the public C API: bad tets and
 * coordinates are refused naming the element or node; inverted tets are reoriented; the
 * surface is a closed, outward oriented manifold (checked by edge pairing and by the
 * divergence theorem); edge counts match a hand count and Euler's formula; orphans are kept. */
#include "test_support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The unit right-handed tet (volume 1/6) and a fifth node beyond its face (1, 2, 3). */
static const double kNodes[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};

/* Creates a mesh expecting status; every non-NULL fragment must be in the error message. */
static void expect_create(const double* nodes, int32_t node_count, const int32_t* tets, int32_t tet_count,
                          sh_status status, const char* fragment1, const char* fragment2) {
    sh_mesh* mesh = (sh_mesh*)&mesh; /* any non-NULL value: a failure must reset it */
    assert_status(sh_mesh_create(nodes, node_count, tets, tet_count, &mesh), status);
    assert_null(mesh);
    const char* fragments[2] = {fragment1, fragment2};
    for (int i = 0; i < 2; ++i)
        if (fragments[i] && !strstr(sh_last_error_message(), fragments[i])) {
            print_error("message \"%s\" lacks \"%s\"\n", sh_last_error_message(), fragments[i]);
            fail();
        }
}

/* ------------------------------------------------------------------------------------------ */
/* Validation                                                                                   */

static void test_index_out_of_range(void** state) {
    (void)state;
    const int32_t too_big[8] = {0, 1, 2, 3, 1, 2, 3, 5};
    expect_create(kNodes, 5, too_big, 2, SH_ERR_DEGENERATE_MESH, "tet 1", "node index 5 out of range");
    const int32_t negative[4] = {0, 1, 2, -1};
    expect_create(kNodes, 5, negative, 1, SH_ERR_DEGENERATE_MESH, "tet 0", "node index -1 out of range");
}

static void test_repeated_node_in_tet(void** state) {
    (void)state;
    const int32_t tets[8] = {1, 2, 3, 4, 0, 1, 1, 3};
    expect_create(kNodes, 5, tets, 2, SH_ERR_DEGENERATE_MESH, "tet 1", "repeats node 1");
}

static void test_duplicate_tet(void** state) {
    (void)state;
    const int32_t same[12] = {0, 1, 2, 3, 1, 2, 3, 4, 0, 1, 2, 3};
    expect_create(kNodes, 5, same, 3, SH_ERR_DEGENERATE_MESH, "tet 2 duplicates tet 0", NULL);
    const int32_t permuted[12] = {0, 1, 2, 3, 1, 2, 3, 4, 3, 1, 0, 2};
    expect_create(kNodes, 5, permuted, 3, SH_ERR_DEGENERATE_MESH, "tet 2 duplicates tet 0", NULL);
    const int32_t inverted_copy[12] = {0, 1, 2, 3, 1, 2, 3, 4, 4, 2, 3, 1};
    expect_create(kNodes, 5, inverted_copy, 3, SH_ERR_DEGENERATE_MESH, "tet 2 duplicates tet 1", NULL);
}

static void test_flat_tet(void** state) {
    (void)state;
    const double flat[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5, 0.5, 0};
    const int32_t tets[8] = {0, 1, 2, 3, 0, 1, 2, 4}; /* node 4 lies in the plane of 0, 1, 2 */
    expect_create(flat, 5, tets, 2, SH_ERR_DEGENERATE_MESH, "tet 1", "zero volume");
    const double collinear[12] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3};
    const int32_t one[4] = {0, 1, 2, 3};
    expect_create(collinear, 4, one, 1, SH_ERR_DEGENERATE_MESH, "tet 0", "zero volume");
}

static void test_non_finite_coordinates(void** state) {
    (void)state;
    const int32_t tets[8] = {0, 1, 2, 3, 1, 2, 3, 4};
    double nodes[15];
    const double bad[3] = {NAN, INFINITY, -INFINITY};
    for (int i = 0; i < 3; ++i) {
        memcpy(nodes, kNodes, sizeof nodes);
        nodes[3 * 2 + i] = bad[i]; /* node 2, coordinate i */
        expect_create(nodes, 5, tets, 2, SH_ERR_DEGENERATE_MESH, "node 2 ", "non-finite");
    }
    memcpy(nodes, kNodes, sizeof nodes);
    nodes[3 * 4 + 2] = NAN; /* even a node no tet of the first uses */
    expect_create(nodes, 5, tets, 2, SH_ERR_DEGENERATE_MESH, "node 4 ", "non-finite");
}

static void test_bad_arguments(void** state) {
    (void)state;
    const int32_t tets[4] = {0, 1, 2, 3};
    sh_mesh* mesh = NULL;
    expect_create(NULL, 4, tets, 1, SH_ERR_INVALID_ARGUMENT, "nodes", NULL);
    expect_create(kNodes, 4, NULL, 1, SH_ERR_INVALID_ARGUMENT, "tets", NULL);
    expect_create(kNodes, -1, tets, 1, SH_ERR_INVALID_ARGUMENT, "node_count", NULL);
    expect_create(kNodes, 0, tets, 1, SH_ERR_INVALID_ARGUMENT, "node_count", NULL);
    expect_create(kNodes, 4, tets, -3, SH_ERR_INVALID_ARGUMENT, "tet_count", NULL);
    expect_create(kNodes, 4, tets, 0, SH_ERR_INVALID_ARGUMENT, "tet_count", NULL);
    assert_status(sh_mesh_create(kNodes, 4, tets, 1, NULL), SH_ERR_INVALID_ARGUMENT);

    /* Output buffers: NULL or too small. */
    assert_ok(sh_mesh_create(kNodes, 4, tets, 1, &mesh));
    double nodes[12];
    int32_t out[4];
    assert_status(sh_mesh_get_nodes(mesh, NULL, 4), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_mesh_get_nodes(mesh, nodes, 3), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_mesh_get_tets(mesh, out, 0), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_mesh_get_info(mesh, NULL), SH_ERR_INVALID_ARGUMENT);
    assert_ok(sh_mesh_destroy(mesh));
}

/* Parity of the permutation taking `from` to `to` (both hold the same 4 distinct values). */
static int is_odd_permutation(const int32_t from[4], const int32_t to[4]) {
    int position[4];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (to[i] == from[j]) position[i] = j;
    int inversions = 0;
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) inversions += position[i] > position[j];
    return inversions % 2;
}

static void test_inverted_tet_is_reoriented(void** state) {
    (void)state;
    const int32_t tets[8] = {1, 2, 3, 4, 0, 2, 1, 3}; /* tet 1 is the unit tet, inverted */
    assert_true(sh_test_tet_volume(kNodes, &tets[4]) < 0);
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_create(kNodes, 5, tets, 2, &mesh));
    const sh_mesh_info info = sh_test_mesh_info(mesh);
    assert_int_equal(info.reoriented_tet_count, 1);
    assert_close(info.volume, 1.0 / 6.0 + 1.0 / 3.0, 1e-15); /* tet 0 = (1,2,3,4) has volume 1/3 */

    int32_t out[8];
    assert_ok(sh_mesh_get_tets(mesh, out, 2));
    assert_memory_equal(out, tets, 4 * sizeof(int32_t)); /* the good tet is untouched */
    int32_t sorted_in[4] = {0, 1, 2, 3}, sorted_out[4];
    memcpy(sorted_out, &out[4], sizeof sorted_out);
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
            if (sorted_out[j] < sorted_out[i]) {
                const int32_t t = sorted_out[i];
                sorted_out[i] = sorted_out[j];
                sorted_out[j] = t;
            }
    assert_memory_equal(sorted_out, sorted_in, sizeof sorted_in); /* same nodes */
    assert_true(is_odd_permutation(&tets[4], &out[4]));           /* an odd swap of them */
    assert_close(sh_test_tet_volume(kNodes, &out[4]), 1.0 / 6.0, 1e-15);
    assert_ok(sh_mesh_destroy(mesh));
}

static void test_destroyed_mesh_is_an_invalid_handle(void** state) {
    (void)state;
    sh_mesh* mesh = sh_test_unit_tet(1.0);
    sh_mesh_info info;
    assert_ok(sh_mesh_destroy(mesh));
    assert_status(sh_mesh_get_info(mesh, &info), SH_ERR_INVALID_HANDLE);
    assert_status(sh_mesh_destroy(mesh), SH_ERR_INVALID_HANDLE);
    assert_ok(sh_mesh_destroy(NULL));
    assert_status(sh_mesh_get_info(NULL, &info), SH_ERR_INVALID_HANDLE);
}

/* ------------------------------------------------------------------------------------------ */
/* Surface and edges                                                                            */

typedef sh_test_mesh_arrays surface;

/* Divergence theorem with F = x/3: volume = sum over outward triangles of p0 . (p1-p0)x(p2-p0) / 6. */
static double enclosed_volume(const surface* s) {
    double volume = 0.0;
    for (int32_t t = 0; t < s->triangle_count; ++t) {
        const double* p0 = &s->nodes[3 * s->triangles[3 * t]];
        const double* p1 = &s->nodes[3 * s->triangles[3 * t + 1]];
        const double* p2 = &s->nodes[3 * s->triangles[3 * t + 2]];
        const double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        const double v[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        volume += (p0[0] * (u[1] * v[2] - u[2] * v[1]) + p0[1] * (u[2] * v[0] - u[0] * v[2]) +
                   p0[2] * (u[0] * v[1] - u[1] * v[0])) / 6.0;
    }
    return volume;
}

static int compare_int64(const void* a, const void* b) {
    const int64_t x = *(const int64_t*)a, y = *(const int64_t*)b;
    return (x > y) - (x < y);
}

/* Every directed edge a->b of the triangles occurs exactly once and b->a occurs too: each
 * surface edge is shared by exactly two triangles that traverse it in opposite directions. */
static void assert_closed_oriented_manifold(const surface* s) {
    const size_t count = 3 * (size_t)s->triangle_count;
    int64_t* edges = malloc(sizeof(int64_t) * count);
    for (int32_t t = 0; t < s->triangle_count; ++t)
        for (int k = 0; k < 3; ++k) {
            const int64_t a = s->triangles[3 * t + k], b = s->triangles[3 * t + (k + 1) % 3];
            edges[3 * (size_t)t + (size_t)k] = a * s->node_count + b;
        }
    qsort(edges, count, sizeof(int64_t), compare_int64);
    for (size_t i = 0; i < count; ++i) {
        if (i > 0) assert_true(edges[i] != edges[i - 1]);
        const int64_t reverse = (edges[i] % s->node_count) * s->node_count + edges[i] / s->node_count;
        assert_non_null(bsearch(&reverse, edges, count, sizeof(int64_t), compare_int64));
    }
    free(edges);
}

static void test_surface_of_unit_tet(void** state) {
    (void)state;
    sh_mesh* mesh = sh_test_unit_tet(2.0);
    const sh_mesh_info info = sh_test_mesh_info(mesh);
    assert_int_equal(info.surface_triangle_count, 4);
    assert_int_equal(info.edge_count, 6);
    surface s = sh_test_mesh_arrays_of(mesh);
    assert_closed_oriented_manifold(&s);
    assert_close(enclosed_volume(&s), 8.0 / 6.0, 1e-14);
    sh_test_mesh_arrays_free(&s);
    assert_ok(sh_mesh_destroy(mesh));
}

/* Edges of the Kuhn-split box by hand: axis-aligned grid edges, one diagonal per square face,
 * one main diagonal per cube. */
static int32_t box_edges(int nx, int ny, int nz) {
    const int axis = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz;
    const int faces = nx * ny * (nz + 1) + ny * nz * (nx + 1) + nx * nz * (ny + 1);
    return axis + faces + nx * ny * nz;
}

static void test_kuhn_cube_counts(void** state) {
    (void)state;
    sh_mesh* mesh = sh_test_box(1, 1, 1, 1, 1, 1);
    const sh_mesh_info info = sh_test_mesh_info(mesh);
    assert_int_equal(info.node_count, 8);
    assert_int_equal(info.tet_count, 6);
    assert_int_equal(info.surface_triangle_count, 12);
    assert_int_equal(info.edge_count, 19); /* 12 cube edges, 6 face diagonals, 1 main diagonal */
    assert_int_equal(box_edges(1, 1, 1), 19);
    assert_close(info.volume, 1.0, 1e-14);
    assert_ok(sh_mesh_destroy(mesh));
}

static void test_surface_and_edges_of_box(void** state) {
    (void)state;
    const int nx = 2, ny = 3, nz = 4;
    const double lx = 1.5, ly = 2.0, lz = 0.5;
    sh_mesh* mesh = sh_test_box(lx, ly, lz, nx, ny, nz);
    const sh_mesh_info info = sh_test_mesh_info(mesh);
    assert_int_equal(info.node_count, (nx + 1) * (ny + 1) * (nz + 1));
    assert_int_equal(info.tet_count, 6 * nx * ny * nz);
    assert_int_equal(info.surface_triangle_count, 2 * 2 * (nx * ny + ny * nz + nx * nz));
    assert_int_equal(info.edge_count, box_edges(nx, ny, nz));
    /* Euler characteristic of a ball: V - E + F - T = 1, with every interior face counted once. */
    const int faces = (4 * info.tet_count + info.surface_triangle_count) / 2;
    assert_int_equal(info.node_count - info.edge_count + faces - info.tet_count, 1);
    assert_close(info.volume, lx * ly * lz, 1e-14);
    for (int k = 0; k < 3; ++k) assert_close(info.bounds_min[k], 0.0, 0.0);
    assert_close(info.bounds_max[0], lx, 1e-15);
    assert_close(info.bounds_max[1], ly, 1e-15);
    assert_close(info.bounds_max[2], lz, 1e-15);

    surface s = sh_test_mesh_arrays_of(mesh);
    assert_closed_oriented_manifold(&s);
    assert_close(enclosed_volume(&s), lx * ly * lz, 1e-13);
    sh_test_mesh_arrays_free(&s);

    /* Edges: (smaller, larger), strictly increasing, and every tet edge among them. */
    int32_t* edges = malloc(sizeof(int32_t) * 2 * (size_t)info.edge_count);
    int32_t* tets = malloc(sizeof(int32_t) * 4 * (size_t)info.tet_count);
    assert_ok(sh_mesh_get_edges(mesh, edges, info.edge_count));
    assert_ok(sh_mesh_get_tets(mesh, tets, info.tet_count));
    int64_t* keys = malloc(sizeof(int64_t) * (size_t)info.edge_count);
    for (int32_t e = 0; e < info.edge_count; ++e) {
        assert_true(edges[2 * e] < edges[2 * e + 1]);
        keys[e] = (int64_t)edges[2 * e] * info.node_count + edges[2 * e + 1];
        if (e > 0) assert_true(keys[e] > keys[e - 1]);
    }
    for (int32_t t = 0; t < info.tet_count; ++t)
        for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b) {
                const int32_t i = tets[4 * t + a], j = tets[4 * t + b];
                const int64_t key = (int64_t)(i < j ? i : j) * info.node_count + (i < j ? j : i);
                assert_non_null(bsearch(&key, keys, (size_t)info.edge_count, sizeof(int64_t), compare_int64));
            }
    free(keys);
    free(tets);
    free(edges);
    assert_ok(sh_mesh_destroy(mesh));
}

/* A loaded organ: closed oriented surface enclosing the tets' volume (computed independently
 * with numpy over the file). */
static void check_organ_surface(const char* path, double expected_volume) {
    print_message("%s\n", path);
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_load(path, &mesh));
    surface s = sh_test_mesh_arrays_of(mesh);
    assert_closed_oriented_manifold(&s);
    assert_close(enclosed_volume(&s), sh_test_mesh_info(mesh).volume, 1e-10);
    assert_close(sh_test_mesh_info(mesh).volume, expected_volume, 1e-10);
    sh_test_mesh_arrays_free(&s);
    assert_ok(sh_mesh_destroy(mesh));
}

static void test_surface_of_liver_and_armadillo(void** state) {
    (void)state;
    check_organ_surface(SH_TEST_MESH("liver.msh"), 36.56085106149482);
    check_organ_surface(SH_TEST_MESH("Armadillo_Tetra_4406.vtu"), 231.21430723500526);
}

/* Orphans (README: 3 and 2 for the raptors) are kept, used by no tet and on no surface. */
static void check_orphans(const char* path, int32_t expected) {
    print_message("%s\n", path);
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_load(path, &mesh));
    const sh_mesh_info info = sh_test_mesh_info(mesh);
    assert_int_equal(info.orphan_node_count, expected);
    int32_t* tets = malloc(sizeof(int32_t) * 4 * (size_t)info.tet_count);
    char* used = calloc((size_t)info.node_count, 1);
    assert_ok(sh_mesh_get_tets(mesh, tets, info.tet_count));
    for (int32_t i = 0; i < 4 * info.tet_count; ++i) used[tets[i]] = 1;
    int32_t unused = 0;
    for (int32_t n = 0; n < info.node_count; ++n) unused += !used[n];
    assert_int_equal(unused, expected);
    surface s = sh_test_mesh_arrays_of(mesh);
    for (int32_t i = 0; i < 3 * s.triangle_count; ++i) assert_true(used[s.triangles[i]]);
    assert_close(enclosed_volume(&s), info.volume, 1e-10);
    sh_test_mesh_arrays_free(&s);
    free(used);
    free(tets);
    assert_ok(sh_mesh_destroy(mesh));
}

static void test_orphans_of_raptors(void** state) {
    (void)state;
    check_orphans(SH_TEST_MESH("raptorTetra_8418.vtu"), 3);
    check_orphans(SH_TEST_MESH("raptorTetra_19409.vtu"), 2);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_index_out_of_range),
        cmocka_unit_test(test_repeated_node_in_tet),
        cmocka_unit_test(test_duplicate_tet),
        cmocka_unit_test(test_flat_tet),
        cmocka_unit_test(test_non_finite_coordinates),
        cmocka_unit_test(test_bad_arguments),
        cmocka_unit_test(test_inverted_tet_is_reoriented),
        cmocka_unit_test(test_destroyed_mesh_is_an_invalid_handle),
        cmocka_unit_test(test_surface_of_unit_tet),
        cmocka_unit_test(test_kuhn_cube_counts),
        cmocka_unit_test(test_surface_and_edges_of_box),
        cmocka_unit_test(test_surface_of_liver_and_armadillo),
        cmocka_unit_test(test_orphans_of_raptors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
