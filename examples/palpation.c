/* palpation.c: a sphere tool presses into a liver lying on a table, slides across its top and
 * lifts off; the tool's reaction force is printed as CSV every 10 ms.
 *
 *   palpation [mesh [symplectic|implicit]]   (defaults: ../shared/meshes/liver.msh, symplectic)
 *
 * `make palpation` runs it from the repository root (about 5 s on one core).
 *
 * The scene (liver_scene.h): SOFA's haptic-demo liver, scaled to 16 cm (550 g), corotational
 * E = 15 kPa, nu = 0.45, lying on a table (a plane obstacle at z = 0) under gravity, settled
 * dynamically for 1.5 s on a frictionless table with heavy per-node damping; then the damping is
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
 * The press starts at the centre of the largest nearly level facet of the top and the slide
 * takes the direction along which the facets under the tool turn least (see liver_scene.h on
 * why: the liver's surface is coarse).
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
 * above the predicted height: the liver settles a little further), grows to 4.1 N by the end
 * of the press with a fitted exponent of 1.7, the tool penetrating at most 0.4 mm. While it
 * slides, the force along the sliding direction is -1.4 to -2.4 N (friction, and the push of the
 * rising slope ahead) under a normal force of 3.6-5.0 N; near the end of the path the surface
 * falls away and the tool briefly loses contact. After lift-off the force is 0 again.
 *
 * Exit status: 0 on success; 1 if any call fails or a force is not finite. */
#include "liver_scene.h"

#include <softhap/softhap.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#define CHECK(call) EXAMPLE_CHECK("palpation", call)

static const double kRowTime = 0.01;       /* one CSV row per 10 ms of simulated time (s) */
static const double kToolRadius = 0.01;    /* m */
static const double kGap = 0.01;           /* start and end height above touching (m) */
static const double kIndentation = 0.012;  /* press depth below touching (m) */
static const double kSlide = 0.03;         /* slide length (m) */

/* Phase end times (s from the start of the approach). */
static const double kApproachEnd = 0.5, kPressEnd = 1.5, kHold1End = 1.7, kSlideEnd = 3.2,
                    kHold2End = 3.4, kLiftEnd = 3.9, kEnd = 4.2;

/* The scripted trajectory: the tool centre at time t along path. */
static void tool_position(double t, const liver_path* path, double out[3]) {
    double slide = 0.0, below = 0.0;
    if (t < kApproachEnd) {
        below = -kGap * (1.0 - liver_ease(liver_progress(t, 0.0, kApproachEnd)));
    } else if (t < kPressEnd) {
        below = kIndentation * liver_progress(t, kApproachEnd, kPressEnd);
    } else if (t < kHold1End) {
        below = kIndentation;
    } else if (t < kSlideEnd) {
        below = kIndentation;
        slide = liver_progress(t, kHold1End, kSlideEnd);
    } else if (t < kHold2End) {
        below = kIndentation;
        slide = 1.0;
    } else {
        slide = 1.0;
        below = kIndentation - (kIndentation + kGap) * liver_ease(liver_progress(t, kHold2End, kLiftEnd));
    }
    liver_path_point(path, slide, below, out);
}

/* The wall time and sub-steps of the steps so far. */
typedef struct step_stats {
    double wall_sum, wall_max;  /* s */
    int max_substeps, max_contact_substeps;
} step_stats;

/* What the summary reports, gathered row by row. */
typedef struct force_summary {
    double peak_normal, peak_depth;    /* N, m */
    double touch_z;                    /* tool height at the first touch (m); NAN before it */
    double fit_sx, fit_sy, fit_sxx, fit_sxy; /* least-squares sums of log d and log F */
    int fit_rows;
    double slide_along, slide_normal;  /* sums of the force along the slide and of force_z (N) */
    int slide_rows;
    double after_lift;                 /* largest |F| after lift-off (N) */
} force_summary;

/* Sets the scene's integrator and the host step (s) for the name given on the command line.
 * 0 on success; 1 for an unknown name. */
static int choose_integrator(const char* name, liver_scene_def* def) {
    if (strcmp(name, "symplectic") == 0) {
        def->integrator = SH_INTEGRATOR_SYMPLECTIC_EULER;
        def->dt = 1e-4; /* s: see the header on friction */
    } else if (strcmp(name, "implicit") == 0) {
        def->integrator = SH_INTEGRATOR_IMPLICIT_EULER;
        def->dt = 1e-2; /* s: a 100 Hz organ step */
    } else {
        return 1;
    }
    return 0;
}

