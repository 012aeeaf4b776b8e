/* Tools, obstacles and Hunt-Crossley contact: impact restitution against the impact ODE,
 * friction against Coulomb's law, the tool's reaction, degenerate inputs and capacity. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- The Hunt-Crossley impact, independently of the library ------------------------------ */

/* m x'' = -lambda x^n (1 + c x'), c = 3/2 alpha, from x = 0 at speed v_in > 0: integrated with
 * classical RK4 at a step of 1/20000 of the contact time scale until x returns to 0; the exit
 * speed x' < 0 is interpolated at the crossing. Returns -x'(exit) / v_in. */
static double hunt_crossley_ode_ratio(double m, double lambda, double n, double alpha, double v_in) {
    const double c = 1.5 * alpha;
    const double x_max = pow((n + 1.0) * 0.5 * m * v_in * v_in / lambda, 1.0 / (n + 1.0));
    const double h = x_max / v_in / 20000.0;
    double x = 0.0, v = v_in;
#define HC_ACC(X, V) ((X) > 0.0 ? -lambda * pow((X), n) * fmax(0.0, 1.0 + c * (V)) / m : 0.0)
    for (int i = 0; i < 10000000; ++i) {
        const double k1x = v, k1v = HC_ACC(x, v);
        const double k2x = v + 0.5 * h * k1v, k2v = HC_ACC(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
        const double k3x = v + 0.5 * h * k2v, k3v = HC_ACC(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
        const double k4x = v + h * k3v, k4v = HC_ACC(x + h * k3x, v + h * k3v);
        const double xn = x + h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
        const double vn = v + h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
        if (i > 0 && xn <= 0.0) {
            const double s = x / (x - xn); /* linear interpolation to x = 0 */
            return -(v + s * (vn - v)) / v_in;
        }
        x = xn;
        v = vn;
    }
#undef HC_ACC
    return NAN;
}

/* The same ratio from the closed form of the impact: with c = 3/2 alpha, integrating
 * v dv / (1 + c v) = -(lambda/m) x^n dx over the whole contact gives G(v_out) = G(v_in) for
 * G(v) = v / c - ln(1 + c v) / c^2; solved for v_out in (-1/c, 0) by bisection. */
static double hunt_crossley_closed_ratio(double alpha, double v_in) {
    const double c = 1.5 * alpha;
#define HC_G(V) ((V) / c - log1p(c * (V)) / (c * c))
    const double target = HC_G(v_in);
    double lo = -1.0 / c * (1.0 - 1e-15), hi = 0.0;  /* G decreasing on (-1/c, 0) */
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (HC_G(mid) > target) lo = mid;
        else hi = mid;
    }
#undef HC_G
    return -0.5 * (lo + hi) / v_in;
}

/* A particle (one-node spring body) of mass m at height z0 moving down at speed v, and a
 * plane obstacle z = 0 with the given law. */
static sh_body_id particle(sh_world* world, double m, double z0, double v, sh_integrator integrator) {
    sh_spring_body_def def;
    sh_spring_body_def_default(&def);
    const double node[3] = {0.0, 0.0, z0};
    def.nodes = node;
    def.node_count = 1;
    def.node_mass = m;
    def.integrator = integrator;
    sh_body_id body = 0;
    assert_ok(sh_world_add_spring_body(world, &def, &body));
    const double velocity[3] = {0.0, 0.0, -v};
    assert_ok(sh_body_set_velocities(world, body, velocity, 1));
    return body;
}

static sh_obstacle_id floor_plane(sh_world* world, const sh_contact_params* law) {
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_PLANE;
    def.contact = *law;
    sh_obstacle_id id = 0;
    assert_ok(sh_obstacle_create(world, &def, &id));
    return id;
}

/* Drops the particle and returns its rebound speed over its impact speed. */
static double simulated_ratio(const sh_contact_params* law, double m, double v_in, sh_integrator integrator) {
    sh_world* world = sh_test_world(0.0);
    floor_plane(world, law);
    const double x_max = pow((law->exponent + 1.0) * 0.5 * m * v_in * v_in / law->stiffness, 1.0 / (law->exponent + 1.0));
    const double dt = x_max / v_in / 400.0;
    const sh_body_id body = particle(world, m, 0.5 * x_max, v_in, integrator);
    double v[3] = {0};
    int left = 0;
    for (int i = 0; i < 100000 && !left; ++i) {
        assert_ok(sh_world_step(world, dt, NULL));
        double x[3];
        assert_ok(sh_body_get_positions(world, body, x, 3));
        assert_ok(sh_body_get_velocities(world, body, v, 3));
        left = v[2] > 0.0 && x[2] > 0.0;
    }
    assert_true(left);
    assert_ok(sh_world_destroy(world));
    return v[2] / v_in;
}

static void test_impact_restitution_matches_hunt_crossley(void** state) {
    (void)state;
    sh_contact_params law;
    sh_contact_params_default(&law);
    law.stiffness = 1e4;
    law.exponent = 1.5;
    law.damping = 0.3;
    const double m = 1e-3;
    const double speeds[] = {0.05, 0.2, 0.5, 1.0, 2.0};
    for (size_t k = 0; k < sizeof speeds / sizeof speeds[0]; ++k) {
        const double v = speeds[k];
        const double ode = hunt_crossley_ode_ratio(m, law.stiffness, law.exponent, law.damping, v);
        const double closed = hunt_crossley_closed_ratio(law.damping, v);
        assert_close(ode, closed, 1e-4); /* the two references agree */
        const double rk4 = simulated_ratio(&law, m, v, SH_INTEGRATOR_RK4);
        const double symplectic = simulated_ratio(&law, m, v, SH_INTEGRATOR_SYMPLECTIC_EULER);
        printf("v_in %.2f m/s: ODE %.5f, closed form %.5f, 1 - alpha v %.5f; RK4 %.5f, symplectic Euler %.5f\n", v, ode,
               closed, 1.0 - law.damping * v, rk4, symplectic);
        assert_true(fabs(rk4 - ode) <= 0.02 * ode);
        assert_true(fabs(symplectic - ode) <= 0.02 * ode);
        if (law.damping * v <= 0.1) assert_true(fabs(rk4 - (1.0 - law.damping * v)) <= 0.02);
    }
}

/* ---- FEM bodies against obstacles and tools ---------------------------------------------- */

/* An FEM cube of side a (n cells per side) with its lowest corner at (x0, y0, z0). */
static sh_body_id fem_cube(sh_world* world, double a, int n, double x0, double y0, double z0, double young,
                           sh_integrator integrator) {
    sh_mesh* unit = sh_test_box(a, a, a, n, n, n);
    const double shift[3] = {x0, y0, z0};
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_transform(unit, 1.0, shift, &mesh));
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = SH_MATERIAL_COROTATIONAL;
    def.material.young = young;
    def.material.poisson = 0.3;
    def.integrator = integrator;
    def.damping_mass = 20.0;
    sh_body_id body = 0;
    assert_ok(sh_world_add_fem_body(world, &def, &body));
    assert_ok(sh_mesh_destroy(unit));
    assert_ok(sh_mesh_destroy(mesh));
    return body;
}

