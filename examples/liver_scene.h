/* liver_scene.h: the scene that palpation.c and haptic_loop.c share: SOFA's haptic-demo liver
 * lying on a table under gravity, settled, and a path for a sphere tool across its top.
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
 * 1.5 s of simulated time, with heavy per-node damping (about critical for its sag mode) on a
 * frictionless table, so that its base can spread to equilibrium (it sags about 1.5 cm); then
 * the damping is cleared and the table replaced by one with the friction the host asks for.
 * A host may instead fix the liver's base to the table (the nodes within a given height of it).
 *
 * The path. This liver's surface is coarse (facets 2-3 cm across, meeting at edges of 15-50
 * degrees), and a sphere straddling a convex edge between two facets gets little support from
 * it: a tool's contact with a surface triangle only counts where the sphere's deepest point
 * projects inside that triangle, and the edge's nodes may lie outside the sphere. So a path
 * starts at the centre of the largest nearly level facet of the top (over at least 3 cm of
 * tissue) and takes the direction, of eight, along which the facets under the tool turn least
 * from that one. Along it, the height at which a sphere lowered vertically would first touch
 * the settled surface is sampled, so that a tool can follow the top at a given depth.
 *
 * Messages (prefixed with the program's name) go to stderr. */
#ifndef SOFTHAP_EXAMPLES_LIVER_SCENE_H
#define SOFTHAP_EXAMPLES_LIVER_SCENE_H

#include <softhap/softhap.h>

/* If status is not SH_OK, prints "<program>: <call> failed: <status text>" and the library's
 * last error message on stderr and returns 1; else returns 0. */
int example_failed(const char* program, const char* call, sh_status status);

/* Runs call (an expression giving an sh_status); on failure reports it and jumps to `done`. */
#define EXAMPLE_CHECK(program, call)                                                        \
    do {                                                                                   \
        if (example_failed((program), #call, (call))) goto done;                           \
    } while (0)

/* What to build. */
typedef struct liver_scene_def {
    const char* program;    /* prefix of the messages on stderr */
    const char* mesh_path;  /* the liver mesh (any format sh_mesh_load reads) */
    sh_integrator integrator;
    double dt;              /* host step while settling (s) */
    double table_friction;  /* static friction of the table after settling (dynamic: 0.1 less),
                               0 for none */
    double base_height;     /* > 0: after settling, the nodes within this height (m) of the table
                               are fixed, the liver held by its base instead of by friction; 0:
                               none */
} liver_scene_def;

/* The settled scene. */
typedef struct liver_scene {
    const char* program;
    sh_world* world;
    sh_mesh* mesh;              /* the turned and scaled mesh */
    sh_body_id body;
    sh_obstacle_id table;       /* the table with friction */
    int32_t node_count, tet_count, triangle_count;
    double* x;                  /* node positions after settling (3 per node, m) */
    int32_t* triangles;         /* surface triangles (3 node indices each, outward) */
    double total_mass;          /* kg */
    double dt_critical;         /* critical explicit step of the body at rest (s) */
} liver_scene;

/* Builds and settles the scene into *out (see the header). Returns 0 on success; on failure
 * reports on stderr, releases what it made and returns 1. */
int liver_scene_create(const liver_scene_def* def, liver_scene* out);

/* Releases everything the scene holds (the world, the mesh, the arrays). */
void liver_scene_destroy(liver_scene* scene);

/* Puts the liver back to its settled state, at rest. Returns 0 on success. */
int liver_scene_reset(liver_scene* scene);

/* Samples along a path, at equal steps from its start to its end. */
#define LIVER_PATH_SAMPLES 31

/* A straight path over the liver's top, seen from above. */
typedef struct liver_path {
    double start[2];      /* m */
    double direction[2];  /* unit */
    double length;        /* m */
    double tool_radius;   /* m */
    double heights[LIVER_PATH_SAMPLES]; /* height of the tool's centre (m) at which a sphere of
                                           tool_radius, lowered vertically, first touches the
                                           settled surface */
} liver_path;

/* Finds a path of the given length for a sphere tool of the given radius (see the header).
 * Returns 0 on success; 1, with a message on stderr, if the top has none. */
int liver_scene_find_path(const liver_scene* scene, double tool_radius, double length, liver_path* out);

/* The tool's centre at fraction `along` in [0, 1] of the path, `below` metres below the
 * height where it would touch the settled surface there (negative: above it). */
void liver_path_point(const liver_path* path, double along, double below, double out[3]);

/* Smooth 0 -> 1 over [0, 1] with zero slope at both ends. */
double liver_ease(double s);

/* Fraction of the way through [begin, end] at time t, clamped to [0, 1]. */
double liver_progress(double t, double begin, double end);

#endif /* SOFTHAP_EXAMPLES_LIVER_SCENE_H */
