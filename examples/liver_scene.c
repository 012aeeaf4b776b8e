/* liver_scene.c: the liver on a table and paths over its top (see liver_scene.h). */
#include "liver_scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CHECK(call) EXAMPLE_CHECK(def->program, call)

static const double kPi = 3.14159265358979323846;
static const double kLiverSize = 0.16;     /* largest extent after scaling (m) */
static const double kSettleTime = 1.5;     /* simulated time to settle on the table (s) */
static const double kSettleDamping = 50.0; /* per-node damping while settling (1/s) */
static const double kMinThickness = 0.03;  /* tissue under a path at least this thick (m) */

int example_failed(const char* program, const char* call, sh_status status) {
    if (status == SH_OK) return 0;
    fprintf(stderr, "%s: %s failed: %s\n  %s\n", program, call, sh_status_string(status), sh_last_error_message());
    return 1;
}

double liver_ease(double s) {
    if (s <= 0.0) return 0.0;
    if (s >= 1.0) return 1.0;
    return 0.5 - 0.5 * cos(kPi * s);
}

double liver_progress(double t, double begin, double end) {
    const double s = (t - begin) / (end - begin);
    return s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
}

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

static const char* integrator_name(sh_integrator integrator) {
    static const char* const kNames[SH_INTEGRATOR_COUNT] = {"forward Euler", "symplectic Euler", "RK2", "RK4",
                                                            "implicit Euler"};
    return (int)integrator >= 0 && integrator < SH_INTEGRATOR_COUNT ? kNames[integrator] : "?";
}

/* Loads the mesh and turns it so that the file's +y side (the flattest) faces down:
 * (x, y, z) -> (x, z, -y), a proper rotation. The turned nodes make a new mesh (*turned); out
 * gets the node and tet counts, and out->x (allocated here) the turned nodes. 0 on success. */
static int load_turned(const liver_scene_def* def, liver_scene* out, sh_mesh** turned) {
    sh_mesh* file_mesh = NULL;
    int32_t* tets = NULL;
    sh_mesh_info info;
    int32_t i;
    int ok = 0;

    CHECK(sh_mesh_load(def->mesh_path, &file_mesh));
    CHECK(sh_mesh_get_info(file_mesh, &info));
    out->node_count = info.node_count;
    out->tet_count = info.tet_count;
    out->x = malloc(sizeof(double) * 3 * (size_t)info.node_count);
    tets = malloc(sizeof(int32_t) * 4 * (size_t)info.tet_count);
    if (!out->x || !tets) {
        fprintf(stderr, "%s: out of memory\n", def->program);
        goto done;
    }
    CHECK(sh_mesh_get_nodes(file_mesh, out->x, info.node_count));
    CHECK(sh_mesh_get_tets(file_mesh, tets, info.tet_count));
    for (i = 0; i < info.node_count; ++i) {
        const double y = out->x[3 * i + 1], z = out->x[3 * i + 2];
        out->x[3 * i + 1] = z;
        out->x[3 * i + 2] = -y;
    }
    CHECK(sh_mesh_create(out->x, info.node_count, tets, info.tet_count, turned));
    ok = 1;

done:
    sh_mesh_destroy(file_mesh); /* NULL is fine */
    free(tets);
    return ok ? 0 : 1;
}

/* Scales the turned mesh to a kLiverSize liver centred over the origin with its lowest point on
 * the table (z = 0) into out->mesh, and reads its surface triangles. 0 on success. */
static int place_on_table(const liver_scene_def* def, const sh_mesh* turned, liver_scene* out) {
    sh_mesh_info info;
    double scale, translation[3], extent = 0.0;
    int i;

    CHECK(sh_mesh_get_info(turned, &info));
    for (i = 0; i < 3; ++i)
        if (info.bounds_max[i] - info.bounds_min[i] > extent) extent = info.bounds_max[i] - info.bounds_min[i];
    scale = kLiverSize / extent;
    translation[0] = -0.5 * scale * (info.bounds_min[0] + info.bounds_max[0]);
    translation[1] = -0.5 * scale * (info.bounds_min[1] + info.bounds_max[1]);
    translation[2] = -scale * info.bounds_min[2];
    CHECK(sh_mesh_transform(turned, scale, translation, &out->mesh));
    CHECK(sh_mesh_get_info(out->mesh, &info));
    out->triangle_count = info.surface_triangle_count;
    out->triangles = malloc(sizeof(int32_t) * 3 * (size_t)out->triangle_count);
    if (!out->triangles) {
        fprintf(stderr, "%s: out of memory\n", def->program);
        return 1;
    }
    CHECK(sh_mesh_get_surface_triangles(out->mesh, out->triangles, out->triangle_count));
    fprintf(stderr, "%s: %s: %d nodes, %d tets, %d surface triangles, scaled by %.4g to "
            "%.1f x %.1f x %.1f cm\n", def->program, def->mesh_path, out->node_count, info.tet_count,
            out->triangle_count, scale, (info.bounds_max[0] - info.bounds_min[0]) * 100,
            (info.bounds_max[1] - info.bounds_min[1]) * 100, (info.bounds_max[2] - info.bounds_min[2]) * 100);
    return 0;

done:
    return 1;
}