/* The sphere tool, at the trajectory's start 1 cm above the path. 0 on success. */
static int create_tool(liver_scene* scene, const liver_path* path, sh_tool_id* tool) {
    sh_collider_def tool_def;
    sh_collider_def_default(&tool_def);
    tool_def.shape.kind = SH_SHAPE_SPHERE;
    tool_def.shape.radius = kToolRadius;
    tool_position(0.0, path, tool_def.position);
    tool_def.contact.stiffness = 1e6;        /* N/m^1.5: 0.2-0.3 mm at a few newtons */
    tool_def.contact.damping = 1.5;          /* s/m: damps a node chattering on the tool */
    tool_def.contact.static_friction = 0.3;
    tool_def.contact.dynamic_friction = 0.2;
    CHECK(sh_tool_create(scene->world, &tool_def, tool));
    return 0;

done:
    return 1;
}

/* The steps of CSV row `row` (1-based): the tool moved along the trajectory before each step.
 * The last step's time and tool position go to *t and pose; the row's wall time to *row_wall.
 * 0 on success. */
static int step_row(liver_scene* scene, sh_tool_id tool, const liver_path* path, int row, int steps_per_row,
                    double dt, double* t, double pose[3], double* row_wall, step_stats* stats) {
    const double identity[4] = {1.0, 0.0, 0.0, 0.0};
    sh_step_report report;
    int step;
    *row_wall = 0.0;
    for (step = 1; step <= steps_per_row; ++step) {
        *t = ((row - 1) * steps_per_row + step) * dt;
        tool_position(*t, path, pose);
        CHECK(sh_tool_set_pose(scene->world, tool, pose, identity));
        CHECK(sh_world_step(scene->world, dt, &report));
        *row_wall += report.wall_seconds;
        if (report.wall_seconds > stats->wall_max) stats->wall_max = report.wall_seconds;
        if (report.substeps > stats->max_substeps) stats->max_substeps = report.substeps;
        if (report.contact_substeps > stats->max_contact_substeps)
            stats->max_contact_substeps = report.contact_substeps;
    }
    stats->wall_sum += *row_wall;
    return 0;

done:
    return 1;
}

/* Adds a row's force to the summary at time t with the tool at pose. */
static void summarise_row(force_summary* s, double t, const double pose[3], const sh_contact_state* state,
                          const liver_path* path) {
    double d;
    if (state->force[2] > s->peak_normal) s->peak_normal = state->force[2];
    if (state->max_depth > s->peak_depth) s->peak_depth = state->max_depth;
    /* The press: fit log F = p log d + c, d the travel below the first touch (the row's tool
     * height plus its penetration then). */
    if (t <= kPressEnd && state->contact_count > 0 && isnan(s->touch_z)) s->touch_z = pose[2] + state->max_depth;
    d = s->touch_z - pose[2];
    if (t > kApproachEnd && t <= kPressEnd && d > 0.2 * kIndentation && state->force[2] > 0.0) {
        const double lx = log(d), ly = log(state->force[2]);
        s->fit_sx += lx;
        s->fit_sy += ly;
        s->fit_sxx += lx * lx;
        s->fit_sxy += lx * ly;
        ++s->fit_rows;
    }
    /* The slide after its first 0.1 s, once the tool has started to move. */
    if (t > kHold1End + 0.1 && t <= kSlideEnd) {
        s->slide_along += state->force[0] * path->direction[0] + state->force[1] * path->direction[1];
        s->slide_normal += state->force[2];
        ++s->slide_rows;
    }
    if (t > kLiftEnd) {
        const double f = sqrt(state->force[0] * state->force[0] + state->force[1] * state->force[1] +
                              state->force[2] * state->force[2]);
        if (f > s->after_lift) s->after_lift = f;
    }
}

/* The palpation: one CSV row every kRowTime, each added to the summary. 0 on success; 1 if a
 * call fails or a force is not finite. */
