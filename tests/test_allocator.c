/* sh_set_allocator: every softhap allocation goes through the host allocator, with the
 * alignment it asks for; everything allocated is freed; the step allocates nothing once the
 * scene is built; allocation failures are SH_ERR_OUT_OF_MEMORY without leaks or crashes.
 *
 * The counting allocator stays installed from the first test on (the tests run in order):
 * it only switches to the default allocator in test_restore_default_allocator, when nothing
 * it allocated is alive, so no block is ever freed by the wrong allocator. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>

#include "test_support.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* A counting allocator                                                                         */

typedef struct counter {
    size_t allocs;            /* successful allocations */
    size_t frees;             /* frees of our blocks */
    size_t null_frees;        /* free(NULL) calls */
    long live_blocks;         /* allocs - frees, never reset */
    long long live_bytes;     /* bytes of the live blocks, never reset */
    size_t bad_alignments;    /* requests whose alignment is not a power of two <= 64 */
    size_t misaligned;        /* returned pointers not aligned as asked (never, by construction) */
    size_t foreign_frees;     /* frees of a pointer we did not hand out (or a double free) */
    size_t wrong_user;        /* callbacks called with a user pointer that is not ours */
    size_t max_alignment;     /* largest alignment asked for */
    long fail_after;          /* < 0: never fail; else the (fail_after+1)-th attempt and later fail */
    size_t attempts;          /* allocation attempts since the last reset */
    size_t failed;            /* attempts refused since the last reset */
} counter;

static counter g;

#define BLOCK_MAGIC 0x5348414c4c4f43ULL /* "SHALLOC" */

typedef struct block_header {
    uint64_t magic;
    size_t size;
    void* raw;
    uint64_t pad;
} block_header; /* 32 bytes, sits just before the returned pointer */

static void* counting_alloc(size_t size, size_t alignment, void* user) {
    counter* c = (counter*)user;
    if (c != &g) {
        ++g.wrong_user;
        c = &g;
    }
    if (alignment == 0 || (alignment & (alignment - 1)) != 0 || alignment > 64) ++c->bad_alignments;
    if (alignment > c->max_alignment) c->max_alignment = alignment;
    ++c->attempts;
    if (c->fail_after >= 0 && c->attempts > (size_t)c->fail_after) {
        ++c->failed;
        return NULL;
    }
    const size_t align = alignment < 16 ? 16 : (alignment > 64 ? 64 : alignment);
    unsigned char* raw = malloc(size + sizeof(block_header) + align);
    if (!raw) return NULL;
    uintptr_t p = (uintptr_t)(raw + sizeof(block_header));
    p = (p + align - 1) & ~(uintptr_t)(align - 1);
    if (alignment != 0 && p % alignment != 0) ++c->misaligned;
    block_header h = {BLOCK_MAGIC, size, raw, 0};
    memcpy((unsigned char*)p - sizeof h, &h, sizeof h);
    ++c->allocs;
    ++c->live_blocks;
    c->live_bytes += (long long)size;
    /* Scribble, so that code reading uninitialised memory is more likely to show it. */
    memset((void*)p, 0xcd, size);
    return (void*)p;
}

static void counting_free(void* ptr, void* user) {
    counter* c = (counter*)user;
    if (c != &g) {
        ++g.wrong_user;
        c = &g;
    }
    if (!ptr) {
        ++c->null_frees;
        return;
    }
    block_header h;
    memcpy(&h, (unsigned char*)ptr - sizeof h, sizeof h);
    if (h.magic != BLOCK_MAGIC) { /* not ours, or freed twice: leave it alone */
        ++c->foreign_frees;
        return;
    }
    h.magic = 0;
    memcpy((unsigned char*)ptr - sizeof h, &h, sizeof h);
    ++c->frees;
    --c->live_blocks;
    c->live_bytes -= (long long)h.size;
    free(h.raw);
}

static const sh_allocator k_counting = {counting_alloc, counting_free, &g};

/* Resets the per-test counters (not the live ones) and disables failure injection. */
static void reset_counts(void) {
    g.allocs = g.frees = g.null_frees = 0;
    g.attempts = g.failed = 0;
    g.fail_after = -1;
}

/* Asserts the allocator saw nothing wrong: no bad request, no foreign free, no wrong user. */
static void assert_allocator_sane(void) {
    assert_int_equal(g.bad_alignments, 0);
    assert_int_equal(g.misaligned, 0);
    assert_int_equal(g.foreign_frees, 0);
    assert_int_equal(g.wrong_user, 0);
}

static int setup_install(void** state) {
    (void)state;
    memset(&g, 0, sizeof g);
    g.fail_after = -1;
    return sh_set_allocator(&k_counting) == SH_OK ? 0 : -1;
}

