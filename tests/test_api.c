/* API misuse through the public C API: every misuse returns its exact status code, the
 * last-error message names the culprit, and a failed call changes nothing. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>

#include "test_support.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* Helpers                                                                                      */

/* Asserts that expr returns status and that the last-error message contains needle. */
#define assert_error(expr, status, needle) \
    check_error((expr), (status), (needle), #expr, __FILE__, __LINE__)

static void check_error(sh_status got, sh_status expected, const char* needle, const char* expr,
                        const char* file, int line) {
    sh_test_assert_status(got, expected, expr, file, line);
    const char* message = sh_last_error_message();
    if (!message || !strstr(message, needle)) {
        print_error("%s:%d: %s: last error \"%s\" does not mention \"%s\"\n", file, line, expr,
                    message ? message : "(NULL)", needle);
        _fail(file, line);
    }
}

/* Asserts the last-error message is the empty string (the previous call succeeded). */
static void assert_no_error_message(void) {
    const char* message = sh_last_error_message();
    assert_non_null(message);
    assert_string_equal(message, "");
}

/* A world with default gravity. */
static sh_world* make_world(void) { return sh_test_world(-9.81); }

/* An FEM body from mesh with default def. */
static sh_body_id add_fem(sh_world* world, const sh_mesh* mesh) {
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    sh_body_id id = SH_NULL_ID;
    assert_ok(sh_fem_body_create(world, &def, &id));
    assert_true(!SH_ID_IS_NULL(id));
    return id;
}

/* A spring body of two nodes 1 cm apart joined by one default spring. */
static sh_body_id add_two_node_spring(sh_world* world) {
    sh_spring_body_def def;
    sh_spring_body_def_default(&def);
    return sh_test_spring_pair(world, 0.01, &def.params, def.node_mass, def.integrator, def.on_unstable);
}

static int32_t node_count_of(const sh_world* world, sh_body_id body) {
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    return info.node_count;
}

/* Heap copy of a body's positions (3n doubles); the caller frees it. */
static double* copy_positions(const sh_world* world, sh_body_id body) {
    const int32_t n = node_count_of(world, body);
    double* x = malloc(sizeof(double) * 3 * (size_t)n);
    assert_non_null(x);
    assert_ok(sh_body_get_positions(world, body, x, n));
    return x;
}

static double* copy_velocities(const sh_world* world, sh_body_id body) {
    const int32_t n = node_count_of(world, body);
    double* v = malloc(sizeof(double) * 3 * (size_t)n);
    assert_non_null(v);
    assert_ok(sh_body_get_velocities(world, body, v, n));
    return v;
}

/* Asserts the body's positions and velocities are bitwise equal to x and v. */
static void assert_state_is(const sh_world* world, sh_body_id body, const double* x, const double* v) {
    const int32_t n = node_count_of(world, body);
    double* x_now = copy_positions(world, body);
    double* v_now = copy_velocities(world, body);
    assert_memory_equal(x_now, x, sizeof(double) * 3 * (size_t)n);
    assert_memory_equal(v_now, v, sizeof(double) * 3 * (size_t)n);
    free(x_now);
    free(v_now);
}

/* Steps a few times so positions and velocities are non-trivial (not the rest state). */
static void move_a_bit(sh_world* world) {
    for (int i = 0; i < 5; ++i) assert_ok(sh_world_step(world, 1e-4, NULL));
}

/* Fixture: a world with an FEM body on a one-cube box (6 tets, 8 nodes), stepped a little
 * (and, for setup_moved_box_and_spring, a two-node spring body added before the steps). */
typedef struct moved_box {
    sh_world* world;
    sh_mesh* mesh;
    sh_body_id body;
    sh_body_id spring;
} moved_box;

static int open_moved_box(void** state, int with_spring) {
    static moved_box box;
    moved_box* s = &box;
    s->world = make_world();
    s->mesh = sh_test_box(0.02, 0.02, 0.02, 1, 1, 1);
    s->body = add_fem(s->world, s->mesh);
    s->spring = with_spring ? add_two_node_spring(s->world) : (sh_body_id)SH_NULL_ID;
    move_a_bit(s->world);
    *state = s;
    return 0;
}

static int setup_moved_box(void** state) { return open_moved_box(state, 0); }

static int setup_moved_box_and_spring(void** state) { return open_moved_box(state, 1); }

static int teardown_moved_box(void** state) {
    moved_box* s = *state;
    assert_ok(sh_mesh_destroy(s->mesh));
    assert_ok(sh_world_destroy(s->world));
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* Version, status strings, last error                                                          */

static void test_version_matches_header(void** state) {
    (void)state;
    assert_int_equal(sh_version(), SH_VERSION);
    assert_int_equal(SH_VERSION, SH_VERSION_MAJOR * 1000000 + SH_VERSION_MINOR * 1000 + SH_VERSION_PATCH);
}

static void test_status_strings_non_null_and_distinct(void** state) {
    (void)state;
    static const struct {
        sh_status status;
        const char* name;
    } codes[] = {
        {SH_OK, "SH_OK"},
        {SH_ERR_INVALID_ARGUMENT, "SH_ERR_INVALID_ARGUMENT"},
        {SH_ERR_INVALID_HANDLE, "SH_ERR_INVALID_HANDLE"},
        {SH_ERR_UNINITIALIZED_DEF, "SH_ERR_UNINITIALIZED_DEF"},
        {SH_ERR_OUT_OF_MEMORY, "SH_ERR_OUT_OF_MEMORY"},
        {SH_ERR_IO, "SH_ERR_IO"},
        {SH_ERR_PARSE, "SH_ERR_PARSE"},
        {SH_ERR_DEGENERATE_MESH, "SH_ERR_DEGENERATE_MESH"},
        {SH_ERR_UNSTABLE, "SH_ERR_UNSTABLE"},
        {SH_ERR_UNSUPPORTED, "SH_ERR_UNSUPPORTED"},
        {SH_ERR_SOLVER, "SH_ERR_SOLVER"},
        {SH_ERR_NOT_CONVERGED, "SH_ERR_NOT_CONVERGED"},
        {SH_ERR_CAPACITY, "SH_ERR_CAPACITY"},
        {SH_ERR_BUSY, "SH_ERR_BUSY"},
        {SH_ERR_INTERNAL, "SH_ERR_INTERNAL"},
    };
    const size_t count = sizeof codes / sizeof codes[0];
    for (size_t i = 0; i < count; ++i) {
        assert_int_equal((int)codes[i].status, (int)i); /* the codes are 0..14, no gap */
        const char* text = sh_status_string(codes[i].status);
        assert_non_null(text);
        assert_true(strlen(text) > 0);
        /* "SH_ERR_PARSE: ...": the text starts with the code's name followed by ':' */
        assert_int_equal(strncmp(text, codes[i].name, strlen(codes[i].name)), 0);
        assert_int_equal(text[strlen(codes[i].name)], ':');
        for (size_t j = 0; j < i; ++j) assert_string_not_equal(text, sh_status_string(codes[j].status));
    }
    /* A value outside the enum still gives static text, never NULL. */
    assert_non_null(sh_status_string((sh_status)99));
    assert_non_null(sh_status_string((sh_status)-1));
}

static void test_last_error_cleared_by_success(void** state) {
    (void)state;
    assert_error(sh_world_step(NULL, 1e-3, NULL), SH_ERR_INVALID_HANDLE, "world");
    assert_true(strlen(sh_last_error_message()) > 0);
    assert_int_equal(sh_version(), SH_VERSION); /* not a fallible call: does not matter */

    sh_world* world = make_world();
    assert_no_error_message();
    assert_error(sh_world_step(world, -1.0, NULL), SH_ERR_INVALID_ARGUMENT, "dt");
    assert_ok(sh_world_step(world, 1e-3, NULL));
    assert_no_error_message();
    assert_ok(sh_world_destroy(world));
    assert_no_error_message();
}

/* ------------------------------------------------------------------------------------------ */
/* NULL pointers                                                                                */

static void test_null_out_pointers(void** state) {
    (void)state;
    sh_world_def world_def;
    sh_world_def_default(&world_def);
    assert_error(sh_world_create(&world_def, NULL), SH_ERR_INVALID_ARGUMENT, "out_world");

    static const double nodes[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const int32_t tets[4] = {0, 1, 2, 3};
    assert_error(sh_mesh_create(nodes, 4, tets, 1, NULL), SH_ERR_INVALID_ARGUMENT, "out_mesh");
    assert_error(sh_mesh_load(SH_TEST_MESH("single_tetra.msh"), NULL), SH_ERR_INVALID_ARGUMENT, "out_mesh");

    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    sh_fem_body_def fem;
    sh_fem_body_def_default(&fem);
    fem.mesh = mesh;
    assert_error(sh_fem_body_create(world, &fem, NULL), SH_ERR_INVALID_ARGUMENT, "out_body");
    sh_spring_body_def spring;
    sh_spring_body_def_default(&spring);
    spring.mesh = mesh;
    assert_error(sh_spring_body_create(world, &spring, NULL), SH_ERR_INVALID_ARGUMENT, "out_body");

    const sh_body_id body = add_fem(world, mesh);
    assert_error(sh_mesh_get_info(mesh, NULL), SH_ERR_INVALID_ARGUMENT, "out_info");
    assert_error(sh_mesh_get_nodes(mesh, NULL, 4), SH_ERR_INVALID_ARGUMENT, "out");
    assert_error(sh_mesh_get_tets(mesh, NULL, 1), SH_ERR_INVALID_ARGUMENT, "out");
    assert_error(sh_mesh_get_edges(mesh, NULL, 6), SH_ERR_INVALID_ARGUMENT, "out");
    assert_error(sh_mesh_get_surface_triangles(mesh, NULL, 4), SH_ERR_INVALID_ARGUMENT, "out");
    assert_error(sh_mesh_write_vtu(mesh, NULL), SH_ERR_INVALID_ARGUMENT, "path");
    assert_error(sh_world_get_warnings(world, NULL), SH_ERR_INVALID_ARGUMENT, "out");
    assert_error(sh_world_set_gravity(world, NULL), SH_ERR_INVALID_ARGUMENT, "gravity");
    assert_error(sh_body_get_info(world, body, NULL), SH_ERR_INVALID_ARGUMENT, "out_info");
    assert_error(sh_body_get_positions(world, body, NULL, 4), SH_ERR_INVALID_ARGUMENT, "out");
    assert_error(sh_body_get_velocities(world, body, NULL, 4), SH_ERR_INVALID_ARGUMENT, "out");
    assert_error(sh_body_get_masses(world, body, NULL, 4), SH_ERR_INVALID_ARGUMENT, "out");
    assert_error(sh_body_get_elastic_forces(world, body, NULL, 4), SH_ERR_INVALID_ARGUMENT, "out");
    assert_error(sh_body_get_elastic_energy(world, body, NULL), SH_ERR_INVALID_ARGUMENT, "out_energy");
    assert_error(sh_body_write_vtu(world, body, NULL), SH_ERR_INVALID_ARGUMENT, "path");
    /* NULL input arrays */
    assert_error(sh_body_set_positions(world, body, NULL, 4), SH_ERR_INVALID_ARGUMENT, "positions");
    assert_error(sh_body_set_velocities(world, body, NULL, 4), SH_ERR_INVALID_ARGUMENT, "velocities");
    assert_error(sh_body_fix_nodes(world, body, NULL, 1), SH_ERR_INVALID_ARGUMENT, "nodes");
    assert_error(sh_body_release_nodes(world, body, NULL, 1), SH_ERR_INVALID_ARGUMENT, "nodes");
    const int32_t node0 = 0;
    assert_error(sh_body_prescribe_positions(world, body, &node0, NULL, 1), SH_ERR_INVALID_ARGUMENT, "positions");
    assert_error(sh_body_set_material(world, body, NULL, 1, &fem.material), SH_ERR_INVALID_ARGUMENT, "elements");
    assert_error(sh_body_set_material(world, body, &node0, 1, NULL), SH_ERR_INVALID_ARGUMENT, "material");
    /* count 0 with a NULL array is a valid empty request */
    assert_ok(sh_body_fix_nodes(world, body, NULL, 0));
    /* NULL external forces and node damping are documented as "clear" */
    assert_ok(sh_body_set_external_forces(world, body, NULL, 0));
    assert_ok(sh_body_set_node_damping(world, body, NULL, 0));

    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
}

static void test_null_defs(void** state) {
    (void)state;
    sh_world* out_world = (sh_world*)&out_world; /* non-NULL garbage: must be reset to NULL */
    assert_error(sh_world_create(NULL, &out_world), SH_ERR_INVALID_ARGUMENT, "def");
    assert_null(out_world);

    sh_world* world = make_world();
    sh_body_id id = {42};
    assert_error(sh_fem_body_create(world, NULL, &id), SH_ERR_INVALID_ARGUMENT, "def");
    assert_true(SH_ID_IS_NULL(id));
    id.value = 42;
    assert_error(sh_spring_body_create(world, NULL, &id), SH_ERR_INVALID_ARGUMENT, "def");
    assert_true(SH_ID_IS_NULL(id));

    /* A def without its mesh: the capi reports a NULL def->mesh as an invalid argument. */
    sh_fem_body_def fem;
    sh_fem_body_def_default(&fem);
    id.value = 42;
    assert_error(sh_fem_body_create(world, &fem, &id), SH_ERR_INVALID_ARGUMENT, "mesh");
    assert_true(SH_ID_IS_NULL(id));

    /* A spring body with neither nodes nor mesh. */
    sh_spring_body_def spring;
    sh_spring_body_def_default(&spring);
    assert_error(sh_spring_body_create(world, &spring, &id), SH_ERR_INVALID_ARGUMENT, "NULL");
    assert_true(SH_ID_IS_NULL(id));
    assert_ok(sh_world_destroy(world));

    /* sh_*_def_default(NULL) must not crash. */
    sh_world_def_default(NULL);
    sh_fem_body_def_default(NULL);
    sh_spring_body_def_default(NULL);
}

static void test_null_handles(void** state) {
    (void)state;
    sh_fem_body_def fem;
    sh_fem_body_def_default(&fem);
    sh_spring_body_def spring;
    sh_spring_body_def_default(&spring);
    double buffer[12];
    int32_t ibuffer[12];
    uint64_t warnings[SH_WARN_COUNT];
    sh_body_info info;
    sh_mesh_info mesh_info;
    sh_step_report report;
    double energy;
    const double gravity[3] = {0, 0, -9.81};
    const sh_body_id body = {((uint64_t)1 << 32) | 1}; /* what a first body id would look like */
    sh_body_id id = {42};

    assert_error(sh_world_step(NULL, 1e-3, &report), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_world_step(NULL, 1e-3, NULL), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_world_set_gravity(NULL, gravity), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_world_get_warnings(NULL, warnings), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_fem_body_create(NULL, &fem, &id), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_spring_body_create(NULL, &spring, &id), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_destroy(NULL, body), SH_ERR_INVALID_HANDLE, "world");
    assert_int_equal(sh_body_is_valid(NULL, body), 0);
    assert_error(sh_body_get_info(NULL, body, &info), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_get_positions(NULL, body, buffer, 4), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_get_velocities(NULL, body, buffer, 4), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_get_masses(NULL, body, buffer, 12), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_set_positions(NULL, body, buffer, 4), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_get_elastic_energy(NULL, body, &energy), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_write_vtu(NULL, body, "x.vtu"), SH_ERR_INVALID_HANDLE, "world");

    assert_error(sh_mesh_get_info(NULL, &mesh_info), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_mesh_get_nodes(NULL, buffer, 4), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_mesh_get_tets(NULL, ibuffer, 3), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_mesh_get_edges(NULL, ibuffer, 6), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_mesh_get_surface_triangles(NULL, ibuffer, 4), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_mesh_write_vtu(NULL, "x.vtu"), SH_ERR_INVALID_HANDLE, "mesh");

    /* Destroying NULL is a documented no-op. */
    assert_ok(sh_world_destroy(NULL));
    assert_ok(sh_mesh_destroy(NULL));
}

/* A pointer that was never returned by softhap (a stack object cast to the opaque type) is
 * rejected by the handle registry without being dereferenced. */
static void test_foreign_pointers(void** state) {
    (void)state;
    double fake[64];
    memset(fake, 0, sizeof fake);
    sh_mesh_info info;
    assert_error(sh_world_step((sh_world*)fake, 1e-3, NULL), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_mesh_get_info((const sh_mesh*)fake, &info), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_world_destroy((sh_world*)fake), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_mesh_destroy((sh_mesh*)fake), SH_ERR_INVALID_HANDLE, "mesh");

    /* A world passed where a mesh is expected (and vice versa) is the wrong kind of handle. */
    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    assert_error(sh_mesh_get_info((const sh_mesh*)world, &info), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_world_step((sh_world*)mesh, 1e-3, NULL), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_mesh_destroy((sh_mesh*)world), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_world_destroy((sh_world*)mesh), SH_ERR_INVALID_HANDLE, "world");
    assert_ok(sh_world_step(world, 1e-3, NULL)); /* both still alive */
    assert_ok(sh_mesh_get_info(mesh, &info));
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
}

/* ------------------------------------------------------------------------------------------ */
/* Destroyed objects (the pointers are only passed back to softhap, never dereferenced)         */

/* A handle names one object for its whole life: after the object is destroyed and its table
 * slot serves new objects, the old handle stays invalid, and a live handle of one kind is
 * refused where another kind is expected. */
static void test_stale_handles_never_name_a_new_object(void** state) {
    (void)state;
    sh_mesh_info info;
    sh_world* stale = make_world();
    assert_ok(sh_world_destroy(stale));
    for (int round = 0; round < 1000; ++round) {
        sh_world* world = make_world();
        sh_mesh* mesh = sh_test_unit_tet(0.01);
        assert_true(world != stale && (void*)mesh != (void*)stale);
        assert_error(sh_world_step(stale, 1e-3, NULL), SH_ERR_INVALID_HANDLE, "world");
        assert_error(sh_world_destroy(stale), SH_ERR_INVALID_HANDLE, "world");
        assert_error(sh_mesh_get_info((const sh_mesh*)stale, &info), SH_ERR_INVALID_HANDLE, "mesh");
        assert_ok(sh_world_step(world, 1e-3, NULL));
        assert_ok(sh_mesh_get_info(mesh, &info));
        assert_ok(sh_mesh_destroy(mesh));
        assert_ok(sh_world_destroy(world));
    }
}

static void test_destroyed_world(void** state) {
    (void)state;
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    sh_world* world = make_world();
    const sh_body_id body = add_fem(world, mesh);
    assert_ok(sh_world_destroy(world));

    sh_fem_body_def fem;
    sh_fem_body_def_default(&fem);
    fem.mesh = mesh;
    sh_body_id id = {42};
    double buffer[12];
    const double gravity[3] = {0, 0, -1};
    assert_error(sh_world_destroy(world), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_world_step(world, 1e-3, NULL), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_world_set_gravity(world, gravity), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_fem_body_create(world, &fem, &id), SH_ERR_INVALID_HANDLE, "world");
    assert_int_equal(sh_body_is_valid(world, body), 0);
    assert_error(sh_body_get_positions(world, body, buffer, 4), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_destroy(world, body), SH_ERR_INVALID_HANDLE, "world");
    assert_ok(sh_mesh_destroy(mesh));
}

static void test_destroyed_mesh(void** state) {
    (void)state;
    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    /* A body copies what it needs: the mesh may be destroyed after the body is made. */
    const sh_body_id body = add_fem(world, mesh);
    assert_ok(sh_mesh_destroy(mesh));

    sh_mesh_info info;
    double nodes[12];
    assert_error(sh_mesh_destroy(mesh), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_mesh_get_info(mesh, &info), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_mesh_get_nodes(mesh, nodes, 4), SH_ERR_INVALID_HANDLE, "mesh");
    assert_error(sh_mesh_write_vtu(mesh, "never_written.vtu"), SH_ERR_INVALID_HANDLE, "mesh");

    sh_fem_body_def fem;
    sh_fem_body_def_default(&fem);
    fem.mesh = mesh;
    sh_body_id id = {42};
    assert_error(sh_fem_body_create(world, &fem, &id), SH_ERR_INVALID_HANDLE, "mesh");
    assert_true(SH_ID_IS_NULL(id));
    sh_spring_body_def spring;
    sh_spring_body_def_default(&spring);
    spring.mesh = mesh;
    id.value = 42;
    assert_error(sh_spring_body_create(world, &spring, &id), SH_ERR_INVALID_HANDLE, "mesh");
    assert_true(SH_ID_IS_NULL(id));

    /* The body made from it still works. */
    for (int i = 0; i < 10; ++i) assert_ok(sh_world_step(world, 1e-3, NULL));
    assert_ok(sh_body_get_positions(world, body, nodes, 4));
    assert_ok(sh_world_destroy(world));
}

/* ------------------------------------------------------------------------------------------ */
/* Body ids                                                                                     */

static void test_stale_body_ids(void** state) {
    (void)state;
    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    const sh_body_id keeper = add_fem(world, mesh); /* another body that must stay untouched */
    sh_body_id old_ids[8];
    sh_body_id body = add_fem(world, mesh);
    double buffer[12];
    sh_body_info info;
    const int32_t node0 = 0;

    for (int round = 0; round < 8; ++round) {
        assert_int_equal(sh_body_is_valid(world, body), 1);
        assert_ok(sh_body_destroy(world, body));
        assert_int_equal(sh_body_is_valid(world, body), 0);
        assert_error(sh_body_destroy(world, body), SH_ERR_INVALID_HANDLE, "body");
        assert_error(sh_body_get_info(world, body, &info), SH_ERR_INVALID_HANDLE, "body");
        assert_error(sh_body_get_positions(world, body, buffer, 4), SH_ERR_INVALID_HANDLE, "body");
        assert_error(sh_body_set_positions(world, body, buffer, 4), SH_ERR_INVALID_HANDLE, "body");
        assert_error(sh_body_fix_nodes(world, body, &node0, 1), SH_ERR_INVALID_HANDLE, "body");
        assert_error(sh_body_write_vtu(world, body, "never_written.vtu"), SH_ERR_INVALID_HANDLE, "body");
        old_ids[round] = body;

        /* A new body goes into the freed slot, with a new id; every old id stays invalid. */
        body = add_fem(world, mesh);
        assert_int_equal(sh_body_is_valid(world, body), 1);
        for (int k = 0; k <= round; ++k) {
            assert_true(!SH_ID_EQUAL(body, old_ids[k]));
            assert_int_equal(sh_body_is_valid(world, old_ids[k]), 0);
            assert_error(sh_body_get_info(world, old_ids[k], &info), SH_ERR_INVALID_HANDLE, "body");
        }
        assert_true(!SH_ID_EQUAL(body, keeper));
        assert_int_equal(sh_body_is_valid(world, keeper), 1);
    }
    assert_ok(sh_world_step(world, 1e-3, NULL));
    assert_ok(sh_body_get_info(world, keeper, &info));
    assert_int_equal(info.node_count, 4);
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
}

static void test_null_and_garbage_body_ids(void** state) {
    (void)state;
    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    const sh_body_id body = add_fem(world, mesh);
    double buffer[12];
    sh_body_info info;

    assert_int_equal(sh_body_is_valid(world, (sh_body_id)SH_NULL_ID), 0);
    assert_error(sh_body_get_info(world, (sh_body_id)SH_NULL_ID, &info), SH_ERR_INVALID_HANDLE, "body");
    assert_error(sh_body_get_positions(world, (sh_body_id)SH_NULL_ID, buffer, 4), SH_ERR_INVALID_HANDLE, "body");
    assert_error(sh_body_destroy(world, (sh_body_id)SH_NULL_ID), SH_ERR_INVALID_HANDLE, "body");

    const sh_body_id garbage[] = {
        {body.value + 1},                         /* next slot, never used */
        {body.value ^ ((uint64_t)1 << 32)},       /* same slot, other generation */
        {body.value + ((uint64_t)1 << 32)},       /* same slot, future generation */
        {body.value & 0xffffffffu},               /* same slot, generation 0 */
        {UINT64_MAX},
        {(uint64_t)1 << 63},
        {0xffffffffu},
    };
    for (size_t i = 0; i < sizeof garbage / sizeof garbage[0]; ++i) {
        if (SH_ID_EQUAL(garbage[i], body)) continue;
        assert_int_equal(sh_body_is_valid(world, garbage[i]), 0);
        assert_error(sh_body_get_info(world, garbage[i], &info), SH_ERR_INVALID_HANDLE, "body");
        assert_error(sh_body_destroy(world, garbage[i]), SH_ERR_INVALID_HANDLE, "body");
    }
    assert_int_equal(sh_body_is_valid(world, body), 1);
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
}

/* The id of a body of world A names no body of an empty world B. */
static void test_body_id_of_another_empty_world(void** state) {
    (void)state;
    sh_world* a = make_world();
    sh_world* b = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    const sh_body_id body_a = add_fem(a, mesh);
    double buffer[12];
    sh_body_info info;
    assert_int_equal(sh_body_is_valid(b, body_a), 0);
    assert_error(sh_body_get_info(b, body_a, &info), SH_ERR_INVALID_HANDLE, "body");
    assert_error(sh_body_get_positions(b, body_a, buffer, 4), SH_ERR_INVALID_HANDLE, "body");
    assert_error(sh_body_destroy(b, body_a), SH_ERR_INVALID_HANDLE, "body");
    assert_int_equal(sh_body_is_valid(a, body_a), 1);
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(a));
    assert_ok(sh_world_destroy(b));
}

/* The id of a body of world A names no body of world B either when B has bodies of its own:
 * sh_body_is_valid is "1 if body is a live body of world", and a removed-from-B call must
 * not remove B's own body. */
static void test_body_id_of_another_populated_world(void** state) {
    (void)state;
    sh_world* a = make_world();
    sh_world* b = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    const sh_body_id body_a = add_fem(a, mesh);
    const sh_body_id body_b = add_fem(b, mesh);
    sh_body_info info;
    assert_int_equal(sh_body_is_valid(b, body_b), 1);
    assert_int_equal(sh_body_is_valid(b, body_a), 0);
    assert_error(sh_body_get_info(b, body_a, &info), SH_ERR_INVALID_HANDLE, "body");
    assert_error(sh_body_destroy(b, body_a), SH_ERR_INVALID_HANDLE, "body");
    assert_int_equal(sh_body_is_valid(b, body_b), 1);
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(a));
    assert_ok(sh_world_destroy(b));
}

/* ------------------------------------------------------------------------------------------ */
/* Uninitialised defs                                                                           */

static void test_uninitialized_defs(void** state) {
    (void)state;
    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    static const double nodes[6] = {0, 0, 0, 0.01, 0, 0};
    static const int32_t springs[2] = {0, 1};
    const unsigned char fills[] = {0x00, 0xab, 0xff, 0x53};

    for (size_t f = 0; f < sizeof fills; ++f) {
        sh_world_def world_def;
        memset(&world_def, fills[f], sizeof world_def);
        sh_world* out_world = (sh_world*)&out_world;
        assert_error(sh_world_create(&world_def, &out_world), SH_ERR_UNINITIALIZED_DEF, "def");
        assert_null(out_world);

        /* Every other field valid: only the missing default call is wrong. */
        sh_fem_body_def fem;
        memset(&fem, fills[f], sizeof fem);
        fem.mesh = mesh;
        fem.material.model = SH_MATERIAL_STVK;
        fem.material.young = 1e4;
        fem.material.poisson = 0.3;
        fem.material.density = 1000;
        fem.integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
        fem.on_unstable = SH_UNSTABLE_SUBSTEP;
        fem.damping_mass = 0;
        fem.damping_stiffness = 0;
        fem.runaway_speed = 1e4;
        sh_body_id id = {42};
        assert_error(sh_fem_body_create(world, &fem, &id), SH_ERR_UNINITIALIZED_DEF, "def");
        assert_true(SH_ID_IS_NULL(id));

        sh_spring_body_def spring;
        memset(&spring, fills[f], sizeof spring);
        spring.nodes = nodes;
        spring.node_count = 2;
        spring.springs = springs;
        spring.spring_count = 1;
        spring.mesh = NULL;
        memset(&spring.params, 0, sizeof spring.params);
        spring.params.law = SH_SPRING_LINEAR;
        spring.params.stiffness = 100;
        spring.node_mass = 1e-3;
        spring.node_masses = NULL;
        spring.integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
        spring.on_unstable = SH_UNSTABLE_SUBSTEP;
        spring.damping_mass = 0;
        spring.runaway_speed = 1e4;
        id.value = 42;
        assert_error(sh_spring_body_create(world, &spring, &id), SH_ERR_UNINITIALIZED_DEF, "def");
        assert_true(SH_ID_IS_NULL(id));
    }
    /* A def copied from a defaulted one is initialised (create copies, keeps no pointer). */
    sh_fem_body_def a, b;
    sh_fem_body_def_default(&a);
    a.mesh = mesh;
    b = a;
    sh_body_id id;
    assert_ok(sh_fem_body_create(world, &b, &id));
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
}

/* ------------------------------------------------------------------------------------------ */
/* Materials                                                                                    */

typedef struct bad_material {
    double young, poisson, density;
    const char* needle;
} bad_material;

static const bad_material k_bad_materials[] = {
    {0.0, 0.3, 1000, "young"},
    {-1e4, 0.3, 1000, "young"},
    {NAN, 0.3, 1000, "young"},
    {INFINITY, 0.3, 1000, "young"},
    {-INFINITY, 0.3, 1000, "young"},
    {1e4, 0.5, 1000, "poisson"},
    {1e4, 0.6, 1000, "poisson"},
    {1e4, -1.0, 1000, "poisson"},
    {1e4, -1.5, 1000, "poisson"},
    {1e4, NAN, 1000, "poisson"},
    {1e4, INFINITY, 1000, "poisson"},
    {1e4, 0.3, 0.0, "density"},
    {1e4, 0.3, -1000, "density"},
    {1e4, 0.3, NAN, "density"},
    {1e4, 0.3, INFINITY, "density"},
};

/* sh_material and sh_contact_params are passed in whole too: one not made by its *_default
 * function is SH_ERR_UNINITIALIZED_DEF, passed alone or inside a def, with nothing created. */
static void test_uninitialized_materials_and_contact_params(void** state) {
    (void)state;
    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    sh_body_id a, b;
    assert_ok(sh_fem_body_create(world, &def, &a));
    assert_ok(sh_fem_body_create(world, &def, &b));
    const int32_t all[1] = {0};

    sh_material raw; /* every field valid, but never passed through sh_material_default */
    memset(&raw, 0, sizeof raw);
    raw.model = SH_MATERIAL_STVK;
    raw.young = 1e4;
    raw.poisson = 0.3;
    raw.density = 1000.0;
    assert_error(sh_body_set_material(world, a, all, 1, &raw), SH_ERR_UNINITIALIZED_DEF, "material");
    def.material = raw;
    sh_body_id c = {42};
    assert_error(sh_fem_body_create(world, &def, &c), SH_ERR_UNINITIALIZED_DEF, "def->material");
    assert_true(SH_ID_IS_NULL(c));

    sh_contact_params law;
    memset(&law, 0, sizeof law);
    law.stiffness = 1e4;
    law.exponent = 1.5;
    law.slip_velocity = 1e-3;
    law.capacity = 64;
    assert_error(sh_world_set_body_contact(world, a, b, &law), SH_ERR_UNINITIALIZED_DEF, "params");
    sh_collider_def tool_def;
    sh_collider_def_default(&tool_def);
    tool_def.contact = law;
    sh_tool_id tool = {42};
    assert_error(sh_tool_create(world, &tool_def, &tool), SH_ERR_UNINITIALIZED_DEF, "def->contact");
    assert_true(SH_ID_IS_NULL(tool));

    /* The same values through the default functions are accepted. */
    sh_material_default(&raw);
    raw.young = 1e4;
    assert_ok(sh_body_set_material(world, a, all, 1, &raw));
    sh_contact_params_default(&law);
    assert_ok(sh_world_set_body_contact(world, a, b, &law));
    sh_contact_params_default(&tool_def.contact);
    assert_ok(sh_tool_create(world, &tool_def, &tool));

    assert_ok(sh_world_destroy(world));
    assert_ok(sh_mesh_destroy(mesh));
}

static void test_material_validation_in_def(void** state) {
    (void)state;
    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    for (size_t i = 0; i < sizeof k_bad_materials / sizeof k_bad_materials[0]; ++i) {
        const bad_material* m = &k_bad_materials[i];
        for (int model = SH_MATERIAL_LINEAR; model <= SH_MATERIAL_NEOHOOKEAN; ++model) {
            sh_fem_body_def def;
            sh_fem_body_def_default(&def);
            def.mesh = mesh;
            def.material.model = (sh_material_model)model;
            def.material.young = m->young;
            def.material.poisson = m->poisson;
            def.material.density = m->density;
            sh_body_id id = {42};
            assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, m->needle);
            assert_true(SH_ID_IS_NULL(id));
        }
    }
    /* Boundary values just inside the admissible ranges are accepted. */
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.poisson = 0.4999;
    sh_body_id id;
    assert_ok(sh_fem_body_create(world, &def, &id));
    def.material.poisson = -0.9999;
    assert_ok(sh_fem_body_create(world, &def, &id));

    /* Unknown model, integrator, policy; bad damping and runaway speed. */
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = (sh_material_model)17;
    assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, "model");
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.integrator = (sh_integrator)9;
    assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, "integrator");
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.on_unstable = (sh_unstable_policy)5;
    assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, "on_unstable");
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.damping_mass = -1.0;
    assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, "damping_mass");
    def.damping_mass = NAN;
    assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, "damping_mass");
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.damping_stiffness = -1.0;
    assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, "damping_stiffness");
    def.damping_stiffness = INFINITY;
    assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, "damping_stiffness");
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.runaway_speed = 0.0;
    assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, "runaway_speed");
    def.runaway_speed = NAN;
    assert_error(sh_fem_body_create(world, &def, &id), SH_ERR_INVALID_ARGUMENT, "runaway_speed");

    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
}