/* The world under gravity, the liver as a corotational body in it and a frictionless table to
 * settle on (its id in *table). 0 on success. */
static int create_world(const liver_scene_def* def, liver_scene* out, sh_obstacle_id* table) {
    sh_world_def world_def;
    sh_fem_body_def body_def;
    sh_body_info body_info;

    sh_world_def_default(&world_def); /* gravity (0, 0, -9.81) m/s^2 */
    CHECK(sh_world_create(&world_def, &out->world));
    sh_fem_body_def_default(&body_def);
    body_def.mesh = out->mesh;
    body_def.material.model = SH_MATERIAL_COROTATIONAL;
    body_def.material.young = 15e3;     /* Pa: liver parenchyma */
    body_def.material.poisson = 0.45;
    body_def.material.density = 1000.0; /* kg/m^3 */
    body_def.integrator = def->integrator;
    body_def.on_unstable = SH_UNSTABLE_SUBSTEP;
    body_def.damping_mass = 2.0;        /* 1/s */
    CHECK(sh_fem_body_create(out->world, &body_def, &out->body));
    CHECK(sh_body_get_info(out->world, out->body, &body_info));
    out->total_mass = body_info.total_mass;
    out->dt_critical = body_info.dt_critical;
    CHECK(add_table(out->world, 0.0, table));
    fprintf(stderr, "%s: mass %.0f g, corotational E = %.0f kPa, nu = %.2f; %s at dt = %g ms (critical "
            "explicit step %.3f ms)\n", def->program, out->total_mass * 1e3, body_def.material.young * 1e-3,
            body_def.material.poisson, integrator_name(def->integrator), def->dt * 1e3, body_info.dt_critical * 1e3);
    return 0;

done:
    return 1;
}

/* Lets the liver settle for kSettleTime under heavy per-node damping, so that it comes to rest
 * quickly, then clears the damping. Prints how well it settled: the table should carry its
 * weight. 0 on success. */
static int settle(const liver_scene_def* def, liver_scene* out, sh_obstacle_id table) {
    double* damping = malloc(sizeof(double) * (size_t)out->node_count);
    const int steps = (int)(kSettleTime / def->dt + 0.5);
    sh_contact_state table_state;
    sh_step_report report;
    double settle_wall = 0.0;
    int32_t i;
    int step, ok = 0;

    if (!damping) {
        fprintf(stderr, "%s: out of memory\n", def->program);
        return 1;
    }
    for (i = 0; i < out->node_count; ++i) damping[i] = kSettleDamping;
    CHECK(sh_body_set_node_damping(out->world, out->body, damping, out->node_count));
    for (step = 0; step < steps; ++step) {
        CHECK(sh_world_step(out->world, def->dt, &report));
        settle_wall += report.wall_seconds;
    }
    CHECK(sh_body_set_node_damping(out->world, out->body, NULL, out->node_count));
    CHECK(sh_obstacle_get_contact(out->world, table, &table_state));
    fprintf(stderr, "%s: settled for %.1f s (%.0f ms of wall time): kinetic energy %.1e J, table force "
            "%.3f N (weight %.3f N) on %d nodes, %.3f mm deep\n", def->program, kSettleTime, settle_wall * 1e3,
            report.kinetic_energy, -table_state.force[2], out->total_mass * 9.81, table_state.contact_count,
            table_state.max_depth * 1e3);
    ok = 1;

done:
    free(damping);
    return ok ? 0 : 1;
}