/* ------------------------------------------------------------------------------------------ */
/* Scenes                                                                                       */

/* The nodes of the box with x == 0 (the first node of every row). */
static int32_t x0_nodes(int nx, int ny, int nz, int32_t* out) {
    int32_t count = 0;
    for (int k = 0; k <= nz; ++k)
        for (int j = 0; j <= ny; ++j) out[count++] = (k * (ny + 1) + j) * (nx + 1);
    return count;
}

/* A world created from sh_world_def_default. */
static sh_world* default_world(void) {
    sh_world_def world_def;
    sh_world_def_default(&world_def);
    sh_world* world = NULL;
    assert_ok(sh_world_create(&world_def, &world));
    return world;
}

/* ------------------------------------------------------------------------------------------ */
/* Tests                                                                                        */

static void test_counting_allocator_sees_everything_freed(void** state) {
    (void)state;
    reset_counts();
    const long live_blocks = g.live_blocks;
    const long long live_bytes = g.live_bytes;
    assert_int_equal(live_blocks, 0);

    sh_world* world = default_world();
    sh_mesh* mesh = sh_test_box(0.04, 0.02, 0.02, 4, 2, 2);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    int32_t fixed[32];
    const int32_t fixed_count = x0_nodes(4, 2, 2, fixed);
    assert_ok(sh_body_fix_nodes(world, body, fixed, fixed_count));
    sh_step_report report;
    for (int i = 0; i < 10; ++i) assert_ok(sh_world_step(world, 1e-3, &report));
    assert_true(g.allocs > 0);
    assert_true(g.live_blocks > 0);
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));

    assert_int_equal(g.frees, g.allocs);
    assert_int_equal(g.live_blocks, live_blocks);
    assert_true(g.live_bytes == live_bytes);
    assert_int_equal(g.failed, 0);
    assert_true(g.max_alignment >= 8);
    assert_allocator_sane();
}

static void test_set_allocator_busy_and_invalid(void** state) {
    (void)state;
    reset_counts();
    sh_world_def world_def;
    sh_world_def_default(&world_def);
    sh_world* world = NULL;
    assert_ok(sh_world_create(&world_def, &world));
    const sh_allocator other = {counting_alloc, counting_free, &g};
    assert_status(sh_set_allocator(&other), SH_ERR_BUSY);
    assert_non_null(strstr(sh_last_error_message(), "alive"));
    assert_status(sh_set_allocator(NULL), SH_ERR_BUSY);
    assert_ok(sh_world_destroy(world));

    sh_mesh* mesh = sh_test_unit_tet(0.01); /* a live mesh alone is enough to be busy */
    assert_status(sh_set_allocator(&k_counting), SH_ERR_BUSY);
    assert_status(sh_set_allocator(NULL), SH_ERR_BUSY);
    assert_ok(sh_mesh_destroy(mesh));

    /* Incomplete allocators are invalid arguments, busy or not. */
    const sh_allocator no_alloc = {NULL, counting_free, &g};
    const sh_allocator no_free = {counting_alloc, NULL, &g};
    assert_status(sh_set_allocator(&no_alloc), SH_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(sh_last_error_message(), "alloc"));
    assert_status(sh_set_allocator(&no_free), SH_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(sh_last_error_message(), "free"));

    /* The counting allocator is still the one in use: a new world goes through it. */
    reset_counts();
    assert_ok(sh_world_create(&world_def, &world));
    assert_true(g.allocs > 0);
    assert_ok(sh_world_destroy(world));
    assert_int_equal(g.frees, g.allocs);
    assert_int_equal(g.live_blocks, 0);
    assert_allocator_sane();
}

static void test_restore_default_allocator(void** state) {
    (void)state;
    assert_int_equal(g.live_blocks, 0); /* nothing of ours is alive: switching is safe */
    assert_ok(sh_set_allocator(NULL));
    reset_counts();
    sh_world* world = default_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    assert_ok(sh_world_step(world, 1e-3, NULL));
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
    assert_int_equal(g.attempts, 0); /* the default allocator did it all */
    assert_int_equal(g.frees, 0);
    assert_ok(sh_set_allocator(&k_counting)); /* and back, for the tests that follow */
}

/* Adds to world one FEM body per integrator in fem_integrators (mixed materials, stiffness and
 * per-node damping) and one mesh-edge spring body per (integrator, law) pair, all fixed at
 * x = 0. Creation may allocate; returns the number of bodies. */