static double body_mass(const sh_world* world, sh_body_id body) {
    sh_body_info info;
    assert_ok(sh_body_get_info(world, body, &info));
    return info.total_mass;
}

/* An implicit body dropped on a very stiff plane at dt = 10 ms: the contact's stiffness is in
 * the implicit system, so every step is stable without sub-steps (its contact frequency is
 * ~1e4 times 1/dt), and at rest the plane carries exactly the weight. */
static void test_implicit_body_rests_on_stiff_plane(void** state) {
    (void)state;
    sh_world* world = sh_test_world(-9.81);
    sh_contact_params law;
    sh_contact_params_default(&law);
    law.stiffness = 1e9;
    law.exponent = 1.0;
    const sh_obstacle_id plane = floor_plane(world, &law);
    const sh_body_id cube = fem_cube(world, 0.02, 3, -0.01, -0.01, 0.001, 3e4, SH_INTEGRATOR_IMPLICIT_EULER);
    const double weight = body_mass(world, cube) * 9.81;
    sh_step_report report;
    for (int i = 0; i < 300; ++i) {
        assert_ok(sh_world_step(world, 0.01, &report));
        assert_int_equal(report.substeps, 1);
    }
    sh_contact_state contact;
    assert_ok(sh_obstacle_get_contact(world, plane, &contact));
    printf("implicit cube on a 1e9 N/m plane: reaction %.6g N, weight %.6g N, depth %.3g m, %d contacts\n",
           contact.force[2], weight, contact.max_depth, contact.contact_count);
    assert_close(-contact.force[2], weight, 1e-3);
    assert_true(contact.max_depth < 1e-9 * 4 /* weight / (stiffness * bottom nodes), order of */ + 1e-10);
    assert_true(fabs(contact.force[0]) < 1e-9 && fabs(contact.force[1]) < 1e-9);
    assert_ok(sh_world_destroy(world));
}

