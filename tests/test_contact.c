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
    sh_body_id body = SH_NULL_ID;
    assert_ok(sh_spring_body_create(world, &def, &body));
    const double velocity[3] = {0.0, 0.0, -v};
    assert_ok(sh_body_set_velocities(world, body, velocity, 1));
    return body;
}

static sh_obstacle_id floor_plane(sh_world* world, const sh_contact_params* law) {
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_PLANE;
    def.contact = *law;
    sh_obstacle_id id = SH_NULL_ID;
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
        assert_ok(sh_body_get_positions(world, body, x, 1));
        assert_ok(sh_body_get_velocities(world, body, v, 1));
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
    sh_body_id body = SH_NULL_ID;
    assert_ok(sh_fem_body_create(world, &def, &body));
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
 * the opposite of its push. The sphere (radius 8 mm) presses the top's middle node and the
 * faces around it: their excess terms hold it centred (a push on the middle node alone would
 * be an unstable balance on the frictionless plane: its push on a node off its apex has a
 * sideways part that nothing holds). */
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
    def.shape.radius = 0.008;
    def.position[2] = 0.02 + 0.008 + 1e-3;
    def.contact = law;
    sh_tool_id tool = SH_NULL_ID;
    assert_ok(sh_tool_create(world, &def, &tool));
    const double q[4] = {1, 0, 0, 0};
    for (int i = 0; i < 400; ++i) {
        const double depth = fmin(1.0, i / 100.0) * 0.003; /* press 2 mm into the top */
        const double p[3] = {0.0, 0.0, 0.02 + 0.008 + 1e-3 - depth};
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
    assert_true(on_tool.contact_count >= 1);
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
    sh_body_id membrane = SH_NULL_ID;
    assert_ok(sh_fem_body_create(world, &def, &membrane));
    const sh_mesh_info info = sh_test_mesh_info(mesh);
    double* x = malloc(3 * sizeof(double) * (size_t)info.node_count);
    int32_t* rim = malloc(sizeof(int32_t) * (size_t)info.node_count);
    assert_ok(sh_mesh_get_nodes(mesh, x, info.node_count));
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
    sh_tool_id tool = SH_NULL_ID;
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
        assert_ok(sh_body_get_positions(world, membrane, x, info.node_count));
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

/* ---- Coulomb friction on an inclined plane ---------------------------------------------------- */

/* A cube of side a (2 cells per side) resting with its bottom face on the plane through the
 * origin whose outward normal is n = (-sin t, 0, cos t): the box [-a/2, a/2]^2 x [0, a] turned
 * by t about y, so that its local x runs up the slope along d = (cos t, 0, sin t). Gravity is
 * -z, so the slope pulls the cube down along -d with g sin t and presses it with g cos t. */
typedef struct incline {
    sh_world* world;
    sh_body_id body;
    int32_t node_count;
    double* masses;
    double total_mass;
    double theta, up[3];
} incline;

static incline incline_create(double theta, const sh_contact_params* law, sh_integrator integrator) {
    incline s;
    s.theta = theta;
    s.up[0] = cos(theta);
    s.up[1] = 0.0;
    s.up[2] = sin(theta);
    s.world = sh_test_world(-9.81);
    const double a = 0.02;
    double* nodes = NULL;
    int32_t* tets = NULL;
    int32_t tet_count = 0;
    sh_test_box_arrays(a, a, a, 2, 2, 2, &nodes, &s.node_count, &tets, &tet_count);
    assert_non_null(nodes);
    assert_non_null(tets);
    for (int32_t i = 0; i < s.node_count; ++i) {
        const double x = nodes[3 * i] - 0.5 * a, y = nodes[3 * i + 1] - 0.5 * a, z = nodes[3 * i + 2];
        nodes[3 * i] = cos(theta) * x - sin(theta) * z; /* x along d, z along n */
        nodes[3 * i + 1] = y;
        nodes[3 * i + 2] = sin(theta) * x + cos(theta) * z;
    }
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_create(nodes, s.node_count, tets, tet_count, &mesh));
    free(nodes);
    free(tets);
    sh_collider_def plane;
    sh_collider_def_default(&plane);
    plane.shape.kind = SH_SHAPE_PLANE;
    plane.shape.normal[0] = -sin(theta);
    plane.shape.normal[1] = 0.0;
    plane.shape.normal[2] = cos(theta);
    plane.contact = *law;
    sh_obstacle_id obstacle = SH_NULL_ID;
    assert_ok(sh_obstacle_create(s.world, &plane, &obstacle));
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = SH_MATERIAL_COROTATIONAL;
    def.material.young = 3e4;
    def.material.poisson = 0.3;
    def.integrator = integrator;
    /* Explicit: a little stiffness damping, which leaves rigid motion alone, keeps the cube's
     * own vibration from making its corners chatter on the plane. */
    if (integrator != SH_INTEGRATOR_IMPLICIT_EULER) def.damping_stiffness = 1e-3;
    assert_ok(sh_fem_body_create(s.world, &def, &s.body));
    assert_ok(sh_mesh_destroy(mesh));
    s.masses = malloc(sizeof(double) * (size_t)s.node_count);
    assert_ok(sh_body_get_masses(s.world, s.body, s.masses, s.node_count));
    s.total_mass = 0.0;
    for (int32_t i = 0; i < s.node_count; ++i) s.total_mass += s.masses[i];
    return s;
}

/* Centre of mass position and velocity along the slope's up direction d. */
static void incline_centre(const incline* s, double* position, double* velocity) {
    double* x = malloc(3 * sizeof(double) * (size_t)s->node_count);
    double* v = malloc(3 * sizeof(double) * (size_t)s->node_count);
    assert_ok(sh_body_get_positions(s->world, s->body, x, s->node_count));
    assert_ok(sh_body_get_velocities(s->world, s->body, v, s->node_count));
    *position = *velocity = 0.0;
    for (int32_t i = 0; i < s->node_count; ++i)
        for (int k = 0; k < 3; ++k) {
            *position += s->masses[i] * x[3 * i + k] * s->up[k] / s->total_mass;
            *velocity += s->masses[i] * v[3 * i + k] * s->up[k] / s->total_mass;
        }
    free(x);
    free(v);
}

/* Steps the cube for `seconds` at dt, every step asserted to succeed (an implicit body's
 * Newton iteration converged); returns the most Newton iterations any step took. */
static int32_t incline_run(incline* s, double dt, double seconds) {
    int32_t most = 0;
    const int steps = (int)lround(seconds / dt);
    for (int i = 0; i < steps; ++i) {
        sh_step_report report;
        assert_ok(sh_world_step(s->world, dt, &report));
        if (report.newton_iterations > most) most = report.newton_iterations;
    }
    return most;
}

static void incline_destroy(incline* s) {
    free(s->masses);
    assert_ok(sh_world_destroy(s->world));
}

static sh_contact_params incline_law(double mu_s, double mu_d) {
    sh_contact_params law;
    sh_contact_params_default(&law);
    law.stiffness = 1e5;
    law.static_friction = mu_s;
    law.dynamic_friction = mu_d;
    return law;
}

/* With mu_s > tan t the cube sticks. The regularised law makes sticking viscous, F =
 * mu_s fn v / s0 on each contact, so the cube creeps at the speed where the friction carries
 * the slope's pull: sum mu_s fn v / s0 = M g sin t with sum fn = M g cos t gives
 * v_creep = s0 tan t / mu_s (0.728 mm/s here), whatever the time step, for implicit Euler and
 * for symplectic Euler (whose friction is taken implicitly on the new velocities, so that no
 * node creeps at its load times the step over its own mass, as with a capped explicit
 * friction). Checked: the creep speed after 1 s and the distance crept over the last 0.5 s,
 * both to 2 %; and that the whole first second, landing included (the cube starts touching
 * the plane at zero depth: its first step has no friction, and its normal force rings for a
 * while), moves it less than 2 s0 x 1 s, where sliding would take it about 1 m. Every
 * implicit step converges (assert_ok). */
static void check_sticking(sh_integrator integrator, double dt) {
    const double theta = 20.0 * 3.14159265358979323846 / 180.0, mu = 0.5, seconds = 1.0;
    const sh_contact_params law = incline_law(mu, mu);
    incline s = incline_create(theta, &law, integrator);
    double x0, v0, x_half, v_half, x1, v1;
    incline_centre(&s, &x0, &v0);
    const int32_t most = incline_run(&s, dt, 0.5 * seconds);
    incline_centre(&s, &x_half, &v_half);
    const int32_t later = incline_run(&s, dt, 0.5 * seconds);
    incline_centre(&s, &x1, &v1);
    const double creep = law.slip_velocity * tan(theta) / mu;
    printf("%s, dt %g s: sticks, creep %.4f mm/s (s0 tan t / mu_s = %.4f), %.4f mm in the last 0.5 s (%.4f), %.4f mm "
           "in 1 s (bound 2 s0 x 1 s = %.4f); most Newton iterations %d\n",
           integrator == SH_INTEGRATOR_IMPLICIT_EULER ? "implicit Euler" : "symplectic Euler", dt, -1e3 * v1, 1e3 * creep,
           -1e3 * (x1 - x_half), 1e3 * 0.5 * seconds * creep, -1e3 * (x1 - x0), 2e3 * law.slip_velocity * seconds,
           most > later ? most : later);
    assert_true(fabs(-v1 - creep) <= 0.02 * creep);
    assert_true(fabs(-(x1 - x_half) - 0.5 * seconds * creep) <= 0.02 * 0.5 * seconds * creep);
    assert_true(-(x1 - x0) >= 0.0 && -(x1 - x0) <= 2.0 * law.slip_velocity * seconds);
    incline_destroy(&s);
}

/* With mu_d < tan t (and mu_s only a little above mu_d) the cube slides down with
 * a = g (sin t - mu_d cos t): Coulomb's law, once the regularisation's extra
 * (mu_s - mu_d) fn s0 / |v| has faded (below 1e-4 of the friction at the speeds measured).
 * The centre of mass moves only under gravity and the plane, so its velocity change over
 * [0.5 s, 1 s] is the acceleration's, free of the cube's own vibration. */
static void check_sliding(sh_integrator integrator, double dt) {
    const double theta = 20.0 * 3.14159265358979323846 / 180.0, mu_s = 0.2, mu_d = 0.15, g = 9.81;
    const sh_contact_params law = incline_law(mu_s, mu_d);
    incline s = incline_create(theta, &law, integrator);
    double x_half, v_half, x1, v1;
    const int32_t most = incline_run(&s, dt, 0.5);
    incline_centre(&s, &x_half, &v_half);
    const int32_t later = incline_run(&s, dt, 0.5);
    incline_centre(&s, &x1, &v1);
    const double expected = g * (sin(theta) - mu_d * cos(theta));
    const double measured = -(v1 - v_half) / 0.5;
    printf("%s, dt %g s: slides, a %.4f m/s^2 (g (sin t - mu_d cos t) = %.4f); most Newton iterations %d\n",
           integrator == SH_INTEGRATOR_IMPLICIT_EULER ? "implicit Euler" : "symplectic Euler", dt, measured, expected,
           most > later ? most : later);
    assert_true(fabs(measured - expected) <= 0.02 * expected);
    incline_destroy(&s);
}

static void test_implicit_block_sticks_on_a_slope(void** state) {
    (void)state;
    check_sticking(SH_INTEGRATOR_IMPLICIT_EULER, 1e-3);
    check_sticking(SH_INTEGRATOR_IMPLICIT_EULER, 1e-2);
}

static void test_implicit_block_slides_down_a_slope(void** state) {
    (void)state;
    check_sliding(SH_INTEGRATOR_IMPLICIT_EULER, 1e-3);
    check_sliding(SH_INTEGRATOR_IMPLICIT_EULER, 1e-2);
}

static void test_explicit_block_sticks_on_a_slope(void** state) {
    (void)state;
    check_sticking(SH_INTEGRATOR_SYMPLECTIC_EULER, 1e-3);
}

static void test_explicit_block_slides_down_a_slope(void** state) {
    (void)state;
    check_sliding(SH_INTEGRATOR_SYMPLECTIC_EULER, 1e-3);
}

/* ---- A sphere on a convex edge of a coarse mesh ---------------------------------------------- */

/* A box 20 x 20 x 10 mm of 4 x 2 x 2 cells (5 x 10 x 5 mm) on fixed bottom nodes, and a sphere
 * of radius 6 mm (more than the cells) against its top edge x = 20 mm, z = 10 mm, centred over
 * y = 5 mm, halfway between the edge's nodes: no node under it, so only the triangles (faces
 * and the edge between them) can hold it. */
#define EDGE_BOX_X 0.02
#define EDGE_BOX_Z 0.01
#define EDGE_RADIUS 0.006

static sh_body_id edge_box(sh_world* world, double young, sh_integrator integrator, int32_t* node_count) {
    double* nodes = NULL;
    int32_t* tets = NULL;
    int32_t tet_count = 0;
    sh_test_box_arrays(EDGE_BOX_X, 0.02, EDGE_BOX_Z, 4, 2, 2, &nodes, node_count, &tets, &tet_count);
    assert_non_null(nodes);
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_create(nodes, *node_count, tets, tet_count, &mesh));
    sh_fem_body_def def;
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = SH_MATERIAL_COROTATIONAL;
    def.material.young = young;
    def.material.poisson = 0.3;
    def.integrator = integrator;
    def.damping_mass = 50.0;
    sh_body_id body = SH_NULL_ID;
    assert_ok(sh_fem_body_create(world, &def, &body));
    int32_t* bottom = malloc(sizeof(int32_t) * (size_t)*node_count);
    const int count = sh_test_nodes_at(nodes, *node_count, 2, 0.0, bottom);
    assert_ok(sh_body_fix_nodes(world, body, bottom, count));
    free(bottom);
    free(nodes);
    free(tets);
    assert_ok(sh_mesh_destroy(mesh));
    return body;
}