static void test_material_validation_in_set_material(void** state) {
    const moved_box* s = *state;
    const int32_t n = node_count_of(s->world, s->body);
    double masses_before[8], masses_after[8];
    assert_int_equal(n, 8);
    assert_ok(sh_body_get_masses(s->world, s->body, masses_before, n));
    double* x = copy_positions(s->world, s->body);
    double* v = copy_velocities(s->world, s->body);
    double energy_before, energy_after;
    assert_ok(sh_body_get_elastic_energy(s->world, s->body, &energy_before));

    const int32_t all[6] = {0, 1, 2, 3, 4, 5};
    for (size_t i = 0; i < sizeof k_bad_materials / sizeof k_bad_materials[0]; ++i) {
        const sh_material m = sh_test_material(SH_MATERIAL_STVK, k_bad_materials[i].young, k_bad_materials[i].poisson,
                               k_bad_materials[i].density);
        assert_error(sh_body_set_material(s->world, s->body, all, 6, &m), SH_ERR_INVALID_ARGUMENT,
                     k_bad_materials[i].needle);
    }
    const sh_material good = sh_test_material(SH_MATERIAL_NEOHOOKEAN, 2e4, 0.4, 2000);
    const sh_material bad_model = sh_test_material((sh_material_model)-1, 2e4, 0.4, 2000);
    assert_error(sh_body_set_material(s->world, s->body, all, 6, &bad_model), SH_ERR_INVALID_ARGUMENT, "model");
    /* Element indices out of range: nothing changes, even for the valid indices before it. */
    const int32_t out_of_range_high[3] = {0, 1, 6};
    const int32_t out_of_range_low[2] = {2, -1};
    const int32_t huge[1] = {INT32_MAX};
    assert_error(sh_body_set_material(s->world, s->body, out_of_range_high, 3, &good), SH_ERR_INVALID_ARGUMENT, "elements[2]");
    assert_error(sh_body_set_material(s->world, s->body, out_of_range_low, 2, &good), SH_ERR_INVALID_ARGUMENT, "elements[1]");
    assert_error(sh_body_set_material(s->world, s->body, huge, 1, &good), SH_ERR_INVALID_ARGUMENT, "elements[0]");
    assert_error(sh_body_set_material(s->world, s->body, all, -1, &good), SH_ERR_INVALID_ARGUMENT, "element_count");

    /* Failed calls changed neither masses nor the state nor the stiffness. */
    assert_ok(sh_body_get_masses(s->world, s->body, masses_after, n));
    assert_memory_equal(masses_after, masses_before, sizeof(double) * (size_t)n);
    assert_state_is(s->world, s->body, x, v);
    assert_ok(sh_body_get_elastic_energy(s->world, s->body, &energy_after));
    assert_memory_equal(&energy_after, &energy_before, sizeof(double));

    /* The valid call does change the masses (density doubled on every element). */
    assert_ok(sh_body_set_material(s->world, s->body, all, 6, &good));
    assert_ok(sh_body_get_masses(s->world, s->body, masses_after, n));
    for (int32_t i = 0; i < n; ++i) assert_close(masses_after[i], 2.0 * masses_before[i], 1e-12);

    /* sh_body_set_material on a mass-spring s->body is unsupported. */
    const sh_body_id spring = add_two_node_spring(s->world);
    const int32_t zero = 0;
    assert_error(sh_body_set_material(s->world, spring, &zero, 1, &good), SH_ERR_UNSUPPORTED, "spring");

    free(x);
    free(v);
}