static int palpate(liver_scene* scene, sh_tool_id tool, const liver_path* path, double dt, force_summary* summary,
                   step_stats* stats) {
    const int steps_per_row = (int)(kRowTime / dt + 0.5);
    const int rows = (int)(kEnd / kRowTime + 0.5);
    sh_contact_state state;
    int row;
    printf("t,tool_x,tool_y,tool_z,force_x,force_y,force_z,contacts,max_depth,step_ms\n");
    for (row = 1; row <= rows; ++row) {
        double t = 0.0, pose[3], row_wall;
        if (step_row(scene, tool, path, row, steps_per_row, dt, &t, pose, &row_wall, stats) != 0) return 1;
        CHECK(sh_tool_get_contact(scene->world, tool, &state));
        if (!isfinite(state.force[0]) || !isfinite(state.force[1]) || !isfinite(state.force[2])) {
            fprintf(stderr, "palpation: non-finite force at t = %g s\n", t);
            return 1;
        }
        printf("%.2f,%.5f,%.5f,%.5f,%.5f,%.5f,%.5f,%d,%.3e,%.4f\n", t, pose[0], pose[1], pose[2], state.force[0],
               state.force[1], state.force[2], state.contact_count, state.max_depth, row_wall / steps_per_row * 1e3);
        summarise_row(summary, t, pose, &state, path);
    }
    return 0;

done:
    return 1;
}

/* The summary on stderr: the forces, the press's power-law exponent, the slide's friction, and
 * the cost of the steps. */
static void print_summary(const force_summary* s, const step_stats* stats, const liver_path* path, double dt,
                          const uint64_t warnings[SH_WARN_COUNT]) {
    const int steps = (int)(kEnd / kRowTime + 0.5) * (int)(kRowTime / dt + 0.5);
    fprintf(stderr, "palpation: peak normal force %.3f N, deepest tool penetration %.3f mm\n", s->peak_normal,
            s->peak_depth * 1e3);
    if (s->fit_rows > 1)
        fprintf(stderr, "palpation: press: F ~ d^%.2f (least-squares fit over %d rows, d = %.1f to %.1f mm below the "
                "first touch)\n",
                (s->fit_rows * s->fit_sxy - s->fit_sx * s->fit_sy) / (s->fit_rows * s->fit_sxx - s->fit_sx * s->fit_sx),
                s->fit_rows, 0.2 * kIndentation * 1e3, (s->touch_z - (path->heights[0] - kIndentation)) * 1e3);
    if (s->slide_rows > 0)
        fprintf(stderr, "palpation: slide: mean force %.3f N along the sliding direction (friction and the slope "
                "ahead), mean force_z %.3f N\n", s->slide_along / s->slide_rows, s->slide_normal / s->slide_rows);
    fprintf(stderr, "palpation: largest force after lift-off %.2e N\n", s->after_lift);
    fprintf(stderr, "palpation: %d steps of %g ms: mean %.3f ms, max %.3f ms per step (%.2f s of wall time per "
            "simulated second), up to %d sub-steps and %d contact sub-steps; warnings: unstable %llu, inverted "
            "%llu, capacity %llu\n",
            steps, dt * 1e3, stats->wall_sum / steps * 1e3, stats->wall_max * 1e3, stats->wall_sum / kEnd,
            stats->max_substeps, stats->max_contact_substeps, (unsigned long long)warnings[SH_WARN_UNSTABLE],
            (unsigned long long)warnings[SH_WARN_INVERTED], (unsigned long long)warnings[SH_WARN_CAPACITY]);
}

int main(int argc, char** argv) {
    const char* integrator_name = argc > 2 ? argv[2] : "symplectic";
    liver_scene_def scene_def;
    liver_scene scene;
    liver_path path;
    sh_tool_id tool;
    force_summary summary;
    step_stats stats;
    uint64_t warnings[SH_WARN_COUNT];
    int exit_code = 1;

    memset(&scene, 0, sizeof scene);
    memset(&summary, 0, sizeof summary);
    summary.touch_z = NAN;
    memset(&stats, 0, sizeof stats);
    stats.max_substeps = stats.max_contact_substeps = 1;
    scene_def.program = "palpation";
    scene_def.mesh_path = argc > 1 ? argv[1] : "../shared/meshes/liver.msh";
    scene_def.table_friction = 0.6;
    scene_def.base_height = 0.0;
    if (choose_integrator(integrator_name, &scene_def) != 0) {
        fprintf(stderr, "usage: palpation [mesh [symplectic|implicit]]\n");
        return 2;
    }

    /* The liver settled on the table, the path across its top, the tool 1 cm above its start. */
    if (liver_scene_create(&scene_def, &scene) != 0) goto done;
    if (liver_scene_find_path(&scene, kToolRadius, kSlide, &path) != 0) goto done;
    if (create_tool(&scene, &path, &tool) != 0) goto done;

    if (palpate(&scene, tool, &path, scene_def.dt, &summary, &stats) != 0) goto done;
    CHECK(sh_world_get_warnings(scene.world, warnings));
    print_summary(&summary, &stats, &path, scene_def.dt, warnings);
    exit_code = 0;

done:
    liver_scene_destroy(&scene);
    return exit_code;
}