/* The sphere's centre at distance EDGE_RADIUS - depth from the point p along the unit u. */
static void edge_tool_centre(const double p[3], const double u[3], double depth, double out[3]) {
    for (int k = 0; k < 3; ++k) out[k] = p[k] + (EDGE_RADIUS - depth) * u[k];
}

/* A stiff box (1 GPa) and a sphere held d = 0.5 mm into it, solved to static equilibrium,
 * once on the edge along its bisector u = (1, 0, 1) / sqrt 2 and once on the top face's middle
 * along z. Either way one contact (no node is inside the sphere) must carry the tool with the
 * Hunt-Crossley force lambda d^n along u: the body's give under ~1 N is below 1 um (its
 * stiffness under a point load is at least E times the 5 mm cell, 5e6 N/m), which changes
 * the depth, so the force, by under 0.1 % and turns the direction by under 1e-4 rad. Before
 * edges were contacts, the sphere on the edge reached through neither face over the face and
 * got no support at all. */
static void test_sphere_on_a_convex_edge_is_supported(void** state) {
    (void)state;
    const double depth = 5e-4, s = sqrt(0.5);
    sh_contact_params law;
    sh_contact_params_default(&law);
    law.stiffness = 1e5;
    law.exponent = 1.5;
    law.damping = 0.0;
    const double expected = law.stiffness * pow(depth, law.exponent);
    const double edge_point[3] = {EDGE_BOX_X, 0.005, EDGE_BOX_Z}, bisector[3] = {s, 0.0, s};
    const double face_point[3] = {0.0125, 0.0025, EDGE_BOX_Z}, up[3] = {0.0, 0.0, 1.0};
    const double* points[2] = {edge_point, face_point};
    const double* directions[2] = {bisector, up};
    double magnitude[2];
    for (int run = 0; run < 2; ++run) {
        sh_world* world = sh_test_world(0.0);
        int32_t node_count = 0;
        edge_box(world, 1e9, SH_INTEGRATOR_IMPLICIT_EULER, &node_count);
        sh_collider_def def;
        sh_collider_def_default(&def);
        def.shape.radius = EDGE_RADIUS;
        def.contact = law;
        edge_tool_centre(points[run], directions[run], depth, def.position);
        sh_tool_id tool = SH_NULL_ID;
        assert_ok(sh_tool_create(world, &def, &tool));
        sh_static_def statics;
        sh_static_def_default(&statics);
        assert_ok(sh_world_solve_static(world, &statics, NULL));
        sh_contact_state contact;
        assert_ok(sh_tool_get_contact(world, tool, &contact));
        const double* f = contact.force;
        magnitude[run] = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        const double along = (f[0] * directions[run][0] + f[1] * directions[run][1] + f[2] * directions[run][2]);
        const double angle = acos(fmin(1.0, along / magnitude[run]));
        printf("sphere %.1f mm into the %s: reaction (%.5f, %.5f, %.5f) N, |F| %.5f N (lambda d^n = %.5f), %.2e rad off "
               "its normal, %d contact(s), depth %.4f mm\n",
               1e3 * depth, run == 0 ? "edge" : "face", f[0], f[1], f[2], magnitude[run], expected, angle,
               contact.contact_count, 1e3 * contact.max_depth);
        assert_int_equal(contact.contact_count, 1);
        assert_true(fabs(magnitude[run] - expected) <= 1e-3 * expected);
        assert_true(angle <= 1e-4);
        assert_ok(sh_world_destroy(world));
    }
    assert_true(fabs(magnitude[0] - magnitude[1]) <= 1e-3 * magnitude[1]);
}