/* ------------------------------------------------------------------------------------------ */
/* Spring bodies                                                                                */

/* Tries def (two nodes 1 cm apart unless the caller changed them) and expects the failure. */
static void expect_spring_error(sh_world* world, const sh_spring_body_def* def, sh_status status,
                                const char* needle, int line) {
    sh_body_id id = {42};
    const sh_status got = sh_spring_body_create(world, def, &id);
    check_error(got, status, needle, "sh_spring_body_create", __FILE__, line);
    if (!SH_ID_IS_NULL(id)) {
        print_error("%s:%d: out_body not reset to the null id on failure\n", __FILE__, line);
        _fail(__FILE__, line);
    }
}

#define EXPECT_SPRING_ERROR(def, status, needle) expect_spring_error(world, (def), (status), (needle), __LINE__)

static void two_node_def(sh_spring_body_def* def, const double* nodes, const int32_t* springs) {
    sh_spring_body_def_default(def);
    def->nodes = nodes;
    def->node_count = 2;
    def->springs = springs;
    def->spring_count = 1;
}

/* Spring bodies whose nodes, springs, masses or counts are wrong: each is the error naming it. */
static void test_spring_def_topology_errors(void** state) {
    (void)state;
    sh_world* world = make_world();
    const double nodes[9] = {0, 0, 0, 0.01, 0, 0, 0, 0.01, 0};
    const double same_place[6] = {0.5, 0.5, 0.5, 0.5, 0.5, 0.5};
    const double nan_node[6] = {0, 0, 0, NAN, 0, 0};
    const int32_t one_spring[2] = {0, 1};
    const int32_t self_spring[2] = {1, 1};
    const int32_t out_of_range[2] = {0, 2};
    const int32_t negative_index[2] = {-1, 1};
    const double negative_masses[2] = {1e-3, -1e-3};
    const double nan_masses[2] = {1e-3, NAN};
    sh_spring_body_def def;

    two_node_def(&def, same_place, one_spring);
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "zero rest length");
    two_node_def(&def, nodes, self_spring);
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "itself");
    two_node_def(&def, nodes, out_of_range);
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "out of range");
    two_node_def(&def, nodes, negative_index);
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "out of range");
    two_node_def(&def, nan_node, one_spring);
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "node 1");

    two_node_def(&def, nodes, one_spring);
    def.node_mass = -1e-3;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "mass");
    def.node_mass = 0.0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "mass");
    def.node_mass = NAN;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "mass");
    two_node_def(&def, nodes, one_spring);
    def.node_masses = negative_masses;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "node 1");
    def.node_masses = nan_masses;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "node 1");

    two_node_def(&def, nodes, one_spring);
    def.node_count = 0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "node_count");
    def.node_count = -2;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "node_count");
    two_node_def(&def, nodes, one_spring);
    def.spring_count = -1;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "spring_count");
    two_node_def(&def, nodes, one_spring);
    def.integrator = (sh_integrator)5;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "integrator");
    two_node_def(&def, nodes, one_spring);
    def.runaway_speed = -1.0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "runaway_speed");

    /* And a single particle with no spring is a valid body. */
    sh_spring_body_def_default(&def);
    def.nodes = nodes;
    def.node_count = 1;
    sh_body_id id;
    assert_ok(sh_spring_body_create(world, &def, &id));
    assert_ok(sh_world_destroy(world));
}

