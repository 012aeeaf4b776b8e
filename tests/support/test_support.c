#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

void sh_test_assert_status(sh_status got, sh_status expected, const char* expr, const char* file, int line) {
    if (got != expected) {
        print_error("%s:%d: %s returned %s, expected %s (last error: %s)\n", file, line, expr,
                    sh_status_string(got), sh_status_string(expected), sh_last_error_message());
        _fail(file, line);
    }
}

void sh_test_assert_close(double a, double b, double tol, const char* expr, const char* file, int line) {
    const double scale = fabs(b) > 1.0 ? fabs(b) : 1.0;
    if (!(fabs(a - b) <= tol * scale)) {
        print_error("%s:%d: %s = %.17g, expected %.17g (tolerance %g)\n", file, line, expr, a, b, tol);
        _fail(file, line);
    }
}

sh_material sh_test_material(sh_material_model model, double young, double poisson, double density) {
    sh_material m;
    sh_material_default(&m);
    m.model = model;
    m.young = young;
    m.poisson = poisson;
    m.density = density;
    return m;
}

void sh_test_skip_from_environment(void) {
    const char* pattern = getenv("SOFTHAP_SKIP_TESTS");
    if (pattern && pattern[0]) cmocka_set_skip_filter(pattern);
}

sh_world* sh_test_world(double gravity_z) {
    sh_world_def def;
    sh_world_def_default(&def);
    def.gravity[2] = gravity_z;
    sh_world* world = NULL;
    sh_test_assert_status(sh_world_create(&def, &world), SH_OK, "sh_world_create", __FILE__, __LINE__);
    return world;
}

static sh_body_id spring_pair(sh_world* world, double rest_length, const sh_spring_params* params, double mass,
                              sh_integrator integrator, sh_unstable_policy policy, sh_linear_solver solver) {
    const double nodes[6] = {0, 0, 0, rest_length, 0, 0};
    const int32_t springs[2] = {0, 1};
    sh_spring_body_def def;
    sh_spring_body_def_default(&def);
    def.nodes = nodes;
    def.node_count = 2;
    def.springs = springs;
    def.spring_count = 1;
    def.params = *params;
    def.node_mass = mass;
    def.integrator = integrator;
    def.on_unstable = policy;
    def.implicit.linear_solver = solver;
    sh_body_id body = SH_NULL_ID;
    sh_test_assert_status(sh_spring_body_create(world, &def, &body), SH_OK, "sh_spring_body_create", __FILE__, __LINE__);
    return body;
}

sh_body_id sh_test_spring_pair(sh_world* world, double rest_length, const sh_spring_params* params, double mass,
                               sh_integrator integrator, sh_unstable_policy policy) {
    return spring_pair(world, rest_length, params, mass, integrator, policy, SH_LINEAR_SOLVER_DEFAULT);
}

sh_body_id sh_test_oscillator(sh_world* world, sh_integrator integrator, sh_linear_solver solver) {
    sh_spring_params params = {SH_SPRING_LINEAR};
    params.stiffness = SH_TEST_OSC_STIFFNESS;
    const sh_body_id body =
        spring_pair(world, SH_TEST_OSC_REST, &params, SH_TEST_OSC_MASS, integrator, SH_UNSTABLE_REJECT, solver);
    const int32_t anchor = 0;
    sh_test_assert_status(sh_body_fix_nodes(world, body, &anchor, 1), SH_OK, "sh_body_fix_nodes", __FILE__, __LINE__);
    const double start[6] = {0, 0, 0, SH_TEST_OSC_REST + SH_TEST_OSC_AMPLITUDE, 0, 0};
    sh_test_assert_status(sh_body_set_positions(world, body, start, 2), SH_OK, "sh_body_set_positions", __FILE__,
                          __LINE__);
    return body;
}

double sh_test_oscillator_energy(const sh_world* world, sh_body_id body) {
    double x[6], v[6];
    sh_test_assert_status(sh_body_get_positions(world, body, x, 2), SH_OK, "sh_body_get_positions", __FILE__, __LINE__);
    sh_test_assert_status(sh_body_get_velocities(world, body, v, 2), SH_OK, "sh_body_get_velocities", __FILE__,
                          __LINE__);
    const double d = x[3] - SH_TEST_OSC_REST;
    return 0.5 * SH_TEST_OSC_MASS * v[3] * v[3] + 0.5 * SH_TEST_OSC_STIFFNESS * d * d;
}

