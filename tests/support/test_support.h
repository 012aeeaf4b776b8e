/* Shared fixtures for the cmocka tests. Include after <stdarg.h>, <stddef.h>, <setjmp.h>. */
#ifndef SOFTHAP_TEST_SUPPORT_H
#define SOFTHAP_TEST_SUPPORT_H

#include <softhap/softhap.h>

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "box_mesh.h"

/** Path of a file in ../shared/meshes (tests run from the repository root). */
#define SH_TEST_MESH(name) ("../shared/meshes/" name)

/** Asserts that expr returns status, printing the last-error message if not. */
#define assert_status(expr, status) sh_test_assert_status((expr), (status), #expr, __FILE__, __LINE__)

/** Asserts that expr returns SH_OK. */
#define assert_ok(expr) assert_status((expr), SH_OK)

/** Skips the tests whose names match the cmocka pattern in the environment variable
 *  SOFTHAP_SKIP_TESTS, if set: for runs that leave out what another run covers (the
 *  sanitizer builds leave out their slowest explicit-contact study, see the Makefile). */
void sh_test_skip_from_environment(void);

/** Implementation of assert_status. */
void sh_test_assert_status(sh_status got, sh_status expected, const char* expr, const char* file, int line);

/** Asserts |a - b| <= tol * max(1, |b|) (relative above 1, absolute below). */
#define assert_close(a, b, tol) sh_test_assert_close((a), (b), (tol), #a, __FILE__, __LINE__)

/** Implementation of assert_close. */
void sh_test_assert_close(double a, double b, double tol, const char* expr, const char* file, int line);

/** A world with gravity (0, 0, gravity_z). */
sh_world* sh_test_world(double gravity_z);

/* A material from sh_material_default with these model, E (Pa), nu and rho (kg/m^3). */
sh_material sh_test_material(sh_material_model model, double young, double poisson, double density);

/** Adds a two-node spring body along x: node 0 at the origin, node 1 at (rest_length, 0, 0),
 *  one spring with params, node masses `mass`, the given integrator and policy. */
sh_body_id sh_test_spring_pair(sh_world* world, double rest_length, const sh_spring_params* params, double mass,
                               sh_integrator integrator, sh_unstable_policy policy);

/** The test oscillator: a spring pair along x (sh_test_spring_pair) with node 0 fixed, node 1
 *  of mass SH_TEST_OSC_MASS on a linear spring of stiffness SH_TEST_OSC_STIFFNESS and rest
 *  length SH_TEST_OSC_REST, started at rest stretched by SH_TEST_OSC_AMPLITUDE. Steps above the
 *  critical one are rejected (a test never sub-steps silently); solver is the implicit
 *  integrator's linear solver. Its motion is x(t) = L + A cos(w t), w = sqrt(k / m). */
#define SH_TEST_OSC_MASS 1.0
#define SH_TEST_OSC_STIFFNESS 100.0
#define SH_TEST_OSC_REST 1.0
#define SH_TEST_OSC_AMPLITUDE 0.01
sh_body_id sh_test_oscillator(sh_world* world, sh_integrator integrator, sh_linear_solver solver);

/** Kinetic plus spring energy of the test oscillator's moving node (J), read from the body. */
double sh_test_oscillator_energy(const sh_world* world, sh_body_id body);

/** One exact backward Euler step of the test oscillator with node damping c (force -c m v):
 *  (m (1 + h c) + h^2 k) v1 = m v - h k s, s1 = s + h v1, for its stretch s and velocity v. */
void sh_test_oscillator_backward_euler(double* stretch, double* velocity, double h, double c);

/** A unit right-handed tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1) scaled by s, as a mesh. */
sh_mesh* sh_test_unit_tet(double s);

/** A mesh's info and arrays, read through the public getters; free with
 *  sh_test_mesh_arrays_free. */
typedef struct sh_test_mesh_arrays {
    sh_mesh_info info;
    int32_t node_count, tet_count, triangle_count; /**< copies of the info's counts */
    double* nodes;                                 /**< node_count x 3 */
    int32_t* tets;                                 /**< tet_count x 4 */
    int32_t* triangles;                            /**< triangle_count x 3, outward surface */
} sh_test_mesh_arrays;
sh_test_mesh_arrays sh_test_mesh_arrays_of(const sh_mesh* mesh);
void sh_test_mesh_arrays_free(sh_test_mesh_arrays* m);

/** sh_mesh_get_info, asserted to succeed. */
sh_mesh_info sh_test_mesh_info(const sh_mesh* mesh);

/** Signed volume of tet (4 node indices) over nodes (x3): positive when right-handed. */
double sh_test_tet_volume(const double* nodes, const int32_t* tet);

/** Nodes among nodes[node_count x 3] whose coordinate axis equals value (to 1e-12 m), written
 *  to out; returns their count. */
int sh_test_nodes_at(const double* nodes, int node_count, int axis, double value, int32_t* out);

/** The box of sh_test_box_arrays (box_mesh.h) as a mesh. */
sh_mesh* sh_test_box(double lx, double ly, double lz, int nx, int ny, int nz);

/** Fills def with the defaults and a stiff (E = 1 GPa, nu = 0.3) FEM body on mesh with the given
 *  material model, integrated by implicit Euler with at most 10 Newton iterations to 1e-10. */
void sh_test_stiff_implicit_def(sh_fem_body_def* def, const sh_mesh* mesh, sh_material_model model);

#endif