static int add_bodies(sh_world* world, const sh_mesh* mesh, const int32_t* fixed, int32_t fixed_count,
                      const sh_integrator* integrators, int integrator_count, sh_body_id* out) {
    sh_mesh_info mesh_info;
    assert_ok(sh_mesh_get_info(mesh, &mesh_info));
    int count = 0;
    for (int k = 0; k < integrator_count; ++k) {
        sh_fem_body_def def;
        sh_fem_body_def_default(&def);
        def.mesh = mesh;
        def.integrator = integrators[k];
        def.damping_mass = 1.0;
        def.damping_stiffness = k == 0 ? 1e-4 : 0.0;
        sh_body_id body;
        assert_ok(sh_fem_body_create(world, &def, &body));
        assert_ok(sh_body_fix_nodes(world, body, fixed, fixed_count));
        const int32_t region[4] = {0, 5, 7, 12};
        const sh_material materials[3] = {sh_test_material(SH_MATERIAL_LINEAR, 5e3, 0.4, 1000),
                                          sh_test_material(SH_MATERIAL_COROTATIONAL, 8e3, 0.3, 1100),
                                          sh_test_material(SH_MATERIAL_NEOHOOKEAN, 4e3, 0.45, 1050)};
        assert_ok(sh_body_set_material(world, body, region, 4, &materials[k % 3]));
        double damping[64];
        assert_true(mesh_info.node_count <= 64);
        for (int i = 0; i < mesh_info.node_count; ++i) damping[i] = 0.5;
        assert_ok(sh_body_set_node_damping(world, body, damping, mesh_info.node_count)); /* Alloc: may */
        out[count++] = body;

        static const double table[8] = {-0.5, -50.0, 0.0, 0.0, 0.2, 10.0, 0.5, 60.0};
        for (int law = 0; law < 4; ++law) {
            sh_spring_body_def spring;
            sh_spring_body_def_default(&spring);
            spring.mesh = mesh;
            spring.integrator = integrators[k];
            spring.params.law = (sh_spring_law)law;
            spring.params.stiffness = 50.0;
            spring.params.damping = 0.01;
            spring.params.lambda1 = 5.0;
            spring.params.lambda2 = 1.0;
            spring.params.a = 2.0;
            spring.params.b = 0.01;
            spring.params.table = table;
            spring.params.table_rows = 4;
            spring.damping_mass = 0.5;
            assert_ok(sh_spring_body_create(world, &spring, &body));
            assert_ok(sh_body_fix_nodes(world, body, fixed, fixed_count));
            out[count++] = body;
        }
    }
    return count;
}

/* Calls every query and setter tagged Alloc: none on each body. */
static void touch_bodies(sh_world* world, const sh_body_id* bodies, int count, const int32_t* fixed) {
    double buffer[3 * 64];
    sh_body_info info;
    double energy;
    uint64_t warnings[SH_WARN_COUNT];
    assert_ok(sh_world_get_warnings(world, warnings));
    for (int b = 0; b < count; ++b) {
        assert_ok(sh_body_get_info(world, bodies[b], &info));
        assert_int_equal(sh_body_is_valid(world, bodies[b]), 1);
        assert_ok(sh_body_get_positions(world, bodies[b], buffer, 64));
        assert_ok(sh_body_set_positions(world, bodies[b], buffer, info.node_count));
        assert_ok(sh_body_get_velocities(world, bodies[b], buffer, 64));
        assert_ok(sh_body_set_velocities(world, bodies[b], buffer, info.node_count));
        assert_ok(sh_body_get_masses(world, bodies[b], buffer, 3 * 64));
        assert_ok(sh_body_get_elastic_forces(world, bodies[b], buffer, 64));
        assert_ok(sh_body_get_elastic_energy(world, bodies[b], &energy));
        for (int i = 0; i < 3 * info.node_count; ++i) buffer[i] = 1e-4;
        assert_ok(sh_body_set_external_forces(world, bodies[b], buffer, info.node_count));
        assert_ok(sh_body_release_nodes(world, bodies[b], fixed, 1));
        assert_ok(sh_body_fix_nodes(world, bodies[b], fixed, 1));
        const double gravity[3] = {0.0, 0.0, -9.81};
        assert_ok(sh_world_set_gravity(world, gravity));
    }
}

/* The scene of the Alloc: none step tests: a 3 x 1 x 1 box (3 cm) with its x == 0 nodes
 * fixed, as every body add_bodies makes for two integrators. The mesh is destroyed (bodies do
 * not need it); then the counts are reset, live_blocks is what is live once the scene is built. */
typedef struct box_bodies {
    sh_world* world;
    int32_t fixed[16];
    sh_body_id bodies[16];
    int count;
    long live_blocks;
} box_bodies;

