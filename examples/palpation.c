/* palpation.c: a sphere tool presses into a liver lying on a table, slides across its top and
 * lifts off; the tool's reaction force is printed as CSV every 10 ms.
 *
 *   palpation [mesh [symplectic|implicit]]   (defaults: ../shared/meshes/liver.msh, symplectic)
 *
 * `make palpation` runs it from the repository root (about 5 s on one core).
 *
 * The scene. SOFA's haptic-demo liver (181 nodes, 596 tets, 276 surface triangles; its numbers
 * are centimetre-scale, about 6.5 units across) is turned so that its flattest side (the file's
 * +y side) faces down, scaled with sh_mesh_transform so that its largest extent is 16 cm (an
 * adult liver's width: 16.0 x 10.9 x 12.2 cm, 550 g) and set on a table, a plane obstacle at
 * z = 0, under gravity (-9.81 m/s^2 along z). The tissue is corotational, E = 15 kPa,
 * nu = 0.45 (the largest value that does not raise SH_WARN_LOCKING on linear tets),
 * rho = 1000 kg/m^3, with a little mass damping (2 /s).
 *
 * Settling. sh_world_solve_static cannot do it: it refuses a body without fixed nodes
 * (SH_ERR_SOLVER) even when an obstacle holds it up. So the liver settles dynamically for
 * kSettleTime, with heavy per-node damping (about critical for its sag mode) on a frictionless
 * table, so that its base can spread to equilibrium (it sags about 1.5 cm); then the damping is
 * cleared and the table replaced by one with friction (mu_s = 0.6, mu_d = 0.5).
 *
 * The palpation. A sphere tool of radius 1 cm with Coulomb friction (mu_s = 0.3, mu_d = 0.2)
 * follows a scripted trajectory (t from the start of the approach):
 *
 *   approach  0.0 - 0.5 s   from 1 cm above the point where it would touch the settled
 *                           surface down to that point
 *   press     0.5 - 1.5 s   1.2 cm further down at constant speed
 *   hold      1.5 - 1.7 s
 *   slide     1.7 - 3.2 s   3 cm sideways at constant speed, 1.2 cm below the height where
 *                           the tool would touch the settled surface (so it follows the top)
 *   hold      3.2 - 3.4 s
 *   lift      3.4 - 3.9 s   back up to 1 cm above the touching height
 *   rest      3.9 - 4.2 s
 *
 * This liver's surface is coarse (facets 2-3 cm across, meeting at edges of 15-50 degrees), and
 * a sphere straddling a convex edge between two facets gets little support from it: a tool's
 * contact with a surface triangle only counts where the sphere's deepest point projects inside
 * that triangle, and the edge's nodes may lie outside the sphere. So the press starts at the
 * centre of the largest nearly level facet of the top (over at least 3 cm of tissue), and the
 * slide takes the direction, of eight, along which the facets under the tool turn least from
 * that one.
 *
 * Integrators. "symplectic" (the default): symplectic Euler at a host step of 0.1 ms, about the
 * critical explicit step. The step is this short for the friction's sake: in an explicit step
 * the library caps each contact's viscous friction coefficient at (touched mass) / (host step),
 * so at a 1 ms step sticking on the table is too weak to hold the liver (it creeps away from
 * the tool at about a centimetre per second) and the tool's friction is mostly cut off.
 * "implicit": backward Euler at a 10 ms step. With contact it iterates Newton; with friction on
 * the table it currently does not converge (SH_ERR_NOT_CONVERGED, the body is left unchanged),
 * so this example then stops with that error.
 *
 * Output. stdout: CSV with the header
 *   t,tool_x,tool_y,tool_z,force_x,force_y,force_z,contacts,max_depth,step_ms
 * one row every 10 ms: t in s from the start of the approach; tool centre in m; the reaction
 * force on the tool in N (world frame, +z up: pressing gives force_z > 0, friction gives a
 * component against the sliding direction); the tool's contact points; its deepest penetration
 * in m; and the mean wall time of the row's sh_world_step calls in ms. stderr: the setup, then
 * a summary: the peak normal force, the exponent p of a power-law fit F ~ d^p over the press
 * (d = tool travel below the first touch; 1.5 for a sphere on an elastic half-space), the mean
 * force along the sliding direction while sliding (friction plus the push of the slope ahead),
 * the largest force after lift-off, and the step times.
 *
 * What you see: the force is exactly 0 until the tool touches (t = 0.37 s, about a millimetre
 * above the predicted height: the liver settles a little further), grows to 3.1 N by the end
 * of the press with a fitted exponent of 1.6, the tool penetrating at most 0.2 mm. For the first
 * 2 cm of the slide the force along the sliding direction is -1.0 to -1.3 N: about -0.2 N is
 * friction (the same run without friction gives the rest, the push of the rising slope ahead),
 * less than mu_d times the normal force because the tissue is dragged along under the tool.
 * Over the last centimetre the tool crosses a convex edge and one contact point carries 1-2.6 N
 * (penetration up to 0.85 mm). After lift-off the force is 0 again.
 *
 * Exit status: 0 on success; 1 if any call fails or a force is not finite. */