/* Spring laws with a parameter out of range, or no law at all: each is the error naming it. */
static void test_spring_law_errors(void** state) {
    (void)state;
    sh_world* world = make_world();
    const double nodes[6] = {0, 0, 0, 0.01, 0, 0};
    const int32_t one_spring[2] = {0, 1};
    sh_spring_body_def def;

    two_node_def(&def, nodes, one_spring);
    def.params.stiffness = 0.0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "stiffness");
    def.params.stiffness = -100.0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "stiffness");
    def.params.stiffness = NAN;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "stiffness");
    def.params.stiffness = INFINITY;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "stiffness");
    two_node_def(&def, nodes, one_spring);
    def.params.damping = -1.0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "damping");

    two_node_def(&def, nodes, one_spring);
    def.params.law = SH_SPRING_CUBIC;
    def.params.lambda1 = 1.0;
    def.params.lambda2 = 0.0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "lambda2");
    def.params.lambda2 = 1.0;
    def.params.lambda1 = -1.0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "lambda1");

    two_node_def(&def, nodes, one_spring);
    def.params.law = SH_SPRING_HYPERBOLIC;
    def.params.a = 1.0;
    def.params.b = 0.0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "params.b");
    def.params.b = 1e-3;
    def.params.a = -1.0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "params.a");

    two_node_def(&def, nodes, one_spring);
    def.params.law = (sh_spring_law)42;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "law");
    def.params.law = (sh_spring_law)-1;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "law");

    assert_ok(sh_world_destroy(world));
}