static box_bodies open_box_bodies(sh_integrator first, sh_integrator second) {
    box_bodies scene;
    reset_counts();
    scene.world = sh_test_world(-9.81);
    sh_mesh* mesh = sh_test_box(0.03, 0.01, 0.01, 3, 1, 1);
    const int32_t fixed_count = x0_nodes(3, 1, 1, scene.fixed);
    const sh_integrator integrators[2] = {first, second};
    scene.count = add_bodies(scene.world, mesh, scene.fixed, fixed_count, integrators, 2, scene.bodies);
    assert_ok(sh_mesh_destroy(mesh));
    reset_counts();
    scene.live_blocks = g.live_blocks;
    return scene;
}

/* No allocation or free since reset_counts, and as many live blocks as before. */
static void assert_nothing_allocated(long live_blocks) {
    assert_int_equal(g.attempts, 0);
    assert_int_equal(g.frees, 0);
    assert_int_equal(g.live_blocks, live_blocks);
}

/* Destroys world and checks that nothing is left live and the allocator's books balance. */
static void destroy_world_checking_leaks(sh_world* world) {
    assert_ok(sh_world_destroy(world));
    assert_int_equal(g.live_blocks, 0);
    assert_allocator_sane();
}

/* "Alloc: none once the scene is built": sh_world_step, with and without a report, with
 * sub-stepping, with every material model and spring law, and the Alloc: none queries,
 * allocate nothing through the installed allocator. Symplectic Euler and RK4 bodies. */
static void test_step_allocates_nothing(void** state) {
    (void)state;
    const box_bodies scene = open_box_bodies(SH_INTEGRATOR_SYMPLECTIC_EULER, SH_INTEGRATOR_RK4);
    /* The scene is built: from here on, nothing may allocate. */
    sh_step_report report;
    for (int i = 0; i < 100; ++i) assert_ok(sh_world_step(scene.world, 1e-3, NULL));
    for (int i = 0; i < 100; ++i) assert_ok(sh_world_step(scene.world, 1e-3, &report));
    assert_true(report.kinetic_energy > 0.0);
    /* A step well above dt_crit sub-steps (SH_UNSTABLE_SUBSTEP): still no allocation. */
    assert_ok(sh_world_step(scene.world, 20.0 * report.dt_critical, &report));
    assert_true(report.substeps > 1);
    touch_bodies(scene.world, scene.bodies, scene.count, scene.fixed);
    for (int i = 0; i < 10; ++i) assert_ok(sh_world_step(scene.world, 1e-3, &report));

    if (g.attempts != 0)
        print_error("%zu allocations (%zu frees) during steps and Alloc: none calls\n", g.attempts, g.frees);
    assert_nothing_allocated(scene.live_blocks);

    destroy_world_checking_leaks(scene.world);
}

/* Same with forward Euler and RK2 bodies, which may blow up and be rolled back
 * (SH_ERR_UNSTABLE): the rollback path allocates nothing either. */
static void test_step_with_rollbacks_allocates_nothing(void** state) {
    (void)state;
    const box_bodies scene = open_box_bodies(SH_INTEGRATOR_FORWARD_EULER, SH_INTEGRATOR_RK2);
    sh_step_report report;
    int unstable = 0;
    for (int i = 0; i < 200; ++i) {
        const sh_status status = sh_world_step(scene.world, 1e-3, i % 2 ? &report : NULL);
        assert_true(status == SH_OK || status == SH_ERR_UNSTABLE);
        unstable += status == SH_ERR_UNSTABLE;
    }
    touch_bodies(scene.world, scene.bodies, scene.count, scene.fixed);
    if (g.attempts != 0)
        print_error("%zu allocations (%zu frees) during steps (%d unstable) and Alloc: none calls\n", g.attempts,
                    g.frees, unstable);
    assert_nothing_allocated(scene.live_blocks);
    destroy_world_checking_leaks(scene.world);
}

/* sh_body_destroy is tagged Alloc: none: removing bodies (the first removal included)
 * allocates nothing, and so it cannot fail with SH_ERR_OUT_OF_MEMORY. */
static void test_remove_body_allocates_nothing(void** state) {
    (void)state;
    reset_counts();
    sh_world* world = sh_test_world(-9.81);
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    sh_body_id bodies[4];
    for (int i = 0; i < 4; ++i) assert_ok(sh_fem_body_create(world, &def, &bodies[i]));
    reset_counts();
    for (int i = 0; i < 4; ++i) assert_ok(sh_body_destroy(world, bodies[i]));
    if (g.attempts != 0) print_error("sh_body_destroy: %zu allocation(s) for 4 removals\n", g.attempts);
    const size_t attempts = g.attempts;
    assert_ok(sh_mesh_destroy(mesh));
    destroy_world_checking_leaks(world);
    assert_int_equal(attempts, 0);
}