#include <softhap/softhap.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CHECK(call)                                                                        \
    do {                                                                                   \
        sh_status status_ = (call);                                                        \
        if (status_ != SH_OK) {                                                            \
            fprintf(stderr, "palpation: %s failed: %s\n  %s\n", #call,                     \
                    sh_status_string(status_), sh_last_error_message());                   \
            goto done;                                                                     \
        }                                                                                  \
    } while (0)

static const double kPi = 3.14159265358979323846;
static const double kLiverSize = 0.16;     /* largest extent after scaling (m) */
static const double kRowTime = 0.01;       /* one CSV row per 10 ms of simulated time (s) */
static const double kSettleTime = 1.5;     /* simulated time to settle on the table (s) */
static const double kSettleDamping = 50.0; /* per-node damping while settling (1/s) */
static const double kToolRadius = 0.01;    /* m */
static const double kGap = 0.01;           /* start and end height above touching (m) */
static const double kIndentation = 0.012;  /* press depth below touching (m) */
static const double kSlide = 0.03;         /* slide length (m) */
static const double kMinThickness = 0.03;  /* tissue under the path at least this thick (m) */

/* Phase end times (s from the start of the approach). */
static const double kApproachEnd = 0.5, kPressEnd = 1.5, kHold1End = 1.7, kSlideEnd = 3.2,
                    kHold2End = 3.4, kLiftEnd = 3.9, kEnd = 4.2;

/* The highest surface triangle above the point (x, y), seen from above: its index, and its
 * height there in *height; -1 and -INFINITY if the vertical line through it misses the surface. */
static int32_t top_triangle(const double* nodes, const int32_t* tris, int32_t tri_count, double x, double y,
                            double* height) {
    int32_t t, hit = -1;
    *height = -INFINITY;
    for (t = 0; t < tri_count; ++t) {
        const double* a = &nodes[3 * tris[3 * t]];
        const double* b = &nodes[3 * tris[3 * t + 1]];
        const double* c = &nodes[3 * tris[3 * t + 2]];
        /* Barycentric coordinates of (x, y) in the triangle's projection on the xy plane. */
        const double det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        double u, v, z;
        if (fabs(det) < 1e-18) continue;
        u = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / det;
        v = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / det;
        if (u < 0.0 || v < 0.0 || u + v > 1.0) continue;
        z = a[2] + u * (b[2] - a[2]) + v * (c[2] - a[2]);
        if (z > *height) {
            *height = z;
            hit = t;
        }
    }
    return hit;
}

/* Height (m) of the surface above (x, y), seen from above; -INFINITY off the surface. */
static double surface_height(const double* nodes, const int32_t* tris, int32_t tri_count, double x, double y) {
    double height;
    top_triangle(nodes, tris, tri_count, x, y, &height);
    return height;
}

/* Height (m) of the tool's centre when the sphere of radius r, lowered vertically over (x, y),
 * first touches the surface: the highest of h(p) + sqrt(r^2 - |p - (x, y)|^2) over points p of
 * the disc under it (the centre, and rings at r/2 and r, every 30 degrees). -INFINITY if the
 * centre is off the liver. */
