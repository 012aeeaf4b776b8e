/* cutting.c: a scalpel draws an incision across the top of a liver lying on a table; .vtu
 * frames of the cut liver go to frames/cutting_NNN.vtu and a trace (CSV) to stdout.
 *
 *   cutting [mesh]   (default: ../shared/meshes/liver.msh)
 *
 * `make cutting` runs it from the repository root (a few seconds on one core).
 *
 * The scene (liver_scene.h): SOFA's haptic-demo liver scaled to 16 cm, corotational,
 * E = 15 kPa, settled on a table under gravity, stepped with implicit Euler at 60 Hz.
 *
 * The scalpel: a thin capsule (radius 0.5 mm) standing upright, whose blade edge is the
 * segment from its tip up 3 cm (tool frame). It comes down 2.5 cm into the tissue at the start
 * of a path across the top (the path liver_scene_find_path picks), draws 5 cm along it, and
 * lifts out. At every step the blade's swept surface cuts the liver (sh_tool_set_cutting),
 * refined to kResolution around the blade.
 *
 * Trace columns: t (s), the tool's reaction force fx, fy, fz (N), faces the step cut, the
 * step's topology time (ms) and wall time (ms), node and tet counts. A summary goes to stderr. */
#include "liver_scene.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const char* kProgram = "cutting";
static const double kDepth = 0.025;     /* m below the touching height */
static const double kLength = 0.05;     /* m along the path */
static const double kDt = 1.0 / 60.0;   /* s */
/* m: the edge length the cut refines the liver to around the blade. This liver's elements are
 * 2.2 cm on average; the default (a quarter of the 3 cm blade, 7.5 mm) follows the blade more
 * closely but triples the tet count along a 5 cm incision and the step's cost with it (README,
 * "Cutting"). */
static const double kResolution = 0.015;

/* Where the scalpel's tip is at time t: down over 0.5 s, along the path over 2 s, up over
 * 0.5 s. */
static void scalpel_tip(const liver_path* path, double t, double out[3]) {
    const double down = liver_ease(liver_progress(t, 0.0, 0.5));
    const double along = liver_ease(liver_progress(t, 0.5, 2.5));
    const double up = liver_ease(liver_progress(t, 2.5, 3.0));
    liver_path_point(path, along, (down - up) * kDepth - 0.01 * (1.0 - down + up), out);
}

/* Makes the scalpel: a capsule along z with its blade from the tip up 3 cm. Its contact law is
 * 2e3 N/m^1.5, not the default 1e4: a thin rounded tool softens the nodes it pushes sideways
 * by up to stiffness * sqrt(radius) (22 N/m here, 224 with 1e4), which must stay well below
 * the liver's own stiffness at a node, E h = 15 kPa x 15 mm = 225 N/m, for implicit Euler to
 * converge without creeping (README, Limits). */
static int create_scalpel(const liver_scene* scene, const liver_path* path, sh_tool_id* out) {
    sh_collider_def def;
    sh_collider_def_default(&def);
    def.shape.kind = SH_SHAPE_CAPSULE;
    def.shape.radius = 0.0005;
    def.shape.half_length = 0.015;
    def.contact.stiffness = 2e3;
    scalpel_tip(path, 0.0, def.position);
    def.position[2] += 0.015; /* the capsule's centre is 1.5 cm above the tip */
    sh_cut_def cut;
    sh_cut_def_default(&cut);
    cut.edge[0][2] = -0.015;
    cut.edge[1][2] = 0.015;
    cut.resolution = kResolution;
    if (example_failed(kProgram, "sh_tool_create", sh_tool_create(scene->world, &def, out))) return 1;
    return example_failed(kProgram, "sh_tool_set_cutting", sh_tool_set_cutting(scene->world, *out, &cut));
}

/* Writes frame number k of the liver. */
static int write_frame(const liver_scene* scene, int k) {
    char path[64];
    snprintf(path, sizeof path, "frames/cutting_%03d.vtu", k);
    return example_failed(kProgram, "sh_body_write_vtu", sh_body_write_vtu(scene->world, scene->body, path));
}

/* Runs the incision, printing the trace; returns 0 on success. */
static int incise(liver_scene* scene, sh_tool_id tool, const liver_path* path) {
    int cut_faces = 0, steps = 0, tets_after = 0;
    double topology_ms = 0.0, wall_ms = 0.0;
    printf("t,fx,fy,fz,cut_faces,topology_ms,wall_ms,nodes,tets\n");
    for (int k = 0; k * kDt <= 3.2; ++k, ++steps) {
        double tip[3], force[3], torque[3];
        const double identity[4] = {1.0, 0.0, 0.0, 0.0};
        scalpel_tip(path, (k + 1) * kDt, tip);
        tip[2] += 0.015;
        if (example_failed(kProgram, "sh_tool_set_pose", sh_tool_set_pose(scene->world, tool, tip, identity))) return 1;
        sh_step_report report;
        if (example_failed(kProgram, "sh_world_step", sh_world_step(scene->world, kDt, &report))) return 1;
        if (example_failed(kProgram, "sh_tool_get_wrench", sh_tool_get_wrench(scene->world, tool, force, torque))) return 1;
        sh_body_info info;
        if (example_failed(kProgram, "sh_body_get_info", sh_body_get_info(scene->world, scene->body, &info))) return 1;
        printf("%.4f,%.5f,%.5f,%.5f,%d,%.3f,%.3f,%d,%d\n", (k + 1) * kDt, force[0], force[1], force[2], report.cut_faces,
               1e3 * report.topology_seconds, 1e3 * report.wall_seconds, info.node_count, info.element_count);
        cut_faces += report.cut_faces;
        tets_after = info.element_count;
        topology_ms += 1e3 * report.topology_seconds;
        wall_ms += 1e3 * report.wall_seconds;
        if (k % 12 == 0 && write_frame(scene, k / 12) != 0) return 1;
    }
    fprintf(stderr, "%s: %d steps of %.1f ms: %d faces cut, topology %.2f ms and step %.2f ms per step on average\n",
            kProgram, steps, 1e3 * kDt, cut_faces, topology_ms / steps, wall_ms / steps);
    fprintf(stderr, "%s: liver of %d tets after the incision\n", kProgram, tets_after);
    return 0;
}

int main(int argc, char** argv) {
    liver_scene_def scene_def;
    liver_scene scene;
    liver_path path;
    sh_tool_id tool;
    int exit_code = 1;
    memset(&scene, 0, sizeof scene);
    scene_def.program = kProgram;
    scene_def.mesh_path = argc > 1 ? argv[1] : "../shared/meshes/liver.msh";
    scene_def.integrator = SH_INTEGRATOR_IMPLICIT_EULER;
    scene_def.dt = kDt;
    scene_def.table_friction = 0.6;
    scene_def.base_height = 0.0;
    if (liver_scene_create(&scene_def, &scene) != 0) goto done;
    if (liver_scene_find_path(&scene, 0.0005, kLength, &path) != 0) goto done;
    if (create_scalpel(&scene, &path, &tool) != 0) goto done;
    fprintf(stderr, "%s: liver of %d tets before the incision, cut at a resolution of %.1f mm\n", kProgram,
            scene.tet_count, 1e3 * kResolution);
    exit_code = incise(&scene, tool, &path);
done:
    liver_scene_destroy(&scene);
    return exit_code;
}