/* A step that is rejected (SH_UNSTABLE_REJECT, dt above dt_crit) is still Alloc: none
 * through the installed allocator. */
static void test_rejected_step_allocates_nothing(void** state) {
    (void)state;
    reset_counts();
    sh_world* world = default_world();
    sh_mesh* mesh = sh_test_box(0.01, 0.01, 0.01, 1, 1, 1);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.on_unstable = SH_UNSTABLE_REJECT;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    reset_counts();
    sh_step_report report;
    for (int i = 0; i < 10; ++i) assert_status(sh_world_step(world, 10.0 * info.dt_critical, &report), SH_ERR_UNSTABLE);
    assert_int_equal(report.unstable_body_count, 1);
    assert_int_equal(g.attempts, 0);
    assert_ok(sh_mesh_destroy(mesh));
    destroy_world_checking_leaks(world);
}

/* A call that may fail on an allocation, and the check that a failed one changed nothing. */
typedef sh_status (*fallible_call)(sh_world* world, void* context);
typedef int (*unchanged_check)(sh_world* world, void* context); /* 1 if nothing changed */

/* Runs call with the allocator failing after 0, 1, 2, ... allocations until a run gets all it
 * asks for (which must succeed). Every failed run must return SH_ERR_OUT_OF_MEMORY and pass
 * unchanged; each that does not is printed (naming name) and counted in *failures. Returns
 * the number of failed runs. */
static long fail_each_allocation(sh_world* world, fallible_call call, unchanged_check unchanged, void* context,
                                 const char* name, int* failures) {
    long n = 0;
    for (; n < 100000; ++n) {
        reset_counts();
        g.fail_after = n;
        const sh_status status = call(world, context);
        const size_t failed = g.failed;
        g.fail_after = -1;
        if (failed == 0) {
            assert_ok(status);
            break;
        }
        assert_status(status, SH_ERR_OUT_OF_MEMORY);
        if (!unchanged(world, context)) {
            print_error("%s failing after %ld allocations returned SH_ERR_OUT_OF_MEMORY but changed the body\n", name, n);
            ++*failures;
        }
    }
    return n;
}

/* What the set-material test changes and compares. */
typedef struct {
    sh_body_id body;
    int32_t node_count;
    double masses[64], forces[3 * 64];
} material_case;

static sh_status set_other_material(sh_world* world, void* context) {
    const material_case* c = context;
    const int32_t region[3] = {1, 4, 9};
    const sh_material other = sh_test_material(SH_MATERIAL_COROTATIONAL, 9e3, 0.3, 2500);
    return sh_body_set_material(world, c->body, region, 3, &other);
}

static int masses_and_forces_unchanged(sh_world* world, void* context) {
    const material_case* c = context;
    double masses[64], forces[3 * 64];
    assert_ok(sh_body_get_masses(world, c->body, masses, 64));
    assert_ok(sh_body_get_elastic_forces(world, c->body, forces, 64));
    return memcmp(masses, c->masses, sizeof(double) * (size_t)c->node_count) == 0 &&
           memcmp(forces, c->forces, sizeof(double) * 3 * (size_t)c->node_count) == 0;
}

/* SH_ERR_OUT_OF_MEMORY means "nothing was changed": sh_body_set_material failing on any of
 * its allocations leaves the masses and the elastic forces bitwise as they were. */
static void test_set_material_out_of_memory_changes_nothing(void** state) {
    (void)state;
    reset_counts();
    sh_world* world = sh_test_world(-9.81);
    sh_mesh* mesh = sh_test_box(0.02, 0.01, 0.01, 2, 1, 1);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    sh_body_id body;
    assert_ok(sh_fem_body_create(world, &def, &body));
    assert_ok(sh_mesh_destroy(mesh));
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    assert_true(info.node_count <= 64);
    material_case c = {body, info.node_count, {0}, {0}};
    double x[3 * 64], masses_now[64];
    assert_ok(sh_body_get_positions(world, body, x, 64));
    for (int i = 0; i < 3 * info.node_count; ++i) x[i] *= 1.0 + 0.01 * (i % 5); /* strained */
    assert_ok(sh_body_set_positions(world, body, x, info.node_count));
    assert_ok(sh_body_get_masses(world, body, c.masses, 64));
    assert_ok(sh_body_get_elastic_forces(world, body, c.forces, 64));

    int failures = 0;
    fail_each_allocation(world, set_other_material, masses_and_forces_unchanged, &c, "sh_body_set_material", &failures);
    /* The successful call does change them. */
    assert_ok(sh_body_get_masses(world, body, masses_now, 64));
    assert_true(memcmp(masses_now, c.masses, sizeof(double) * (size_t)info.node_count) != 0);
    destroy_world_checking_leaks(world);
    assert_int_equal(failures, 0);
}

