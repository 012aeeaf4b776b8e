/* A scene pays only for what it uses: an explicit FEM body holds its node state and element
 * blocks and nothing else (no sparse stiffness matrix, no factorisation, no topology it cannot
 * use). Memory is counted through sh_set_allocator. Also reports the optional components. */
#define _POSIX_C_SOURCE 200112L
#include "test_support.h"

#include <stdio.h>
#include <stdlib.h>

static size_t g_live_bytes = 0;

typedef struct {
    size_t size;
    size_t pad[7]; /* keeps the payload 64-byte aligned after the header */
} header;

static void* counting_alloc(size_t size, size_t alignment, void* user) {
    (void)user;
    if (alignment > 64) return NULL;
    void* block = NULL;
    if (posix_memalign(&block, 64, sizeof(header) + size) != 0) return NULL;
    header* h = block;
    h->size = size;
    g_live_bytes += size;
    return h + 1;
}

static void counting_free(void* ptr, void* user) {
    (void)user;
    if (!ptr) return;
    header* h = (header*)ptr - 1;
    g_live_bytes -= h->size;
    free(h);
}

static int setup(void** state) {
    (void)state;
    const sh_allocator allocator = {counting_alloc, counting_free, NULL};
    return sh_set_allocator(&allocator) == SH_OK ? 0 : -1;
}

static int teardown(void** state) {
    (void)state;
    return sh_set_allocator(NULL) == SH_OK ? 0 : -1;
}

/* Budget of an explicit FEM body, derived from what it must store:
 * per tet: 4 node indices, Bm (9 doubles), V0, its material (4 words), and the same in the
 * lane-blocked copy the kernels read: about 240 bytes; per node: x, v, external force, target
 * and the integrator's stage arrays (RK4 needs 8 vectors of 3 doubles) plus mass: about 360
 * bytes. A sparse stiffness matrix alone would need 9 x (nodes + 2 edges) x 12 bytes, more
 * than 1000 bytes per node. */
static void test_explicit_body_memory(void** state) {
    (void)state;
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_load(SH_TEST_MESH("raptorTetra_19409.vtu"), &mesh));
    sh_mesh_info info;
    assert_ok(sh_mesh_get_info(mesh, &info));
    sh_world_def wd;
    sh_world_def_default(&wd);
    sh_world* world = NULL;
    assert_ok(sh_world_create(&wd, &world));
    const size_t before = g_live_bytes;
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    for (int s = 0; s < 3; ++s) assert_ok(sh_world_step(world, 1e-4, NULL));
    const size_t used = g_live_bytes - before;
    const size_t budget = 320 * (size_t)info.tet_count + 420 * (size_t)info.node_count;
    const size_t sparse_matrix = 9 * ((size_t)info.node_count + 2 * (size_t)info.edge_count) * 12;
    print_message("explicit body on %d tets, %d nodes: %zu bytes (budget %zu; a sparse K alone: %zu)\n",
                  info.tet_count, info.node_count, used, budget, sparse_matrix);
    assert_true(used <= budget);
    assert_true(budget < used + sparse_matrix);
    assert_ok(sh_world_destroy(world));
    assert_ok(sh_mesh_destroy(mesh));
    assert_int_equal(g_live_bytes, 0);
}

/* The build options are visible at run time; tests of an option left out are skipped. */
static void test_build_features(void** state) {
    (void)state;
    const uint32_t features = sh_build_features();
#ifdef SOFTHAP_TEST_WITH_CHOLMOD
    assert_true(features & SH_FEATURE_CHOLMOD);
#else
    assert_false(features & SH_FEATURE_CHOLMOD);
    print_message("built without CHOLMOD: implicit-solver tests are skipped\n");
#endif
#ifdef SOFTHAP_TEST_WITH_CCD
    assert_true(features & SH_FEATURE_CCD);
#else
    assert_false(features & SH_FEATURE_CCD);
    print_message("built without libccd: convex-shape tests are skipped\n");
#endif
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_explicit_body_memory, setup, teardown),
        cmocka_unit_test(test_build_features),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