/* The same cube pressed by a sphere tool while resting on the plane, explicit: in equilibrium
 * (heavy mass damping) the plane carries the weight plus the tool's push, and the tool feels
 * the opposite of its push. */
static void test_tool_reaction_balances_the_plane(void** state) {
    (void)state;
    sh_world* world = sh_test_world(-9.81);
    sh_contact_params law;
    sh_contact_params_default(&law);
    law.stiffness = 1e5;
    const sh_obstacle_id plane = floor_plane(world, &law);
    const sh_body_id cube = fem_cube(world, 0.02, 4, -0.01, -0.01, 0.0, 3e4, SH_INTEGRATOR_IMPLICIT_EULER);
    const double weight = body_mass(world, cube) * 9.81;
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.radius = 0.005;
    def.position[2] = 0.02 + 0.005 + 1e-3;
    def.contact = law;
    sh_tool_id tool = 0;
    assert_ok(sh_tool_create(world, &def, &tool));
    const double q[4] = {1, 0, 0, 0};
    for (int i = 0; i < 400; ++i) {
        const double depth = fmin(1.0, i / 100.0) * 0.003; /* press 2 mm into the top */
        const double p[3] = {0.0, 0.0, 0.02 + 0.005 + 1e-3 - depth};
        assert_ok(sh_tool_set_pose(world, tool, p, q));
        assert_ok(sh_world_step(world, 0.005, NULL));
    }
    sh_contact_state on_tool, on_plane;
    assert_ok(sh_tool_get_contact(world, tool, &on_tool));
    assert_ok(sh_obstacle_get_contact(world, plane, &on_plane));
    double force[3], torque[3];
    assert_ok(sh_tool_get_wrench(world, tool, force, torque));
    printf("cube pressed by a sphere: tool %.6g N (%d contacts, depth %.3g mm), plane %.6g N, weight %.6g N\n",
           on_tool.force[2], on_tool.contact_count, 1e3 * on_tool.max_depth, on_plane.force[2], weight);
    assert_true(on_tool.force[2] > 0.01);  /* pushed up by the tissue */
    assert_true(on_tool.contact_count >= 4);
    assert_close(-on_plane.force[2], weight + on_tool.force[2], 2e-3);
    assert_close(force[2], on_tool.force[2], 0.0);
    /* A centred push on a symmetric cube: no sideways force, no torque about the centre. */
    assert_true(fabs(on_tool.force[0]) < 1e-3 * on_tool.force[2] && fabs(on_tool.force[1]) < 1e-3 * on_tool.force[2]);
    assert_true(fabs(torque[0]) < 1e-6 && fabs(torque[1]) < 1e-6 && fabs(torque[2]) < 1e-6);
    assert_ok(sh_world_destroy(world));
}

/* A 2 mm membrane clamped on its rim, hit by a sphere at 1 m/s and stepped at 1 kHz: the
 * sphere (radius 1.5 mm on 1 mm elements, aimed between nodes) moves 1 mm per step, more than
 * half its radius, yet stays on its side: the step is split so that no tool moves more than
 * half its radius at once, and the first touch, between nodes, is a triangle contact. */