static double touch_height(const double* nodes, const int32_t* tris, int32_t tri_count, double x,
                           double y, double r) {
    double best = surface_height(nodes, tris, tri_count, x, y) + r;
    int ring, k;
    if (!isfinite(best)) return best;
    for (ring = 1; ring <= 2; ++ring)
        for (k = 0; k < 12; ++k) {
            const double d = 0.5 * ring * r, a = k * kPi / 6.0;
            const double h = surface_height(nodes, tris, tri_count, x + d * cos(a), y + d * sin(a));
            const double z = h + sqrt(r * r - d * d);
            if (z > best) best = z;
        }
    return best;
}

/* Normal (unit, outward) of the triangle with node indices tri[0..2]. */
static void triangle_normal(const double* nodes, const int32_t* tri, double n[3]) {
    const double* a = &nodes[3 * tri[0]];
    const double* b = &nodes[3 * tri[1]];
    const double* c = &nodes[3 * tri[2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double length;
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    n[0] /= length;
    n[1] /= length;
    n[2] /= length;
}

/* Smooth 0 -> 1 over [0, 1] with zero slope at both ends (for approach and lift-off). */
static double ease(double s) {
    if (s <= 0.0) return 0.0;
    if (s >= 1.0) return 1.0;
    return 0.5 - 0.5 * cos(kPi * s);
}

/* Fraction of the way through [begin, end] at time t, clamped to [0, 1]. */
static double progress(double t, double begin, double end) {
    const double s = (t - begin) / (end - begin);
    return s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
}

/* The scripted trajectory: the tool centre at time t. heights[0..samples-1] are the touching
 * heights of the tool's centre at equal steps along the slide. */
static void tool_position(double t, const double start[2], const double direction[2], const double* heights,
                          int samples, double out[3]) {
    double slide = 0.0, below = 0.0, s, h;
    int k;
    if (t < kApproachEnd) {
        below = -kGap * (1.0 - ease(progress(t, 0.0, kApproachEnd)));
    } else if (t < kPressEnd) {
        below = kIndentation * progress(t, kApproachEnd, kPressEnd);
    } else if (t < kHold1End) {
        below = kIndentation;
    } else if (t < kSlideEnd) {
        below = kIndentation;
        slide = progress(t, kHold1End, kSlideEnd);
    } else if (t < kHold2End) {
        below = kIndentation;
        slide = 1.0;
    } else {
        slide = 1.0;
        below = kIndentation - (kIndentation + kGap) * ease(progress(t, kHold2End, kLiftEnd));
    }
    /* Linear interpolation of the touch height along the slide. */
    s = slide * (samples - 1);
    k = (int)s;
    if (k >= samples - 1) k = samples - 2;
    h = heights[k] + (s - k) * (heights[k + 1] - heights[k]);
    out[0] = start[0] + slide * kSlide * direction[0];
    out[1] = start[1] + slide * kSlide * direction[1];
    out[2] = h - below;
}

/* The table: a plane through the origin with normal +z. Its stiffness keeps the liver's weight
 * (about 5.4 N on a few nodes) within a tenth of a millimetre. */
static sh_status add_table(sh_world* world, double friction, sh_obstacle_id* out) {
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_PLANE; /* normal (0, 0, 1) by default */
    def.contact.stiffness = 2e6;     /* N/m^1.5 per node */
    def.contact.damping = 0.2;       /* s/m */
    def.contact.static_friction = friction;
    def.contact.dynamic_friction = friction > 0.0 ? friction - 0.1 : 0.0;
    return sh_obstacle_create(world, &def, out);
}

int main(int argc, char** argv) {
    enum { kSamples = 31 };
    static const double kDirections[8][2] = {{1.0, 0.0}, {-1.0, 0.0}, {0.0, 1.0}, {0.0, -1.0},
                                             {0.70710678118654752, 0.70710678118654752},
                                             {-0.70710678118654752, 0.70710678118654752},
                                             {0.70710678118654752, -0.70710678118654752},
                                             {-0.70710678118654752, -0.70710678118654752}};
    const char* mesh_path = argc > 1 ? argv[1] : "../shared/meshes/liver.msh";
    const char* integrator_name = argc > 2 ? argv[2] : "symplectic";
    const double identity[4] = {1.0, 0.0, 0.0, 0.0};
    sh_mesh* file_mesh = NULL;
    sh_mesh* turned = NULL;
    sh_mesh* mesh = NULL;
    sh_world* world = NULL;
    double* x = NULL;
    double* damping = NULL;
    int32_t* tets = NULL;
    int32_t* tris = NULL;
    int exit_code = 1;
    int32_t i, node_count, tri_count;
    sh_mesh_info info;
    sh_world_def world_def;
    sh_fem_body_def def;
    sh_collider_def tool_def;
    sh_body_id body;
    sh_body_info body_info;
    sh_obstacle_id table;
    sh_tool_id tool;
    sh_contact_state table_state, tool_state;
    sh_step_report report;
    uint64_t warnings[SH_WARN_COUNT];
    double dt, scale, translation[3], extent = 0.0, start[2] = {0.0, 0.0}, direction[2] = {1.0, 0.0};
    double heights[kSamples], pose[3], settle_wall = 0.0, row_wall, wall_sum = 0.0, wall_max = 0.0;
    double peak_normal = 0.0, peak_depth = 0.0, slide_along = 0.0, slide_normal = 0.0, after_lift = 0.0;
    double touch_z = NAN, fit_sxx = 0.0, fit_sxy = 0.0, fit_sx = 0.0, fit_sy = 0.0, total_mass;
    int step, steps, steps_per_row, row, rows, slide_rows = 0, fit_rows = 0, max_substeps = 1;
    int max_contact_substeps = 1;
    sh_integrator integrator;

    if (strcmp(integrator_name, "symplectic") == 0) {
        integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
        dt = 1e-4; /* s: see the header on friction */
    } else if (strcmp(integrator_name, "implicit") == 0) {
        integrator = SH_INTEGRATOR_IMPLICIT_EULER;
        dt = 1e-2; /* s: a 100 Hz organ step */
    } else {
        fprintf(stderr, "usage: palpation [mesh [symplectic|implicit]]\n");
        return 2;
    }
    steps_per_row = (int)(kRowTime / dt + 0.5);

    /* 1. The mesh: turned so that the file's +y side (the flattest) faces down, (x, y, z) ->
     *    (x, z, -y), a proper rotation, then scaled to a 16 cm liver centred over the origin
     *    with its lowest point on the table (z = 0). */
    CHECK(sh_mesh_load(mesh_path, &file_mesh));
    CHECK(sh_mesh_get_info(file_mesh, &info));
    node_count = info.node_count;
    x = malloc(sizeof(double) * 3 * (size_t)node_count);
    damping = malloc(sizeof(double) * (size_t)node_count);
    tets = malloc(sizeof(int32_t) * 4 * (size_t)info.tet_count);
    tris = malloc(sizeof(int32_t) * 3 * (size_t)info.surface_triangle_count);
    if (!x || !damping || !tets || !tris) {
        fprintf(stderr, "palpation: out of memory\n");
        goto done;
    }
    CHECK(sh_mesh_get_nodes(file_mesh, x, 3 * (int64_t)node_count));
    CHECK(sh_mesh_get_tets(file_mesh, tets, 4 * (int64_t)info.tet_count));
    for (i = 0; i < node_count; ++i) {
        const double y = x[3 * i + 1], z = x[3 * i + 2];
        x[3 * i + 1] = z;
        x[3 * i + 2] = -y;
    }
    CHECK(sh_mesh_create(x, node_count, tets, info.tet_count, &turned));
    CHECK(sh_mesh_get_info(turned, &info));
    for (i = 0; i < 3; ++i)
        if (info.bounds_max[i] - info.bounds_min[i] > extent) extent = info.bounds_max[i] - info.bounds_min[i];
    scale = kLiverSize / extent;
    translation[0] = -0.5 * scale * (info.bounds_min[0] + info.bounds_max[0]);
    translation[1] = -0.5 * scale * (info.bounds_min[1] + info.bounds_max[1]);
    translation[2] = -scale * info.bounds_min[2];
    CHECK(sh_mesh_transform(turned, scale, translation, &mesh));
    CHECK(sh_mesh_get_info(mesh, &info));
    tri_count = info.surface_triangle_count;
    CHECK(sh_mesh_get_surface_triangles(mesh, tris, 3 * (int64_t)tri_count));
    fprintf(stderr, "palpation: %s: %d nodes, %d tets, %d surface triangles, scaled by %.4g to "
            "%.1f x %.1f x %.1f cm\n", mesh_path, node_count, info.tet_count, tri_count, scale,
            (info.bounds_max[0] - info.bounds_min[0]) * 100, (info.bounds_max[1] - info.bounds_min[1]) * 100,
            (info.bounds_max[2] - info.bounds_min[2]) * 100);

    /* 2. The world, the liver and a frictionless table to settle on. */
    sh_world_def_default(&world_def); /* gravity (0, 0, -9.81) m/s^2 */
    CHECK(sh_world_create(&world_def, &world));
    sh_fem_body_def_default(&def);
    def.mesh = mesh;
    def.material.model = SH_MATERIAL_COROTATIONAL;
    def.material.young = 15e3;     /* Pa: liver parenchyma */
    def.material.poisson = 0.45;
    def.material.density = 1000.0; /* kg/m^3 */
    def.integrator = integrator;
    def.on_unstable = SH_UNSTABLE_SUBSTEP;
    def.damping_mass = 2.0;        /* 1/s */
    CHECK(sh_world_add_fem_body(world, &def, &body));
    CHECK(sh_body_get_info(world, body, &body_info));
    total_mass = body_info.total_mass;
    CHECK(add_table(world, 0.0, &table));
    fprintf(stderr, "palpation: mass %.0f g, corotational E = %.0f kPa, nu = %.2f; %s Euler at dt = %g ms "
            "(critical explicit step %.3f ms)\n", total_mass * 1e3, def.material.young * 1e-3,
            def.material.poisson, integrator_name, dt * 1e3,
            integrator == SH_INTEGRATOR_SYMPLECTIC_EULER ? body_info.dt_critical * 1e3 : INFINITY);

    /* 3. Settle with heavy damping, then clear it and put friction on the table. */
    for (i = 0; i < node_count; ++i) damping[i] = kSettleDamping;
    CHECK(sh_body_set_node_damping(world, body, damping, node_count));
    steps = (int)(kSettleTime / dt + 0.5);
    for (step = 0; step < steps; ++step) {
        CHECK(sh_world_step(world, dt, &report));
        settle_wall += report.wall_seconds;
    }
    CHECK(sh_body_set_node_damping(world, body, NULL, node_count));
    CHECK(sh_obstacle_get_contact(world, table, &table_state));
    fprintf(stderr, "palpation: settled for %.1f s (%.0f ms of wall time): kinetic energy %.1e J, table force "
            "%.3f N (weight %.3f N) on %d nodes, %.3f mm deep\n", kSettleTime, settle_wall * 1e3,
            report.kinetic_energy, -table_state.force[2], total_mass * 9.81, table_state.contact_count,
            table_state.max_depth * 1e3);
    CHECK(sh_obstacle_destroy(world, table));
    CHECK(add_table(world, 0.6, &table));

    /* 4. The path (see the header): the centre of the largest nearly level facet of the top,
     *    then the direction along which the facets under the tool (on the path and half a
     *    radius to either side) turn least from that facet. */
    CHECK(sh_body_get_positions(world, body, x, 3 * (int64_t)node_count));
    {
        double best_area = 0.0, best_turn = INFINITY, n0[3];
        int32_t t, facet = -1;
        int dir, k, side;
        for (t = 0; t < tri_count; ++t) {
            const double* a = &x[3 * tris[3 * t]];
            const double* b = &x[3 * tris[3 * t + 1]];
            const double* c = &x[3 * tris[3 * t + 2]];
            const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            const double w[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
            const double area = 0.5 * sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            const double cx = (a[0] + b[0] + c[0]) / 3.0, cy = (a[1] + b[1] + c[1]) / 3.0;
            if (w[2] < 0.95 * 2.0 * area || area <= best_area) continue; /* tilted over 18 deg, or smaller */
            double height;
            if (top_triangle(x, tris, tri_count, cx, cy, &height) != t) continue; /* not on top */
            if (height < kMinThickness) continue;
            best_area = area;
            facet = t;
            start[0] = cx;
            start[1] = cy;
        }
        if (facet < 0) {
            fprintf(stderr, "palpation: no level facet on the liver's top\n");
            goto done;
        }
        triangle_normal(x, &tris[3 * facet], n0);
        for (dir = 0; dir < 8; ++dir) {
            double turn = 0.0; /* largest 1 - cos(angle) between n0 and a facet under the tool */
            for (k = 0; k < kSamples && turn < best_turn; ++k)
                for (side = -1; side <= 1; ++side) {
                    const double s = kSlide * k / (kSamples - 1), o = 0.5 * kToolRadius * side;
                    const double px = start[0] + s * kDirections[dir][0] - o * kDirections[dir][1];
                    const double py = start[1] + s * kDirections[dir][1] + o * kDirections[dir][0];
                    double n[3], height;
                    const int32_t hit = top_triangle(x, tris, tri_count, px, py, &height);
                    if (hit < 0 || height < kMinThickness) {
                        turn = INFINITY;
                        break;
                    }
                    triangle_normal(x, &tris[3 * hit], n);
                    if (1.0 - (n[0] * n0[0] + n[1] * n0[1] + n[2] * n0[2]) > turn)
                        turn = 1.0 - (n[0] * n0[0] + n[1] * n0[1] + n[2] * n0[2]);
                }
            if (turn < best_turn) {
                best_turn = turn;
                direction[0] = kDirections[dir][0];
                direction[1] = kDirections[dir][1];
            }
        }
        if (!isfinite(best_turn)) {
            fprintf(stderr, "palpation: no %.0f cm path over the liver's top from (%.1f, %.1f) cm\n", kSlide * 100,
                    start[0] * 100, start[1] * 100);
            goto done;
        }
        fprintf(stderr, "palpation: path from (%.1f, %.1f) cm along (%.2f, %.2f), over facets within %.0f degrees "
                "of the first\n", start[0] * 100, start[1] * 100, direction[0], direction[1],
                acos(1.0 - best_turn) * 180.0 / kPi);
    }
    for (i = 0; i < kSamples; ++i)
        heights[i] = touch_height(x, tris, tri_count, start[0] + kSlide * i / (kSamples - 1) * direction[0],
                                  start[1] + kSlide * i / (kSamples - 1) * direction[1], kToolRadius);
    fprintf(stderr, "palpation: the tool would touch the settled surface with its centre at z = %.2f cm at the "
            "start, %.2f cm in the middle, %.2f cm at the end\n", heights[0] * 100, heights[kSamples / 2] * 100,
            heights[kSamples - 1] * 100);

    /* 5. The tool, 1 cm above the start. */
    sh_collider_def_default(&tool_def);
    tool_def.shape.kind = SH_SHAPE_SPHERE;
    tool_def.shape.radius = kToolRadius;
    tool_position(0.0, start, direction, heights, kSamples, tool_def.position);
    tool_def.contact.stiffness = 1e6;        /* N/m^1.5: 0.2-0.3 mm at a few newtons */
    tool_def.contact.damping = 1.5;          /* s/m: damps a node chattering on the tool */
    tool_def.contact.static_friction = 0.3;
    tool_def.contact.dynamic_friction = 0.2;
    CHECK(sh_tool_create(world, &tool_def, &tool));

    /* 6. The palpation: a row every kRowTime. */
    printf("t,tool_x,tool_y,tool_z,force_x,force_y,force_z,contacts,max_depth,step_ms\n");
    rows = (int)(kEnd / kRowTime + 0.5);
    for (row = 1; row <= rows; ++row) {
        double t = 0.0, d;
        row_wall = 0.0;
        for (step = 1; step <= steps_per_row; ++step) {
            t = ((row - 1) * steps_per_row + step) * dt;
            tool_position(t, start, direction, heights, kSamples, pose);
            CHECK(sh_tool_set_pose(world, tool, pose, identity));
            CHECK(sh_world_step(world, dt, &report));
            row_wall += report.wall_seconds;
            if (report.wall_seconds > wall_max) wall_max = report.wall_seconds;
            if (report.substeps > max_substeps) max_substeps = report.substeps;
            if (report.contact_substeps > max_contact_substeps) max_contact_substeps = report.contact_substeps;
        }
        wall_sum += row_wall;
        CHECK(sh_tool_get_contact(world, tool, &tool_state));
        if (!isfinite(tool_state.force[0]) || !isfinite(tool_state.force[1]) || !isfinite(tool_state.force[2])) {
            fprintf(stderr, "palpation: non-finite force at t = %g s\n", t);
            goto done;
        }
        printf("%.2f,%.5f,%.5f,%.5f,%.5f,%.5f,%.5f,%d,%.3e,%.4f\n", t, pose[0], pose[1], pose[2],
               tool_state.force[0], tool_state.force[1], tool_state.force[2], tool_state.contact_count,
               tool_state.max_depth, row_wall / steps_per_row * 1e3);
        if (tool_state.force[2] > peak_normal) peak_normal = tool_state.force[2];
        if (tool_state.max_depth > peak_depth) peak_depth = tool_state.max_depth;
        /* The press: fit log F = p log d + c, d the travel below the first touch (the row's
         * tool height plus its penetration then). */
        if (t <= kPressEnd && tool_state.contact_count > 0 && isnan(touch_z)) touch_z = pose[2] + tool_state.max_depth;
        d = touch_z - pose[2];
        if (t > kApproachEnd && t <= kPressEnd && d > 0.2 * kIndentation && tool_state.force[2] > 0.0) {
            const double lx = log(d), ly = log(tool_state.force[2]);
            fit_sx += lx;
            fit_sy += ly;
            fit_sxx += lx * lx;
            fit_sxy += lx * ly;
            ++fit_rows;
        }
        /* The slide after its first 0.1 s. */
        if (t > kHold1End + 0.1 && t <= kSlideEnd) {
            slide_along += tool_state.force[0] * direction[0] + tool_state.force[1] * direction[1];
            slide_normal += tool_state.force[2];
            ++slide_rows;
        }
        if (t > kLiftEnd) {
            const double f = sqrt(tool_state.force[0] * tool_state.force[0] + tool_state.force[1] * tool_state.force[1] +
                                  tool_state.force[2] * tool_state.force[2]);
            if (f > after_lift) after_lift = f;
        }
    }
    CHECK(sh_world_get_warnings(world, warnings));
    fprintf(stderr, "palpation: peak normal force %.3f N, deepest tool penetration %.3f mm\n", peak_normal,
            peak_depth * 1e3);
    if (fit_rows > 1)
        fprintf(stderr, "palpation: press: F ~ d^%.2f (least-squares fit over %d rows, d = %.1f to %.1f mm below the "
                "first touch)\n", (fit_rows * fit_sxy - fit_sx * fit_sy) / (fit_rows * fit_sxx - fit_sx * fit_sx),
                fit_rows, 0.2 * kIndentation * 1e3, (touch_z - (heights[0] - kIndentation)) * 1e3);
    if (slide_rows > 0)
        fprintf(stderr, "palpation: slide: mean force %.3f N along the sliding direction (friction and the slope "
                "ahead), mean force_z %.3f N\n", slide_along / slide_rows, slide_normal / slide_rows);
    fprintf(stderr, "palpation: largest force after lift-off %.2e N\n", after_lift);
    fprintf(stderr, "palpation: %d steps of %g ms: mean %.3f ms, max %.3f ms per step (%.2f s of wall time per "
            "simulated second), up to %d sub-steps and %d contact sub-steps; warnings: unstable %llu, inverted "
            "%llu, capacity %llu\n",
            rows * steps_per_row, dt * 1e3, wall_sum / (rows * steps_per_row) * 1e3, wall_max * 1e3, wall_sum / kEnd,
            max_substeps, max_contact_substeps, (unsigned long long)warnings[SH_WARN_UNSTABLE],
            (unsigned long long)warnings[SH_WARN_INVERTED], (unsigned long long)warnings[SH_WARN_CAPACITY]);
    exit_code = 0;

done:
    sh_world_destroy(world); /* NULL is fine */
    sh_mesh_destroy(mesh);
    sh_mesh_destroy(turned);
    sh_mesh_destroy(file_mesh);
    free(x);
    free(damping);
    free(tets);
    free(tris);
    return exit_code;
}