/* Tearing: a negative or non-finite break strain is an error naming it; a spring stretched past
 * a valid one breaks at the start of the next step and the report counts it. */
static void test_spring_break_strain(void** state) {
    (void)state;
    sh_world* world = sh_test_world(0.0);
    const double nodes[6] = {0, 0, 0, 0.01, 0, 0};
    const int32_t one_spring[2] = {0, 1};
    sh_spring_body_def def;
    two_node_def(&def, nodes, one_spring);
    assert_true(def.params.break_strain == 0.0); /* the default: never tears */
    def.params.break_strain = -0.1;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "break_strain");
    def.params.break_strain = NAN;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "break_strain");
    def.params.break_strain = 0.5;
    sh_body_id body = SH_NULL_ID;
    assert_ok(sh_spring_body_create(world, &def, &body));
    /* 1 cm to 1.4 cm: strain 0.4, below 0.5; then 1.6 cm: strain 0.6, above. */
    const double stretched[2][6] = {{0, 0, 0, 0.014, 0, 0}, {0, 0, 0, 0.016, 0, 0}};
    const int32_t expected[2] = {0, 1};
    for (int k = 0; k < 2; ++k) {
        assert_ok(sh_body_set_positions(world, body, stretched[k], 2));
        sh_step_report report;
        assert_ok(sh_world_step(world, 1e-9, &report));
        assert_int_equal(report.springs_broken, expected[k]);
    }
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    assert_int_equal(info.element_count, 0);
    assert_ok(sh_world_destroy(world));
}

/* A cutting tool's resolution must be finite and >= 0; a refused definition changes nothing. */
static void test_cut_def_resolution(void** state) {
    (void)state;
    sh_world* world = make_world();
    sh_collider_def tool_def;
    sh_collider_def_default(&tool_def);
    sh_tool_id tool = SH_NULL_ID;
    assert_ok(sh_tool_create(world, &tool_def, &tool));
    sh_cut_def cut;
    sh_cut_def_default(&cut);
    assert_true(cut.resolution == 0.0); /* the default: a quarter of the blade */
    const double bad[3] = {-0.001, NAN, INFINITY};
    for (int k = 0; k < 3; ++k) {
        cut.resolution = bad[k];
        assert_error(sh_tool_set_cutting(world, tool, &cut), SH_ERR_INVALID_ARGUMENT, "resolution");
    }
    cut.resolution = 0.002;
    assert_ok(sh_tool_set_cutting(world, tool, &cut));
    assert_ok(sh_tool_set_cutting(world, tool, NULL));
    assert_ok(sh_world_destroy(world));
}

/* Measured-curve springs: tables that are not strictly increasing in strain, not finite, too
 * short or missing are errors naming the table; a valid one makes a body. */
static void test_spring_table_errors(void** state) {
    (void)state;
    sh_world* world = make_world();
    const double nodes[6] = {0, 0, 0, 0.01, 0, 0};
    const int32_t one_spring[2] = {0, 1};
    const double decreasing[6] = {0.0, 0.0, 0.2, 1.0, 0.1, 2.0};
    const double repeated[6] = {0.0, 0.0, 0.1, 1.0, 0.1, 2.0};
    const double good_table[6] = {-0.1, -1.0, 0.0, 0.0, 0.1, 1.0};
    const double nan_table[4] = {0.0, 0.0, NAN, 1.0};
    sh_spring_body_def def;

    two_node_def(&def, nodes, one_spring);
    def.params.law = SH_SPRING_TABLE;
    def.params.table = decreasing;
    def.params.table_rows = 3;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "table");
    def.params.table = repeated;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "table");
    def.params.table = nan_table;
    def.params.table_rows = 2;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "table");
    def.params.table = good_table;
    def.params.table_rows = 1;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "table_rows");
    def.params.table_rows = 0;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "table_rows");
    def.params.table_rows = -3;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "table_rows");
    def.params.table = NULL;
    def.params.table_rows = 3;
    EXPECT_SPRING_ERROR(&def, SH_ERR_INVALID_ARGUMENT, "table");

    two_node_def(&def, nodes, one_spring);
    def.params.law = SH_SPRING_TABLE;
    def.params.table = good_table;
    def.params.table_rows = 3;
    sh_body_id id;
    assert_ok(sh_spring_body_create(world, &def, &id));
    assert_ok(sh_world_destroy(world));
}