static void test_fast_tool_does_not_pass_through_membrane(void** state) {
    (void)state;
    sh_world* world = sh_test_world(0.0);
    sh_mesh* unit = sh_test_box(0.02, 0.02, 0.002, 20, 20, 2);
    const double shift[3] = {-0.01, -0.01, -0.002};
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_transform(unit, 1.0, shift, &mesh));
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = SH_MATERIAL_NEOHOOKEAN;
    def.material.young = 3e4; /* soft tissue */
    def.material.poisson = 0.3;
    sh_body_id membrane = 0;
    assert_ok(sh_world_add_fem_body(world, &def, &membrane));
    const sh_mesh_info info = sh_test_mesh_info(mesh);
    double* x = malloc(3 * sizeof(double) * (size_t)info.node_count);
    int32_t* rim = malloc(sizeof(int32_t) * (size_t)info.node_count);
    assert_ok(sh_mesh_get_nodes(mesh, x, 3 * (int64_t)info.node_count));
    int32_t rim_count = 0;
    for (int32_t i = 0; i < info.node_count; ++i)
        if (fabs(fabs(x[3 * i]) - 0.01) < 1e-9 || fabs(fabs(x[3 * i + 1]) - 0.01) < 1e-9) rim[rim_count++] = i;
    assert_ok(sh_body_fix_nodes(world, membrane, rim, rim_count));

    sh_collider_def tool_def;
    sh_collider_def_default(&tool_def);
    const double radius = 0.0015;
    tool_def.shape.radius = radius;
    tool_def.contact.stiffness = 1e5;
    const double cx = 0.0003, cy = 0.0006; /* inside a surface triangle, away from its nodes */
    tool_def.position[0] = cx;
    tool_def.position[1] = cy;
    tool_def.position[2] = 0.003 + radius;
    sh_tool_id tool = 0;
    assert_ok(sh_tool_create(world, &tool_def, &tool));
    const double q[4] = {1, 0, 0, 0};
    double peak = 0.0;
    int face_contact_steps = 0;
    for (int i = 1; i <= 10; ++i) { /* 1 m/s, 1 kHz: from 3 mm above the top to 7 mm below */
        const double p[3] = {cx, cy, 0.003 + radius - 0.001 * i};
        assert_ok(sh_tool_set_pose(world, tool, p, q));
        sh_step_report report;
        assert_ok(sh_world_step(world, 1e-3, &report));
        assert_true(report.contact_substeps >= 2);
        sh_contact_state contact;
        assert_ok(sh_tool_get_contact(world, tool, &contact));
        peak = fmax(peak, contact.force[2]);
        if (contact.contact_count > 0 && contact.penetration_volume == 0.0) ++face_contact_steps;
        /* No node of the membrane under the sphere (inside 0.8 of its radius, so away from
         * its equator, where the membrane may wrap up to the centre's height) is above its
         * centre: none came through; and none is deeper in it than half its radius. */
        assert_ok(sh_body_get_positions(world, membrane, x, 3 * (int64_t)info.node_count));
        for (int32_t k = 0; k < info.node_count; ++k) {
            const double dx = x[3 * k] - cx, dy = x[3 * k + 1] - cy, dz = x[3 * k + 2] - p[2];
            if (dx * dx + dy * dy < 0.64 * radius * radius) assert_true(dz < 0.0);
            assert_true(sqrt(dx * dx + dy * dy + dz * dz) > 0.5 * radius);
        }
        printf("step %d: tool z %.1f mm, force %.4g N, %d contacts, depth %.3g mm, %d sub-steps\n", i, 1e3 * p[2],
               contact.force[2], contact.contact_count, 1e3 * contact.max_depth, report.contact_substeps);
    }
    assert_true(peak > 0.0);
    assert_true(face_contact_steps >= 1); /* the first touch is between nodes */
    free(x);
    free(rim);
    assert_ok(sh_mesh_destroy(unit));
    assert_ok(sh_mesh_destroy(mesh));
    assert_ok(sh_world_destroy(world));
}

/* ---- Degenerate inputs and capacity -------------------------------------------------------- */