/* Fixes the nodes within def->base_height of the table to it. 0 on success. */
static int fix_base(const liver_scene_def* def, liver_scene* out) {
    int32_t* base = malloc(sizeof(int32_t) * (size_t)out->node_count);
    int32_t i, count = 0;
    int ok = 0;

    if (!base) {
        fprintf(stderr, "%s: out of memory\n", def->program);
        return 1;
    }
    for (i = 0; i < out->node_count; ++i)
        if (out->x[3 * i + 2] < def->base_height) base[count++] = i;
    CHECK(sh_body_fix_nodes(out->world, out->body, base, count));
    fprintf(stderr, "%s: %d nodes within %.0f mm of the table fixed to it\n", def->program, count,
            def->base_height * 1e3);
    ok = 1;

done:
    free(base);
    return ok ? 0 : 1;
}

int liver_scene_create(const liver_scene_def* def, liver_scene* out) {
    sh_mesh* turned = NULL;
    sh_obstacle_id table;
    int ok = 0;

    memset(out, 0, sizeof *out);
    out->program = def->program;
    if (load_turned(def, out, &turned) != 0) goto done;
    if (place_on_table(def, turned, out) != 0) goto done;
    if (create_world(def, out, &table) != 0) goto done;
    if (settle(def, out, table) != 0) goto done;
    /* Settled: the frictionless table goes, one with the friction asked for takes its place. */
    CHECK(sh_obstacle_destroy(out->world, table));
    CHECK(add_table(out->world, def->table_friction, &out->table));
    CHECK(sh_body_get_positions(out->world, out->body, out->x, out->node_count));
    if (def->base_height > 0.0 && fix_base(def, out) != 0) goto done;
    ok = 1;

done:
    sh_mesh_destroy(turned); /* NULL is fine */
    if (!ok) liver_scene_destroy(out);
    return ok ? 0 : 1;
}

void liver_scene_destroy(liver_scene* scene) {
    sh_world_destroy(scene->world); /* NULL is fine */
    sh_mesh_destroy(scene->mesh);
    free(scene->x);
    free(scene->triangles);
    memset(scene, 0, sizeof *scene);
}

int liver_scene_reset(liver_scene* scene) {
    double* zero = calloc(3 * (size_t)scene->node_count, sizeof(double));
    int ok = 0;
    if (!zero) {
        fprintf(stderr, "%s: out of memory\n", scene->program);
        return 1;
    }
    EXAMPLE_CHECK(scene->program, sh_body_set_positions(scene->world, scene->body, scene->x, scene->node_count));
    EXAMPLE_CHECK(scene->program, sh_body_set_velocities(scene->world, scene->body, zero, scene->node_count));
    ok = 1;
done:
    free(zero);
    return ok ? 0 : 1;
}

/* The eight directions a path may take, seen from above. */
static const double kDirections[8][2] = {{1.0, 0.0}, {-1.0, 0.0}, {0.0, 1.0}, {0.0, -1.0},
                                         {0.70710678118654752, 0.70710678118654752},
                                         {-0.70710678118654752, 0.70710678118654752},
                                         {0.70710678118654752, -0.70710678118654752},
                                         {-0.70710678118654752, -0.70710678118654752}};

/* The largest nearly level facet of the top (tilted at most 18 degrees) over at least
 * kMinThickness of tissue: its index, and its centre into out->start. -1 if there is none. */