/* ------------------------------------------------------------------------------------------ */
/* Stepping and state                                                                           */

static void test_step_rejects_bad_dt(void** state) {
    const moved_box* s = *state;
    double* x = copy_positions(s->world, s->body);
    double* v = copy_velocities(s->world, s->body);
    double* xs = copy_positions(s->world, s->spring);
    double* vs = copy_velocities(s->world, s->spring);
    uint64_t warnings_before[SH_WARN_COUNT], warnings_after[SH_WARN_COUNT];
    assert_ok(sh_world_get_warnings(s->world, warnings_before));

    const double bad[] = {0.0, -0.0, -1e-3, NAN, -NAN, INFINITY, -INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        sh_step_report report;
        assert_error(sh_world_step(s->world, bad[i], &report), SH_ERR_INVALID_ARGUMENT, "dt");
        assert_error(sh_world_step(s->world, bad[i], NULL), SH_ERR_INVALID_ARGUMENT, "dt");
    }
    assert_state_is(s->world, s->body, x, v);
    assert_state_is(s->world, s->spring, xs, vs);
    assert_ok(sh_world_get_warnings(s->world, warnings_after));
    assert_memory_equal(warnings_after, warnings_before, sizeof warnings_before);

    free(x);
    free(v);
    free(xs);
    free(vs);
}

static void test_set_state_rejects_non_finite_and_wrong_counts(void** state) {
    const moved_box* s = *state;
    const int32_t n = node_count_of(s->world, s->body);
    double* x = copy_positions(s->world, s->body);
    double* v = copy_velocities(s->world, s->body);
    double* input = malloc(sizeof(double) * 3 * (size_t)n);
    assert_non_null(input);
    const double non_finite[] = {NAN, INFINITY, -INFINITY};

    for (size_t k = 0; k < sizeof non_finite / sizeof non_finite[0]; ++k) {
        /* One bad value at the last entry: nothing may have been copied before the check. */
        memcpy(input, x, sizeof(double) * 3 * (size_t)n);
        for (int32_t i = 0; i < 3 * n; ++i) input[i] += 1e-3;
        input[3 * n - 1] = non_finite[k];
        assert_error(sh_body_set_positions(s->world, s->body, input, n), SH_ERR_INVALID_ARGUMENT, "positions");
        assert_error(sh_body_set_velocities(s->world, s->body, input, n), SH_ERR_INVALID_ARGUMENT, "velocities");
        assert_error(sh_body_set_external_forces(s->world, s->body, input, n), SH_ERR_INVALID_ARGUMENT, "forces");
        const int32_t node = 3;
        const double target[3] = {0.0, non_finite[k], 0.0};
        assert_error(sh_body_prescribe_positions(s->world, s->body, &node, target, 1), SH_ERR_INVALID_ARGUMENT,
                     "positions");
        assert_state_is(s->world, s->body, x, v);
    }
    /* Wrong node counts. */
    memcpy(input, x, sizeof(double) * 3 * (size_t)n);
    const int32_t wrong[] = {n - 1, n + 1, 0, -1, INT32_MIN};
    for (size_t k = 0; k < sizeof wrong / sizeof wrong[0]; ++k) {
        assert_error(sh_body_set_positions(s->world, s->body, input, wrong[k]), SH_ERR_INVALID_ARGUMENT, "node_count");
        assert_error(sh_body_set_velocities(s->world, s->body, input, wrong[k]), SH_ERR_INVALID_ARGUMENT, "node_count");
        assert_error(sh_body_set_external_forces(s->world, s->body, input, wrong[k]), SH_ERR_INVALID_ARGUMENT,
                     "node_count");
        assert_error(sh_body_set_node_damping(s->world, s->body, input, wrong[k]), SH_ERR_INVALID_ARGUMENT, "node_count");
    }
    /* Bad node damping coefficients. */
    double coefficients[8] = {1, 1, 1, 1, 1, 1, 1, -1};
    assert_int_equal(n, 8);
    assert_error(sh_body_set_node_damping(s->world, s->body, coefficients, n), SH_ERR_INVALID_ARGUMENT, "coefficients[7]");
    coefficients[7] = NAN;
    assert_error(sh_body_set_node_damping(s->world, s->body, coefficients, n), SH_ERR_INVALID_ARGUMENT, "coefficients[7]");
    /* Bad gravity. */
    const double bad_gravity[3] = {0, NAN, 0};
    assert_error(sh_world_set_gravity(s->world, bad_gravity), SH_ERR_INVALID_ARGUMENT, "gravity");

    assert_state_is(s->world, s->body, x, v);

    /* A good set_positions does change them (so the comparisons above are meaningful). */
    for (int32_t i = 0; i < 3 * n; ++i) input[i] = x[i] + 1e-3;
    assert_ok(sh_body_set_positions(s->world, s->body, input, n));
    double* x_after = copy_positions(s->world, s->body);
    assert_memory_equal(x_after, input, sizeof(double) * 3 * (size_t)n);

    free(x_after);
    free(input);
    free(x);
    free(v);
}

static void test_get_capacity_too_small(void** state) {
    const moved_box* s = *state;
    const int32_t n = node_count_of(s->world, s->body);
    sh_mesh_info info;
    assert_ok(sh_mesh_get_info(s->mesh, &info));
    enum { SENTINEL_COUNT = 256 };
    double out[SENTINEL_COUNT], sentinel[SENTINEL_COUNT];
    int32_t iout[SENTINEL_COUNT], isentinel[SENTINEL_COUNT];
    for (int i = 0; i < SENTINEL_COUNT; ++i) {
        sentinel[i] = -12345.0;
        isentinel[i] = -777;
    }
    /* Capacities count items (nodes, tets, edges, triangles), each of `per` values. */
    const int32_t too_small[] = {-1, 0, 1};
#define CHECK_D(call_with_cap, items, per)                                                      \
    do {                                                                                        \
        for (size_t k_ = 0; k_ < sizeof too_small / sizeof too_small[0]; ++k_) {                \
            const int32_t cap = too_small[k_] <= 0 ? too_small[k_] : (items) - 1;              \
            memcpy(out, sentinel, sizeof out);                                                  \
            assert_error(call_with_cap, SH_ERR_INVALID_ARGUMENT, "capacity");                   \
            assert_memory_equal(out, sentinel, sizeof out);                                     \
        }                                                                                       \
        {                                                                                       \
            const int32_t cap = (items);                                                        \
            assert_ok(call_with_cap);                                                           \
            assert_memory_equal(out + (items) * (per), sentinel,                                \
                                sizeof(double) * (SENTINEL_COUNT - (items) * (per)));           \
        }                                                                                       \
    } while (0)
#define CHECK_I(call_with_cap, items, per)                                                      \
    do {                                                                                        \
        for (size_t k_ = 0; k_ < sizeof too_small / sizeof too_small[0]; ++k_) {                \
            const int32_t cap = too_small[k_] <= 0 ? too_small[k_] : (items) - 1;              \
            memcpy(iout, isentinel, sizeof iout);                                               \
            assert_error(call_with_cap, SH_ERR_INVALID_ARGUMENT, "capacity");                   \
            assert_memory_equal(iout, isentinel, sizeof iout);                                  \
        }                                                                                       \
        {                                                                                       \
            const int32_t cap = (items) + 5; /* larger than needed is fine */                   \
            memcpy(iout, isentinel, sizeof iout);                                               \
            assert_ok(call_with_cap);                                                           \
            assert_memory_equal(iout + (items) * (per), isentinel,                              \
                                sizeof(int32_t) * (SENTINEL_COUNT - (items) * (per)));          \
        }                                                                                       \
    } while (0)

    CHECK_D(sh_body_get_positions(s->world, s->body, out, cap), n, 3);
    CHECK_D(sh_body_get_velocities(s->world, s->body, out, cap), n, 3);
    CHECK_D(sh_body_get_masses(s->world, s->body, out, cap), n, 1);
    CHECK_D(sh_body_get_elastic_forces(s->world, s->body, out, cap), n, 3);
    CHECK_D(sh_mesh_get_nodes(s->mesh, out, cap), info.node_count, 3);
    CHECK_I(sh_mesh_get_tets(s->mesh, iout, cap), info.tet_count, 4);
    CHECK_I(sh_mesh_get_edges(s->mesh, iout, cap), info.edge_count, 2);
    CHECK_I(sh_mesh_get_surface_triangles(s->mesh, iout, cap), info.surface_triangle_count, 3);
#undef CHECK_D
#undef CHECK_I
}