/* A world with the error estimate on and an implicit FEM bar of length (m) x 1 x 1 cm in
 * cells x 1 x 1 cubes, its id in *body. */
static sh_world* implicit_bar(double length, int cells, sh_body_id* body) {
    sh_world_def wd;
    sh_world_def_default(&wd);
    wd.error_estimate = 1;
    sh_world* world = NULL;
    assert_ok(sh_world_create(&wd, &world));
    sh_mesh* mesh = sh_test_box(length, 0.01, 0.01, cells, 1, 1);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    assert_ok(sh_fem_body_create(world, &def, body));
    assert_ok(sh_mesh_destroy(mesh));
    return world;
}

/* What the cut test cuts with and compares; after each failed cut the body steps on. */
typedef struct {
    sh_body_id body;
    sh_body_info before;
    double x[3 * 128];
    double plane_x; /* where the cut's plane x = const lies (m) */
} cut_case;

static sh_status cut_the_bar(sh_world* world, void* context) {
    const cut_case* c = context;
    const double a = c->plane_x; /* crossing the bar's cells, not its node planes */
    const double plane[18] = {a, -1, -1, a, 1, -1, a, 1, 1, a, -1, -1, a, 1, 1, a, -1, 1};
    sh_cut_report report;
    return sh_body_cut(world, c->body, plane, 2, &report);
}

static int uncut_and_steps_on(sh_world* world, void* context) {
    cut_case* c = context;
    sh_body_info now;
    double x_now[3 * 128];
    assert_ok(sh_body_get_info(world, c->body, &now));
    assert_ok(sh_body_get_positions(world, c->body, x_now, 128));
    const int same = now.node_count == c->before.node_count && now.element_count == c->before.element_count &&
                     now.topology_version == c->before.topology_version &&
                     memcmp(x_now, c->x, sizeof(double) * 3 * (size_t)c->before.node_count) == 0;
    assert_ok(sh_world_step(world, 1e-3, NULL));
    assert_ok(sh_body_get_positions(world, c->body, c->x, 128));
    return same;
}

/* A cut of an implicit bar of `cells` 1 cm cubes that runs out of memory anywhere (the cut
 * surface, the split, the separation, the body's new arrays, the world's resized step scratch)
 * returns SH_ERR_OUT_OF_MEMORY and leaves the body exactly as it was: same topology, same
 * positions. The body then still steps, and the cut that finally gets its memory cuts the bar
 * in two (more nodes, a new version). */
static void check_cut_out_of_memory_changes_nothing(int cells, int earlier_cuts) {
    reset_counts();
    cut_case c;
    sh_world* world = implicit_bar(0.01 * cells, cells, &c.body);
    for (int k = 0; k < earlier_cuts; ++k) { /* what the body keeps of them is cut with too */
        c.plane_x = 0.023 + 0.04 * (k + 1);
        assert_ok(cut_the_bar(world, &c));
    }
    c.plane_x = 0.023;
    assert_ok(sh_world_step(world, 1e-3, NULL)); /* the body's solver state exists */
    assert_ok(sh_body_get_info(world, c.body, &c.before));
    assert_true(c.before.node_count <= 128);
    assert_ok(sh_body_get_positions(world, c.body, c.x, 128));
    int failures = 0;
    const long tried = fail_each_allocation(world, cut_the_bar, uncut_and_steps_on, &c, "sh_body_cut", &failures);
    assert_true(tried > 5); /* the cut does allocate: the failures above were tried */
    sh_body_info now;
    assert_ok(sh_body_get_info(world, c.body, &now));
    assert_true(now.node_count > c.before.node_count && now.topology_version > c.before.topology_version);
    assert_ok(sh_world_step(world, 1e-3, NULL));
    destroy_world_checking_leaks(world);
    assert_int_equal(failures, 0);
}

/* On a 4-cube bar the cut changes a third of the tets: the body rebuilds all its elements. */
static void test_cut_out_of_memory_changes_nothing(void** state) {
    (void)state;
    check_cut_out_of_memory_changes_nothing(4, 0);
}

/* On a 16-cube bar it changes a few: the body updates them in place (emptied lanes, new
 * blocks, its surface updated from the changed tets). */
static void test_local_cut_out_of_memory_changes_nothing(void** state) {
    (void)state;
    check_cut_out_of_memory_changes_nothing(16, 0);
}

/* A body's later cut is cut together with what it keeps of the earlier ones (in its rest
 * shape): running out of memory there leaves the body, and what it keeps, as they were. */
static void test_later_cut_out_of_memory_changes_nothing(void** state) {
    (void)state;
    check_cut_out_of_memory_changes_nothing(16, 1);
}