static int32_t find_start_facet(const liver_scene* scene, liver_path* out) {
    const double* x = scene->x;
    const int32_t* tris = scene->triangles;
    double best_area = 0.0;
    int32_t t, facet = -1;
    for (t = 0; t < scene->triangle_count; ++t) {
        const double* a = &x[3 * tris[3 * t]];
        const double* b = &x[3 * tris[3 * t + 1]];
        const double* c = &x[3 * tris[3 * t + 2]];
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double w[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        const double area = 0.5 * sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        const double cx = (a[0] + b[0] + c[0]) / 3.0, cy = (a[1] + b[1] + c[1]) / 3.0;
        double height;
        if (w[2] < 0.95 * 2.0 * area || area <= best_area) continue; /* tilted over 18 deg, or smaller */
        if (top_triangle(x, tris, scene->triangle_count, cx, cy, &height) != t) continue; /* not on top */
        if (height < kMinThickness) continue;
        best_area = area;
        facet = t;
        out->start[0] = cx;
        out->start[1] = cy;
    }
    return facet;
}

/* How far the facets under a tool going from path->start along dir turn from the normal n0:
 * the largest 1 - cos(angle) over the path and half a radius to either side of it. INFINITY if
 * the tool would leave the top or its tissue grow thin; the search stops early once the turn
 * reaches `enough` (a better direction is already known). */
static double path_turn(const liver_scene* scene, const liver_path* path, const double dir[2], const double n0[3],
                        double enough) {
    double turn = 0.0;
    int k, side;
    for (k = 0; k < LIVER_PATH_SAMPLES && turn < enough; ++k)
        for (side = -1; side <= 1; ++side) {
            const double s = path->length * k / (LIVER_PATH_SAMPLES - 1), o = 0.5 * path->tool_radius * side;
            const double px = path->start[0] + s * dir[0] - o * dir[1];
            const double py = path->start[1] + s * dir[1] + o * dir[0];
            double n[3], height;
            const int32_t hit = top_triangle(scene->x, scene->triangles, scene->triangle_count, px, py, &height);
            if (hit < 0 || height < kMinThickness) return INFINITY;
            triangle_normal(scene->x, &scene->triangles[3 * hit], n);
            if (1.0 - (n[0] * n0[0] + n[1] * n0[1] + n[2] * n0[2]) > turn)
                turn = 1.0 - (n[0] * n0[0] + n[1] * n0[1] + n[2] * n0[2]);
        }
    return turn;
}

/* Samples the touching height along the path. */
static void sample_heights(const liver_scene* scene, liver_path* out) {
    enum { kSamples = LIVER_PATH_SAMPLES };
    int i;
    for (i = 0; i < kSamples; ++i)
        out->heights[i] = touch_height(scene->x, scene->triangles, scene->triangle_count,
                                       out->start[0] + out->length * i / (kSamples - 1) * out->direction[0],
                                       out->start[1] + out->length * i / (kSamples - 1) * out->direction[1],
                                       out->tool_radius);
}

/* The start at the centre of the largest level facet of the top, then the direction along
 * which the facets under the tool turn least from that facet: the coarse surface gives a
 * sphere little support where it straddles a sharp edge (see liver_scene.h). */
int liver_scene_find_path(const liver_scene* scene, double tool_radius, double length, liver_path* out) {
    double best_turn = INFINITY, n0[3];
    int32_t facet;
    int dir;

    memset(out, 0, sizeof *out);
    out->direction[0] = 1.0;
    out->length = length;
    out->tool_radius = tool_radius;
    facet = find_start_facet(scene, out);
    if (facet < 0) {
        fprintf(stderr, "%s: no level facet on the liver's top\n", scene->program);
        return 1;
    }
    triangle_normal(scene->x, &scene->triangles[3 * facet], n0);
    for (dir = 0; dir < 8; ++dir) {
        const double turn = path_turn(scene, out, kDirections[dir], n0, best_turn);
        if (turn < best_turn) {
            best_turn = turn;
            out->direction[0] = kDirections[dir][0];
            out->direction[1] = kDirections[dir][1];
        }
    }
    if (!isfinite(best_turn)) {
        fprintf(stderr, "%s: no %.0f cm path over the liver's top from (%.1f, %.1f) cm\n", scene->program,
                length * 100, out->start[0] * 100, out->start[1] * 100);
        return 1;
    }
    fprintf(stderr, "%s: path from (%.1f, %.1f) cm along (%.2f, %.2f), over facets within %.0f degrees "
            "of the first\n", scene->program, out->start[0] * 100, out->start[1] * 100, out->direction[0],
            out->direction[1], acos(1.0 - best_turn) * 180.0 / kPi);
    sample_heights(scene, out);
    fprintf(stderr, "%s: the tool would touch the settled surface with its centre at z = %.2f cm at the "
            "start, %.2f cm in the middle, %.2f cm at the end\n", scene->program, out->heights[0] * 100,
            out->heights[LIVER_PATH_SAMPLES / 2] * 100, out->heights[LIVER_PATH_SAMPLES - 1] * 100);
    return 0;
}

void liver_path_point(const liver_path* path, double along, double below, double out[3]) {
    /* Linear interpolation of the touch height along the path. */
    const double s = along * (LIVER_PATH_SAMPLES - 1);
    int k = (int)s;
    double h;
    if (k >= LIVER_PATH_SAMPLES - 1) k = LIVER_PATH_SAMPLES - 2;
    h = path->heights[k] + (s - k) * (path->heights[k + 1] - path->heights[k]);
    out[0] = path->start[0] + along * path->length * path->direction[0];
    out[1] = path->start[1] + along * path->length * path->direction[1];
    out[2] = h - below;
}