static void test_fix_nodes_out_of_range_changes_nothing(void** state) {
    const moved_box* s = *state;
    double* x = copy_positions(s->world, s->body);
    double* v = copy_velocities(s->world, s->body);
    sh_body_info info;

    const int32_t high[3] = {0, 1, 8};
    const int32_t negative[2] = {0, -1};
    assert_error(sh_body_fix_nodes(s->world, s->body, high, 3), SH_ERR_INVALID_ARGUMENT, "nodes[2]");
    assert_error(sh_body_fix_nodes(s->world, s->body, negative, 2), SH_ERR_INVALID_ARGUMENT, "nodes[1]");
    assert_error(sh_body_fix_nodes(s->world, s->body, high, -1), SH_ERR_INVALID_ARGUMENT, "count");
    const double targets[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    assert_error(sh_body_prescribe_positions(s->world, s->body, high, targets, 3), SH_ERR_INVALID_ARGUMENT, "nodes[2]");
    assert_ok(sh_body_get_info(s->world, s->body, &info));
    assert_int_equal(info.fixed_node_count, 0); /* nodes 0 and 1 were not fixed either */
    assert_state_is(s->world, s->body, x, v);          /* their velocities were not zeroed */

    /* The valid part alone fixes them; out-of-range release changes nothing. */
    assert_ok(sh_body_fix_nodes(s->world, s->body, high, 2));
    assert_ok(sh_body_get_info(s->world, s->body, &info));
    assert_int_equal(info.fixed_node_count, 2);
    assert_error(sh_body_release_nodes(s->world, s->body, high, 3), SH_ERR_INVALID_ARGUMENT, "nodes[2]");
    assert_ok(sh_body_get_info(s->world, s->body, &info));
    assert_int_equal(info.fixed_node_count, 2);

    free(x);
    free(v);
}

/* A battery of failing calls on a moving body: none of them changes its state or the other
 * body's, and a subsequent step is identical to the step of an untouched twin world. */
static void test_failed_calls_leave_state_intact(void** state) {
    (void)state;
    sh_mesh* mesh = sh_test_box(0.02, 0.02, 0.02, 2, 1, 1);
    sh_world* worlds[2];
    sh_body_id bodies[2];
    for (int w = 0; w < 2; ++w) {
        worlds[w] = make_world();
        bodies[w] = add_fem(worlds[w], mesh);
        const int32_t fixed[2] = {0, 3};
        assert_ok(sh_body_fix_nodes(worlds[w], bodies[w], fixed, 2));
        move_a_bit(worlds[w]);
    }
    sh_world* world = worlds[0];
    const sh_body_id body = bodies[0];
    const int32_t n = node_count_of(world, body);
    double* x = copy_positions(world, body);
    double* v = copy_velocities(world, body);
    double* buffer = malloc(sizeof(double) * 3 * (size_t)(n + 1));
    assert_non_null(buffer);
    memcpy(buffer, x, sizeof(double) * 3 * (size_t)n);
    buffer[5] = NAN;
    const int32_t bad_nodes[2] = {1, n};
    const sh_material bad = sh_test_material(SH_MATERIAL_STVK, -1.0, 0.3, 1000);
    const int32_t all[1] = {0};
    sh_fem_body_def bad_def;
    sh_fem_body_def_default(&bad_def);
    bad_def.mesh = mesh;
    bad_def.material.poisson = 0.5;
    sh_body_id id;

    assert_status(sh_world_step(world, NAN, NULL), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_set_positions(world, body, buffer, n), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_set_velocities(world, body, buffer, n), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_set_positions(world, body, x, n + 1), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_set_external_forces(world, body, buffer, n), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_fix_nodes(world, body, bad_nodes, 2), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_release_nodes(world, body, bad_nodes, 2), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_prescribe_positions(world, body, bad_nodes, buffer, 2), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_set_material(world, body, all, 1, &bad), SH_ERR_INVALID_ARGUMENT);
    const sh_material good = sh_test_material(SH_MATERIAL_COROTATIONAL, 1e5, 0.3, 3000);
    assert_status(sh_body_set_material(world, body, bad_nodes, 2, &good), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_get_positions(world, body, buffer, n - 1), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_fem_body_create(world, &bad_def, &id), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_body_destroy(world, (sh_body_id){body.value + 1}), SH_ERR_INVALID_HANDLE);
    assert_state_is(world, body, x, v);

    /* Same next step as the twin that saw no failed call: no hidden state was touched. */
    for (int i = 0; i < 20; ++i) {
        assert_ok(sh_world_step(worlds[0], 1e-4, NULL));
        assert_ok(sh_world_step(worlds[1], 1e-4, NULL));
    }
    double* x0 = copy_positions(worlds[0], bodies[0]);
    double* x1 = copy_positions(worlds[1], bodies[1]);
    double* v0 = copy_velocities(worlds[0], bodies[0]);
    double* v1 = copy_velocities(worlds[1], bodies[1]);
    assert_memory_equal(x0, x1, sizeof(double) * 3 * (size_t)n);
    assert_memory_equal(v0, v1, sizeof(double) * 3 * (size_t)n);

    free(x0);
    free(x1);
    free(v0);
    free(v1);
    free(buffer);
    free(x);
    free(v);
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(worlds[0]));
    assert_ok(sh_world_destroy(worlds[1]));
}

/* ------------------------------------------------------------------------------------------ */
/* Mesh creation misuse                                                                         */