/* What the implicit-step test steps and compares. */
typedef struct {
    sh_body_id body;
    size_t bytes;
    double x[3 * 64], v[3 * 64];
} step_case;

static sh_status step_once(sh_world* world, void* context) {
    (void)context;
    return sh_world_step(world, 1e-3, NULL);
}

static int positions_and_velocities_unchanged(sh_world* world, void* context) {
    const step_case* c = context;
    double x[3 * 64], v[3 * 64];
    assert_ok(sh_body_get_positions(world, c->body, x, 64));
    assert_ok(sh_body_get_velocities(world, c->body, v, 64));
    return memcmp(x, c->x, c->bytes) == 0 && memcmp(v, c->v, c->bytes) == 0;
}

/* The first implicit step builds the body's solver state (and, with the error estimate, the
 * half steps' own): running out of memory anywhere in it leaves positions, velocities and the
 * prescribed motion as they were, so the step then succeeds and the prescribed node still
 * ends exactly on its target. */
static void test_implicit_step_out_of_memory_changes_nothing(void** state) {
    (void)state;
    reset_counts();
    step_case c;
    sh_world* world = implicit_bar(0.02, 2, &c.body);
    sh_body_info info;
    assert_ok(sh_body_get_info(world, c.body, &info));
    assert_true(info.node_count <= 64);
    assert_ok(sh_body_get_positions(world, c.body, c.x, 64));
    const int32_t pulled = 0;
    const double target[3] = {c.x[0] - 1e-3, c.x[1], c.x[2]};
    assert_ok(sh_body_prescribe_positions(world, c.body, &pulled, target, 1));
    assert_ok(sh_body_get_velocities(world, c.body, c.v, 64));
    c.bytes = sizeof(double) * 3 * (size_t)info.node_count;
    int failures = 0;
    fail_each_allocation(world, step_once, positions_and_velocities_unchanged, &c, "sh_world_step", &failures);
    double x_now[3 * 64];
    assert_ok(sh_body_get_positions(world, c.body, x_now, 64));
    assert_memory_equal(x_now, target, sizeof target);
    destroy_world_checking_leaks(world);
    assert_int_equal(failures, 0);
}

/* sh_spring_body_create into a garbage id: on failure the id must be (sh_body_id)SH_NULL_ID. */
static sh_status add_spring_body_or_null(sh_world* world, const sh_spring_body_def* def, sh_body_id* body) {
    body->value = 42;
    const sh_status status = sh_spring_body_create(world, def, body);
    if (status != SH_OK) assert_true(SH_ID_IS_NULL(*body));
    return status;
}

/* The scene of the failure-injection test: every creation call, each may fail with
 * SH_ERR_OUT_OF_MEMORY. Returns the first failing status (SH_OK if all succeeded); whatever
 * was created is destroyed before returning. */
static char g_failure_message[1024]; /* the failing call's last-error message */

static sh_status build_and_destroy_scene(const double* nodes, int32_t node_count, const int32_t* tets,
                                         int32_t tet_count, int* out_stage) {
    sh_world* world = NULL;
    sh_mesh* mesh = NULL;
    sh_status status = SH_OK;
    int stage = 0;
    sh_body_id body = {42};
    sh_world_def world_def;
    sh_world_def_default(&world_def);

    world = (sh_world*)&world; /* garbage: must be NULL after a failure */
    status = sh_world_create(&world_def, &world);
    if (status != SH_OK) {
        assert_null(world);
        goto done;
    }
    ++stage;
    mesh = (sh_mesh*)&mesh;
    status = sh_mesh_create(nodes, node_count, tets, tet_count, &mesh);
    if (status != SH_OK) {
        assert_null(mesh);
        goto done;
    }
    ++stage;
    sh_fem_body_def fem;
    sh_fem_body_def_default(&fem);
    fem.mesh = mesh;
    status = sh_fem_body_create(world, &fem, &body);
    if (status != SH_OK) {
        assert_true(SH_ID_IS_NULL(body));
        goto done;
    }
    ++stage;
    const int32_t region[2] = {0, 1};
    const sh_material soft = sh_test_material(SH_MATERIAL_NEOHOOKEAN, 2e3, 0.45, 1000);
    status = sh_body_set_material(world, body, region, 2, &soft);
    if (status != SH_OK) goto done;
    ++stage;
    double damping[64];
    for (int i = 0; i < node_count; ++i) damping[i] = 0.1;
    status = sh_body_set_node_damping(world, body, damping, node_count);
    if (status != SH_OK) goto done;
    ++stage;
    sh_spring_body_def spring;
    sh_spring_body_def_default(&spring);
    spring.mesh = mesh;
    status = add_spring_body_or_null(world, &spring, &body);
    if (status != SH_OK) goto done;
    ++stage;
    const double table[6] = {-0.1, -1.0, 0.0, 0.0, 0.1, 1.0};
    spring.params.law = SH_SPRING_TABLE;
    spring.params.table = table;
    spring.params.table_rows = 3;
    status = add_spring_body_or_null(world, &spring, &body);
    if (status != SH_OK) goto done;
    ++stage;
    status = sh_body_destroy(world, body);
    if (status != SH_OK) goto done;
    ++stage;
    status = sh_spring_body_create(world, &spring, &body);
    if (status != SH_OK) goto done;
    ++stage;
    sh_step_report report;
    status = sh_world_step(world, 1e-3, &report);
    if (status != SH_OK) goto done;
    ++stage;

done:
    *out_stage = stage;
    snprintf(g_failure_message, sizeof g_failure_message, "%s", sh_last_error_message());
    if (mesh && mesh != (sh_mesh*)&mesh) assert_ok(sh_mesh_destroy(mesh));
    if (world && world != (sh_world*)&world) assert_ok(sh_world_destroy(world));
    return status;
}