static sh_status try_tool(sh_world* world, const sh_collider_def* def) {
    sh_tool_id id = 0;
    return sh_tool_create(world, def, &id);
}

static void test_invalid_shapes_are_rejected(void** state) {
    (void)state;
    sh_world* world = sh_test_world(-9.81);
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.radius = 0.0;
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(sh_last_error_message(), "radius"));
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_BOX;
    def.shape.half_extents[0] = def.shape.half_extents[1] = 0.01;
    def.shape.half_extents[2] = 0.0;
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(sh_last_error_message(), "half_extents"));
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_PLANE;
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
    sh_collider_def_default(&def);
    def.position[1] = NAN;
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_CONVEX;
    const double same[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}; /* coincident points */
    const double flat[12] = {0, 0, 0, 1e-2, 0, 0, 0, 1e-2, 0, 1e-2, 1e-2, 0}; /* one plane */
    def.shape.points = same;
    def.shape.point_count = 4;
#ifdef SOFTHAP_TEST_WITH_CCD
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
    def.shape.points = flat;
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
    def.shape.point_count = 3;
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
#else
    (void)flat;
    assert_status(try_tool(world, &def), SH_ERR_UNSUPPORTED);
#endif
    sh_contact_params law;
    sh_contact_params_default(&law);
    sh_collider_def_default(&def);
    def.contact.exponent = 0.5;
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(sh_last_error_message(), "exponent"));
    sh_collider_def_default(&def);
    def.contact.static_friction = 0.1;
    def.contact.dynamic_friction = 0.2;
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
    sh_collider_def_default(&def);
    def.contact.capacity = 0;
    assert_status(try_tool(world, &def), SH_ERR_INVALID_ARGUMENT);
    assert_ok(sh_world_destroy(world));
}

/* A particle exactly at a sphere tool's centre, on a box obstacle's face and a box exactly
 * touching a body's face: finite forces, no NaN, zero force at zero depth. A NaN pose is
 * refused and the tool keeps working; a destroyed tool's id is stale. */
static void test_degenerate_contacts_stay_finite(void** state) {
    (void)state;
    sh_world* world = sh_test_world(0.0);
    const sh_body_id p = particle(world, 1e-3, 0.0, 0.0, SH_INTEGRATOR_SYMPLECTIC_EULER);
    sh_collider_def def;
    sh_collider_def_default(&def); /* sphere at the origin: the particle is at its centre */
    sh_tool_id tool = 0;
    assert_ok(sh_tool_create(world, &def, &tool));
    assert_ok(sh_world_step(world, 1e-5, NULL));
    double x[3], v[3];
    assert_ok(sh_body_get_positions(world, p, x, 3));
    assert_ok(sh_body_get_velocities(world, p, v, 3));
    for (int k = 0; k < 3; ++k) assert_true(isfinite(x[k]) && isfinite(v[k]));
    sh_contact_state contact;
    assert_ok(sh_tool_get_contact(world, tool, &contact));
    assert_int_equal(contact.contact_count, 1);
    assert_close(contact.max_depth, def.shape.radius, 0.01);

    const double bad[3] = {0.0, NAN, 0.0}, q[4] = {1, 0, 0, 0}, zero_q[4] = {0, 0, 0, 0}, far[3] = {1, 1, 1};
    assert_status(sh_tool_set_pose(world, tool, bad, q), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_tool_set_pose(world, tool, far, zero_q), SH_ERR_INVALID_ARGUMENT);
    assert_ok(sh_tool_set_pose(world, tool, far, q));
    assert_ok(sh_world_step(world, 1e-5, NULL));
    assert_ok(sh_tool_get_contact(world, tool, &contact));
    assert_int_equal(contact.contact_count, 0);
    assert_true(contact.force[0] == 0.0 && contact.force[1] == 0.0 && contact.force[2] == 0.0);
    assert_ok(sh_tool_destroy(world, tool));
    assert_int_equal(sh_tool_is_valid(world, tool), 0);
    assert_status(sh_tool_set_pose(world, tool, far, q), SH_ERR_INVALID_HANDLE);
    assert_status(sh_tool_destroy(world, tool), SH_ERR_INVALID_HANDLE);
    assert_status(sh_obstacle_destroy(world, tool), SH_ERR_INVALID_HANDLE);

    assert_ok(sh_world_destroy(world));

    /* A box obstacle whose top face is exactly a cube's bottom face. */
    world = sh_test_world(0.0);
    const sh_body_id cube = fem_cube(world, 0.01, 2, -0.005, -0.005, 0.0, 3e4, SH_INTEGRATOR_SYMPLECTIC_EULER);
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_BOX;
    def.shape.half_extents[0] = def.shape.half_extents[1] = def.shape.half_extents[2] = 0.005;
    def.position[2] = -0.005;
    sh_obstacle_id box = 0;
    assert_ok(sh_obstacle_create(world, &def, &box));
    assert_ok(sh_world_step(world, 1e-5, NULL));
    assert_ok(sh_obstacle_get_contact(world, box, &contact));
    /* Zero depth up to the round-off of the box's frame (1e-23 m here): a force of that order. */
    assert_true(fabs(contact.force[2]) < 1e-20 && contact.max_depth < 1e-20);
    double* y = malloc(3 * sizeof(double) * 27);
    assert_ok(sh_body_get_positions(world, cube, y, 81));
    for (int k = 0; k < 81; ++k) assert_true(isfinite(y[k]));
    free(y);
    assert_ok(sh_world_destroy(world));
}