static void test_mesh_create_misuse(void** state) {
    (void)state;
    const double nodes[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const int32_t tets[4] = {0, 1, 2, 3};
    const int32_t bad_index[4] = {0, 1, 2, 4};
    const int32_t repeated[4] = {0, 1, 2, 2};
    const double nan_nodes[12] = {0, 0, 0, 1, 0, 0, 0, NAN, 0, 0, 0, 1};
    const double flat[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    sh_mesh* mesh = (sh_mesh*)&mesh;

    assert_error(sh_mesh_create(NULL, 4, tets, 1, &mesh), SH_ERR_INVALID_ARGUMENT, "nodes");
    assert_null(mesh);
    assert_error(sh_mesh_create(nodes, 4, NULL, 1, &mesh), SH_ERR_INVALID_ARGUMENT, "tets");
    assert_error(sh_mesh_create(nodes, 0, tets, 1, &mesh), SH_ERR_INVALID_ARGUMENT, "node_count");
    assert_error(sh_mesh_create(nodes, -4, tets, 1, &mesh), SH_ERR_INVALID_ARGUMENT, "node_count");
    assert_error(sh_mesh_create(nodes, 4, tets, 0, &mesh), SH_ERR_INVALID_ARGUMENT, "tet_count");
    assert_error(sh_mesh_create(nodes, 4, tets, -1, &mesh), SH_ERR_INVALID_ARGUMENT, "tet_count");
    assert_error(sh_mesh_create(nodes, 4, bad_index, 1, &mesh), SH_ERR_DEGENERATE_MESH, "out of range");
    assert_error(sh_mesh_create(nodes, 4, repeated, 1, &mesh), SH_ERR_DEGENERATE_MESH, "node 2");
    assert_error(sh_mesh_create(nan_nodes, 4, tets, 1, &mesh), SH_ERR_DEGENERATE_MESH, "node 2");
    assert_error(sh_mesh_create(flat, 4, tets, 1, &mesh), SH_ERR_DEGENERATE_MESH, "zero volume");
    assert_null(mesh);
    assert_error(sh_mesh_load(NULL, &mesh), SH_ERR_INVALID_ARGUMENT, "path");
    assert_null(mesh);
}

static void test_write_vtu_to_unwritable_path(void** state) {
    (void)state;
    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_unit_tet(0.01);
    const sh_body_id body = add_fem(world, mesh);
    assert_error(sh_body_write_vtu(world, body, "/nonexistent-softhap-dir/frame.vtu"), SH_ERR_IO,
                 "nonexistent-softhap-dir");
    assert_error(sh_mesh_write_vtu(mesh, "/nonexistent-softhap-dir/mesh.vtu"), SH_ERR_IO, "nonexistent-softhap-dir");
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
}

/* ------------------------------------------------------------------------------------------ */
/* Cutting and topology queries: the API surface (what a cut does is test_cut's)                */

/* Asserts the body is still its uncut self: topology version 0, node and tet counts as given. */
static void assert_uncut(const sh_world* world, sh_body_id body, int32_t nodes, int32_t tets) {
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    assert_int_equal(info.topology_version, 0);
    assert_int_equal(info.node_count, nodes);
    assert_int_equal(info.element_count, tets);
}

static void test_cut_rejects_bad_arguments(void** state) {
    (void)state;
    sh_world* world = make_world();
    sh_mesh* mesh = sh_test_box(0.02, 0.02, 0.02, 1, 1, 1);
    const sh_mesh_info mesh_info = sh_test_mesh_info(mesh);
    const sh_body_id body = add_fem(world, mesh);
    const sh_body_id stale = add_fem(world, mesh);
    assert_ok(sh_body_destroy(world, stale));
    /* Two triangles spanning the plane x = 7 mm, well past the 2 cm box on every side. */
    const double blade[18] = {0.007, -1, -1, 0.007, 1, -1, 0.007, 1, 1,
                              0.007, -1, -1, 0.007, 1, 1,  0.007, -1, 1};
    double nan_blade[18], flat_blade[18];
    memcpy(nan_blade, blade, sizeof blade);
    nan_blade[9 + 4] = NAN; /* triangle 1, corner 1, y */
    memcpy(flat_blade, blade, sizeof blade);
    memcpy(flat_blade + 6, flat_blade + 3, 3 * sizeof(double)); /* triangle 0: two equal corners */
    sh_cut_report report, untouched;
    memset(&untouched, 0x5a, sizeof untouched);
    report = untouched;

    assert_error(sh_body_cut(world, body, NULL, 2, &report), SH_ERR_INVALID_ARGUMENT, "triangles");
    assert_error(sh_body_cut(world, body, NULL, 2, NULL), SH_ERR_INVALID_ARGUMENT, "triangles");
    assert_error(sh_body_cut(world, body, blade, 0, &report), SH_ERR_INVALID_ARGUMENT, "triangle_count");
    assert_error(sh_body_cut(world, body, blade, -3, NULL), SH_ERR_INVALID_ARGUMENT, "triangle_count");
    assert_error(sh_body_cut(world, body, blade, INT32_MIN, &report), SH_ERR_INVALID_ARGUMENT, "triangle_count");
    assert_error(sh_body_cut(world, body, nan_blade, 2, &report), SH_ERR_INVALID_ARGUMENT, "triangles[1]");
    assert_error(sh_body_cut(world, body, flat_blade, 2, &report), SH_ERR_INVALID_ARGUMENT, "triangles[0]");
    assert_error(sh_body_cut(NULL, body, blade, 2, &report), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_cut(world, stale, blade, 2, &report), SH_ERR_INVALID_HANDLE, "body");
    assert_error(sh_body_cut(world, (sh_body_id)SH_NULL_ID, blade, 2, &report), SH_ERR_INVALID_HANDLE, "body");
    /* A stale id is reported before the other arguments are looked at. */
    assert_error(sh_body_cut(world, stale, NULL, 0, &report), SH_ERR_INVALID_HANDLE, "body");
    /* A failed cut writes no report and changes nothing. */
    assert_memory_equal(&report, &untouched, sizeof report);
    assert_uncut(world, body, mesh_info.node_count, mesh_info.tet_count);

    /* The same blade, valid: out_report may be NULL, and the body is cut. */
    assert_ok(sh_body_cut(world, body, blade, 2, NULL));
    assert_no_error_message();
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    assert_true(info.topology_version > 0);
    assert_true(info.node_count > mesh_info.node_count);
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
}

typedef sh_status (*topology_getter)(const sh_world*, sh_body_id, int32_t*, int32_t);

/* Asserts get refuses NULL and the capacities -1, 0 and items - 1 (SH_ERR_INVALID_ARGUMENT
 * naming the capacity, nothing written), and copies items x per values into room for more,
 * writing nothing past them; leaves the copy in out. */
static void check_topology_getter(topology_getter get, const char* name, const sh_world* world, sh_body_id body,
                                  int32_t items, int per, int32_t* out, size_t out_count) {
    int32_t* sentinel = malloc(out_count * sizeof(int32_t));
    assert_non_null(sentinel);
    for (size_t i = 0; i < out_count; ++i) sentinel[i] = -777;
    assert_true((size_t)(items + 1) * (size_t)per <= out_count);
    assert_error(get(world, body, NULL, items), SH_ERR_INVALID_ARGUMENT, name);
    const int32_t too_small[] = {-1, 0, items - 1};
    for (size_t k = 0; k < sizeof too_small / sizeof too_small[0]; ++k) {
        memcpy(out, sentinel, out_count * sizeof(int32_t));
        assert_error(get(world, body, out, too_small[k]), SH_ERR_INVALID_ARGUMENT, "capacity");
        assert_memory_equal(out, sentinel, out_count * sizeof(int32_t));
    }
    memcpy(out, sentinel, out_count * sizeof(int32_t));
    assert_ok(get(world, body, out, items + 1)); /* larger than needed is fine */
    assert_memory_equal(out + (size_t)items * (size_t)per, sentinel,
                        (out_count - (size_t)items * (size_t)per) * sizeof(int32_t));
    free(sentinel);
}

static void test_topology_getters_check_capacity_and_kind(void** state) {
    const moved_box* s = *state;
    sh_test_mesh_arrays mesh = sh_test_mesh_arrays_of(s->mesh);
    const sh_mesh_info mesh_info = sh_test_mesh_info(s->mesh);
    enum { ROOM = 256 };
    int32_t out[ROOM];

    sh_body_info info;
    assert_ok(sh_body_get_info(s->world, s->body, &info));
    assert_int_equal(info.surface_triangle_count, mesh_info.surface_triangle_count);
    assert_int_equal(info.topology_version, 0);
    assert_int_equal(info.reserved, 0);
    check_topology_getter(sh_body_get_tets, "out_tets", s->world, s->body, info.element_count, 4, out, ROOM);
    assert_memory_equal(out, mesh.tets, sizeof(int32_t) * 4 * (size_t)mesh_info.tet_count);
    check_topology_getter(sh_body_get_surface_triangles, "out_triangles", s->world, s->body,
                          info.surface_triangle_count, 3, out, ROOM);
    assert_memory_equal(out, mesh.triangles, sizeof(int32_t) * 3 * (size_t)mesh_info.surface_triangle_count);
    check_topology_getter(sh_body_get_node_parents, "out_parents", s->world, s->body, info.node_count, 1, out, ROOM);
    for (int32_t i = 0; i < info.node_count; ++i) assert_int_equal(out[i], -1);

    sh_body_info spring_info;
    assert_ok(sh_body_get_info(s->world, s->spring, &spring_info));
    assert_int_equal(spring_info.surface_triangle_count, 0);
    assert_int_equal(spring_info.topology_version, 0);
    check_topology_getter(sh_body_get_springs, "out_springs", s->world, s->spring, spring_info.element_count, 2, out, ROOM);
    assert_int_equal(out[0], 0);
    assert_int_equal(out[1], 1);
    check_topology_getter(sh_body_get_node_parents, "out_parents", s->world, s->spring, 2, 1, out, ROOM);
    assert_int_equal(out[0], -1);
    assert_int_equal(out[1], -1);

    /* The wrong kind of body, whatever the capacity: the message names the kind. */
    assert_error(sh_body_get_tets(s->world, s->spring, out, ROOM / 4), SH_ERR_UNSUPPORTED, "mass-spring");
    assert_error(sh_body_get_surface_triangles(s->world, s->spring, out, ROOM / 3), SH_ERR_UNSUPPORTED, "mass-spring");
    assert_error(sh_body_get_springs(s->world, s->body, out, ROOM / 2), SH_ERR_UNSUPPORTED, "FEM");
    assert_error(sh_body_get_tets(s->world, s->spring, NULL, 0), SH_ERR_UNSUPPORTED, "sh_body_get_tets");

    /* Handles and ids. */
    assert_error(sh_body_get_tets(NULL, s->body, out, ROOM / 4), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_get_springs(NULL, s->spring, out, ROOM / 2), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_get_surface_triangles(NULL, s->body, out, ROOM / 3), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_get_node_parents(NULL, s->body, out, ROOM), SH_ERR_INVALID_HANDLE, "world");
    assert_error(sh_body_get_node_parents(s->world, (sh_body_id)SH_NULL_ID, out, ROOM), SH_ERR_INVALID_HANDLE, "body");
    sh_test_mesh_arrays_free(&mesh);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_version_matches_header),
        cmocka_unit_test(test_status_strings_non_null_and_distinct),
        cmocka_unit_test(test_last_error_cleared_by_success),
        cmocka_unit_test(test_null_out_pointers),
        cmocka_unit_test(test_null_defs),
        cmocka_unit_test(test_null_handles),
        cmocka_unit_test(test_foreign_pointers),
        cmocka_unit_test(test_destroyed_world),
        cmocka_unit_test(test_stale_handles_never_name_a_new_object),
        cmocka_unit_test(test_destroyed_mesh),
        cmocka_unit_test(test_stale_body_ids),
        cmocka_unit_test(test_null_and_garbage_body_ids),
        cmocka_unit_test(test_body_id_of_another_empty_world),
        cmocka_unit_test(test_body_id_of_another_populated_world),
        cmocka_unit_test(test_uninitialized_defs),
        cmocka_unit_test(test_uninitialized_materials_and_contact_params),
        cmocka_unit_test(test_material_validation_in_def),
        cmocka_unit_test_setup_teardown(test_material_validation_in_set_material, setup_moved_box, teardown_moved_box),
        cmocka_unit_test(test_spring_def_topology_errors),
        cmocka_unit_test(test_spring_law_errors),
        cmocka_unit_test(test_spring_table_errors),
        cmocka_unit_test(test_spring_break_strain),
        cmocka_unit_test(test_cut_def_resolution),
        cmocka_unit_test_setup_teardown(test_step_rejects_bad_dt, setup_moved_box_and_spring, teardown_moved_box),
        cmocka_unit_test_setup_teardown(test_set_state_rejects_non_finite_and_wrong_counts, setup_moved_box, teardown_moved_box),
        cmocka_unit_test_setup_teardown(test_get_capacity_too_small, setup_moved_box, teardown_moved_box),
        cmocka_unit_test_setup_teardown(test_fix_nodes_out_of_range_changes_nothing, setup_moved_box, teardown_moved_box),
        cmocka_unit_test(test_failed_calls_leave_state_intact),
        cmocka_unit_test(test_mesh_create_misuse),
        cmocka_unit_test(test_write_vtu_to_unwritable_path),
        cmocka_unit_test(test_cut_rejects_bad_arguments),
        cmocka_unit_test_setup_teardown(test_topology_getters_check_capacity_and_kind, setup_moved_box_and_spring,
                                        teardown_moved_box),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