/* A soft box (30 kPa) and the sphere driven half its radius into the edge along the bisector
 * in 0.2 s, symplectic Euler at 2 ms: the edge gives way and holds it. Nothing passes through: every
 * node stays outside the sphere but for the edge region's give (none deeper than the half
 * radius it was pushed), the edge's middle stays in front of the sphere's centre along the
 * bisector, and the tool is pushed back out along it (its reaction's component along the
 * bisector is most of it, and half as large again at r / 2 in as at r / 4 in). */
static void test_sphere_pushed_into_an_edge_does_not_pass_through(void** state) {
    (void)state;
    const double s = sqrt(0.5), bisector[3] = {s, 0.0, s}, edge_point[3] = {EDGE_BOX_X, 0.005, EDGE_BOX_Z};
    sh_world* world = sh_test_world(0.0);
    int32_t node_count = 0;
    const sh_body_id box = edge_box(world, 3e4, SH_INTEGRATOR_SYMPLECTIC_EULER, &node_count);
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.radius = EDGE_RADIUS;
    def.contact.stiffness = 1e5;
    edge_tool_centre(edge_point, bisector, -1e-3, def.position); /* 1 mm clear of the edge */
    sh_tool_id tool = SH_NULL_ID;
    assert_ok(sh_tool_create(world, &def, &tool));
    const double q[4] = {1, 0, 0, 0};
    double* x = malloc(3 * sizeof(double) * (size_t)node_count);
    double quarter = 0.0, last = 0.0;  /* the push along the bisector at r / 4 in and at the end */
    const int steps = 100;
    for (int i = 1; i <= steps; ++i) {
        const double depth = -1e-3 + (1e-3 + 0.5 * EDGE_RADIUS) * i / steps;
        double centre[3];
        edge_tool_centre(edge_point, bisector, depth, centre);
        assert_ok(sh_tool_set_pose(world, tool, centre, q));
        assert_ok(sh_world_step(world, 2e-3, NULL));
        sh_contact_state contact;
        assert_ok(sh_tool_get_contact(world, tool, &contact));
        const double* f = contact.force;
        const double along = f[0] * bisector[0] + f[1] * bisector[1] + f[2] * bisector[2];
        const double magnitude = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        assert_ok(sh_body_get_positions(world, box, x, node_count));
        double edge_mid[3] = {0.0, 0.0, 0.0}, deepest = 0.0;
        for (int32_t k = 0; k < node_count; ++k) {
            const double d[3] = {x[3 * k] - centre[0], x[3 * k + 1] - centre[1], x[3 * k + 2] - centre[2]};
            deepest = fmax(deepest, EDGE_RADIUS - sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
        }
        /* The edge's nodes at y = 0 and 10 mm (grid nodes (4, 0, 2) and (4, 1, 2)). */
        const int32_t e0 = (2 * 3 + 0) * 5 + 4, e1 = (2 * 3 + 1) * 5 + 4;
        for (int k = 0; k < 3; ++k) edge_mid[k] = 0.5 * (x[3 * e0 + k] + x[3 * e1 + k]) - centre[k];
        const double ahead = -(edge_mid[0] * bisector[0] + edge_mid[1] * bisector[1] + edge_mid[2] * bisector[2]);
        if (i % 20 == 0)
            printf("sphere %.2f mm into the edge: reaction %.4f N, %.4f N of it along the bisector, edge middle %.3f mm "
                   "in front of the centre, deepest node %.3f mm in\n",
                   1e3 * depth, magnitude, along, 1e3 * ahead, 1e3 * deepest);
        assert_true(ahead > 0.0);
        assert_true(deepest < 0.5 * EDGE_RADIUS);
        if (depth > 0.25 * EDGE_RADIUS) {
            assert_true(along > 0.9 * magnitude);
            if (quarter == 0.0) quarter = along;
            last = along;
        }
    }
    assert_true(quarter > 0.0 && last > 1.5 * quarter); /* deeper, pushed back harder */
    free(x);
    assert_ok(sh_world_destroy(world));
}

/* ---- Degenerate inputs and capacity -------------------------------------------------------- */

static sh_status try_tool(sh_world* world, const sh_collider_def* def) {
    sh_tool_id id = SH_NULL_ID;
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
    sh_tool_id tool = SH_NULL_ID;
    assert_ok(sh_tool_create(world, &def, &tool));
    assert_ok(sh_world_step(world, 1e-5, NULL));
    double x[3], v[3];
    assert_ok(sh_body_get_positions(world, p, x, 1));
    assert_ok(sh_body_get_velocities(world, p, v, 1));
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
    assert_status(sh_obstacle_destroy(world, (sh_obstacle_id){tool.value}), SH_ERR_INVALID_HANDLE);

    assert_ok(sh_world_destroy(world));

    /* A box obstacle whose top face is exactly a cube's bottom face. */
    world = sh_test_world(0.0);
    const sh_body_id cube = fem_cube(world, 0.01, 2, -0.005, -0.005, 0.0, 3e4, SH_INTEGRATOR_SYMPLECTIC_EULER);
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_BOX;
    def.shape.half_extents[0] = def.shape.half_extents[1] = def.shape.half_extents[2] = 0.005;
    def.position[2] = -0.005;
    sh_obstacle_id box = SH_NULL_ID;
    assert_ok(sh_obstacle_create(world, &def, &box));
    assert_ok(sh_world_step(world, 1e-5, NULL));
    assert_ok(sh_obstacle_get_contact(world, box, &contact));
    /* Zero depth up to the round-off of the box's frame (1e-23 m here): a force of that order. */
    assert_true(fabs(contact.force[2]) < 1e-20 && contact.max_depth < 1e-20);
    double* y = malloc(3 * sizeof(double) * 27);
    assert_ok(sh_body_get_positions(world, cube, y, 27));
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
        sh_tool_id tool = SH_NULL_ID;
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
        cmocka_unit_test(test_implicit_block_sticks_on_a_slope),
        cmocka_unit_test(test_implicit_block_slides_down_a_slope),
        cmocka_unit_test(test_explicit_block_sticks_on_a_slope),
        cmocka_unit_test(test_explicit_block_slides_down_a_slope),
        cmocka_unit_test(test_sphere_on_a_convex_edge_is_supported),
        cmocka_unit_test(test_sphere_pushed_into_an_edge_does_not_pass_through),
        cmocka_unit_test(test_invalid_shapes_are_rejected),
        cmocka_unit_test(test_degenerate_contacts_stay_finite),
        cmocka_unit_test(test_contact_capacity_keeps_the_deepest),
    };
    sh_test_skip_from_environment();
    return cmocka_run_group_tests(tests, NULL, NULL);
}