static void test_failing_allocator(void** state) {
    (void)state;
    double* nodes;
    int32_t* tets;
    int32_t node_count, tet_count;
    sh_test_box_arrays(0.02, 0.01, 0.01, 2, 1, 1, &nodes, &node_count, &tets, &tet_count);
    assert_non_null(nodes);
    assert_non_null(tets);
    assert_true(node_count <= 64);

    /* How many allocations the whole scene takes when nothing fails. */
    reset_counts();
    int stage = 0;
    assert_ok(build_and_destroy_scene(nodes, node_count, tets, tet_count, &stage));
    const size_t needed = g.attempts;
    assert_true(needed > 0);
    assert_int_equal(g.live_blocks, 0);

    int leaks = 0, wrong_status = 0;
    for (long n = 0; n <= (long)needed; ++n) {
        reset_counts();
        g.fail_after = n;
        const long live_before = g.live_blocks;
        const long long bytes_before = g.live_bytes;
        const sh_status status = build_and_destroy_scene(nodes, node_count, tets, tet_count, &stage);
        const size_t failed = g.failed;
        g.fail_after = -1;
        if (failed == 0) {
            /* Allocation n+1 was never attempted: the scene was built in full. */
            assert_ok(status);
            assert_true((size_t)n >= needed);
        } else if (status != SH_ERR_OUT_OF_MEMORY) {
            print_error("fail after %ld allocations: stage %d returned %s (%s), expected SH_ERR_OUT_OF_MEMORY\n", n,
                        stage, sh_status_string(status), g_failure_message);
            ++wrong_status;
        } else if (!strstr(g_failure_message, "memory")) {
            print_error("fail after %ld allocations: stage %d: message \"%s\" does not mention memory\n", n, stage,
                        g_failure_message);
            ++wrong_status;
        }
        if (g.live_blocks > live_before) {
            print_error("fail after %ld allocations (stage %d, %s: %s): %ld block(s), %lld byte(s) still live after "
                        "destroying everything\n",
                        n, stage, sh_status_string(status), g_failure_message, g.live_blocks - live_before,
                        g.live_bytes - bytes_before);
            ++leaks;
        } else if (g.live_blocks < live_before) {
            print_error("fail after %ld allocations (stage %d): %ld block(s) leaked by an earlier run were freed\n", n,
                        stage, live_before - g.live_blocks);
        }
        assert_allocator_sane();
    }
    free(nodes);
    free(tets);
    assert_int_equal(wrong_status, 0);
    assert_int_equal(leaks, 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counting_allocator_sees_everything_freed),
        cmocka_unit_test(test_set_allocator_busy_and_invalid),
        cmocka_unit_test(test_restore_default_allocator),
        cmocka_unit_test(test_step_allocates_nothing),
        cmocka_unit_test(test_step_with_rollbacks_allocates_nothing),
        cmocka_unit_test(test_rejected_step_allocates_nothing),
        cmocka_unit_test(test_remove_body_allocates_nothing),
        cmocka_unit_test(test_set_material_out_of_memory_changes_nothing),
        cmocka_unit_test(test_implicit_step_out_of_memory_changes_nothing),
        cmocka_unit_test(test_cut_out_of_memory_changes_nothing),
        cmocka_unit_test(test_local_cut_out_of_memory_changes_nothing),
        cmocka_unit_test(test_later_cut_out_of_memory_changes_nothing),
        cmocka_unit_test(test_failing_allocator), /* last: a leak would stay behind */
    };
    return cmocka_run_group_tests(tests, setup_install, NULL);
}