/* A flat box pressed into a cube's top with room for 5 contacts: 5 act, the deepest ones,
 * and SH_WARN_CAPACITY is counted. */
static void test_contact_capacity_keeps_the_deepest(void** state) {
    (void)state;
    double depth[2];
    int32_t count[2];
    uint64_t warnings[2][SH_WARN_COUNT];
    for (int run = 0; run < 2; ++run) {
        sh_world* world = sh_test_world(0.0);
        const sh_body_id cube = fem_cube(world, 0.01, 4, -0.005, -0.005, -0.01, 3e4, SH_INTEGRATOR_SYMPLECTIC_EULER);
        (void)cube;
        sh_collider_def def;
        sh_collider_def_default(&def);
        def.shape.kind = SH_SHAPE_BOX;
        def.shape.half_extents[0] = def.shape.half_extents[1] = 0.02;
        def.shape.half_extents[2] = 0.005;
        /* Tilted about x so that the nodes' depths differ. */
        def.orientation[0] = cos(0.05);
        def.orientation[1] = sin(0.05);
        def.position[2] = 0.005 - 0.0002;
        def.contact.capacity = run == 0 ? 5 : 4096;
        sh_tool_id tool = 0;
        assert_ok(sh_tool_create(world, &def, &tool));
        sh_step_report report;
        assert_ok(sh_world_step(world, 1e-6, &report));
        sh_contact_state contact;
        assert_ok(sh_tool_get_contact(world, tool, &contact));
        depth[run] = contact.max_depth;
        count[run] = contact.contact_count;
        assert_ok(sh_world_get_warnings(world, warnings[run]));
        assert_ok(sh_world_destroy(world));
    }
    printf("capacity 5: %d contacts, deepest %.4g mm; unlimited: %d contacts, deepest %.4g mm\n", count[0], 1e3 * depth[0],
           count[1], 1e3 * depth[1]);
    assert_int_equal(count[0], 5);
    assert_true(count[1] > 5);
    assert_close(depth[0], depth[1], 1e-9);
    assert_int_equal(warnings[0][SH_WARN_CAPACITY], 1);
    assert_int_equal(warnings[1][SH_WARN_CAPACITY], 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_impact_restitution_matches_hunt_crossley),
        cmocka_unit_test(test_implicit_body_rests_on_stiff_plane),
        cmocka_unit_test(test_tool_reaction_balances_the_plane),
        cmocka_unit_test(test_fast_tool_does_not_pass_through_membrane),
        cmocka_unit_test(test_invalid_shapes_are_rejected),
        cmocka_unit_test(test_degenerate_contacts_stay_finite),
        cmocka_unit_test(test_contact_capacity_keeps_the_deepest),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