void sh_test_oscillator_backward_euler(double* stretch, double* velocity, double h, double c) {
    const double m = SH_TEST_OSC_MASS, k = SH_TEST_OSC_STIFFNESS;
    *velocity = (m * *velocity - h * k * *stretch) / (m * (1.0 + h * c) + h * h * k);
    *stretch += h * *velocity;
}

sh_mesh* sh_test_unit_tet(double s) {
    const double nodes[12] = {0, 0, 0, s, 0, 0, 0, s, 0, 0, 0, s};
    const int32_t tets[4] = {0, 1, 2, 3};
    sh_mesh* mesh = NULL;
    sh_test_assert_status(sh_mesh_create(nodes, 4, tets, 1, &mesh), SH_OK, "sh_mesh_create", __FILE__, __LINE__);
    return mesh;
}

sh_mesh_info sh_test_mesh_info(const sh_mesh* mesh) {
    sh_mesh_info info;
    sh_test_assert_status(sh_mesh_get_info(mesh, &info), SH_OK, "sh_mesh_get_info", __FILE__, __LINE__);
    return info;
}

sh_test_mesh_arrays sh_test_mesh_arrays_of(const sh_mesh* mesh) {
    sh_test_mesh_arrays m;
    m.info = sh_test_mesh_info(mesh);
    m.node_count = m.info.node_count;
    m.tet_count = m.info.tet_count;
    m.triangle_count = m.info.surface_triangle_count;
    m.nodes = malloc(sizeof(double) * 3 * (size_t)m.node_count);
    m.tets = malloc(sizeof(int32_t) * 4 * (size_t)m.tet_count);
    m.triangles = malloc(sizeof(int32_t) * 3 * (size_t)m.triangle_count + 1);
    sh_test_assert_status(sh_mesh_get_nodes(mesh, m.nodes, m.node_count), SH_OK, "sh_mesh_get_nodes",
                          __FILE__, __LINE__);
    sh_test_assert_status(sh_mesh_get_tets(mesh, m.tets, m.tet_count), SH_OK, "sh_mesh_get_tets",
                          __FILE__, __LINE__);
    sh_test_assert_status(sh_mesh_get_surface_triangles(mesh, m.triangles, m.triangle_count), SH_OK,
                          "sh_mesh_get_surface_triangles", __FILE__, __LINE__);
    return m;
}

void sh_test_mesh_arrays_free(sh_test_mesh_arrays* m) {
    free(m->nodes);
    free(m->tets);
    free(m->triangles);
}

double sh_test_tet_volume(const double* nodes, const int32_t* tet) {
    const double* p0 = &nodes[3 * tet[0]];
    double a[3], b[3], c[3];
    for (int k = 0; k < 3; ++k) {
        a[k] = nodes[3 * tet[1] + k] - p0[k];
        b[k] = nodes[3 * tet[2] + k] - p0[k];
        c[k] = nodes[3 * tet[3] + k] - p0[k];
    }
    return (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) /
           6.0;
}

int sh_test_nodes_at(const double* nodes, int node_count, int axis, double value, int32_t* out) {
    int count = 0;
    for (int i = 0; i < node_count; ++i)
        if (fabs(nodes[3 * i + axis] - value) < 1e-12) out[count++] = i;
    return count;
}

sh_mesh* sh_test_box(double lx, double ly, double lz, int nx, int ny, int nz) {
    double* nodes;
    int32_t* tets;
    int32_t node_count, tet_count;
    sh_test_box_arrays(lx, ly, lz, nx, ny, nz, &nodes, &node_count, &tets, &tet_count);
    sh_mesh* mesh = NULL;
    sh_test_assert_status(sh_mesh_create(nodes, node_count, tets, tet_count, &mesh), SH_OK, "sh_mesh_create", __FILE__, __LINE__);
    free(nodes);
    free(tets);
    return mesh;
}

void sh_test_stiff_implicit_def(sh_fem_body_def* def, const sh_mesh* mesh, sh_material_model model) {
    sh_fem_body_def_default(def);
    def->mesh = mesh;
    def->material.model = model;
    def->material.young = 1e9;
    def->material.poisson = 0.3;
    def->integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    def->implicit.newton_max_iterations = 10;
    def->implicit.newton_tolerance = 1e-10;
}
