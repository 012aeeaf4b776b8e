/* softhap_bench haptic-error: the Volumetric Buffer Model's force against the full model's
 * static solve, for buffer radii from 1 cm to the whole organ, with the world frozen or coupled
 * (haptic.c describes the study). */
#include "haptic_common.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const double kErrorDepth = 0.008;   /* m */
static const double kErrorDamping = 100.0; /* 1/s: about critical for the organ's lowest mode */
static const double kErrorRadii[] = {0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.1, 1.0}; /* m */
static const double kErrorPressTime = 0.3, kErrorTime = 3.0; /* s */
static const int kErrorTimedTicks = 2000;
static const int kSettleTicks = 500; /* settled: the force's change over the last 0.5 s */
enum { kRadiusCount = sizeof kErrorRadii / sizeof kErrorRadii[0] };
enum { kSimKept = 256 }; /* world step times kept */

/* SOFA's haptic-demo liver and its finer version. */
typedef struct {
    const char* file;
    const char* name;
} liver_file;
static const liver_file kLivers[] = {{"liver.msh", "liver"}, {"liver2.msh", "liver2"}};

/* ------------------------------------------------------------------------------------------ */
/* The reference                                                                                */

typedef struct {
    double touch[3];
} press_path;

/* Down kErrorDepth over kErrorPressTime, then held. */
static void error_pose(const void* ctx, long tick, double out[3]) {
    const press_path* c = (const press_path*)ctx;
    const double s = fmin(1.0, (tick + 1) * kHapticDt / kErrorPressTime);
    out[0] = c->touch[0];
    out[1] = c->touch[1];
    out[2] = c->touch[2] - kErrorDepth * s;
}

/* The reference's JSON line and its summary on stderr. */
static void print_reference(const tissue* liver, const double pressed[3], const double force[3],
                            const sh_contact_state* contact, const sh_static_report* report, double ms) {
    printf("{\"study\":\"haptic_error_reference\",\"mesh\":\"%s\",\"mesh_tets\":%d,\"fixed_nodes\":%d,"
           "\"depth_m\":%g,\"tool\":[%.6g,%.6g,%.6g],\"force\":[%.9g,%.9g,%.9g],\"contact_count\":%d,"
           "\"max_depth_m\":%.4g,\"converged\":%d,\"iterations\":%d,\"residual\":%.3g,\"solve_ms\":%.1f}\n",
           liver->name, liver->tet_count, liver->fixed_count, kErrorDepth, pressed[0], pressed[1], pressed[2],
           force[0], force[1], force[2], contact->contact_count, contact->max_depth, report->converged,
           report->iterations, report->residual, ms);
    fflush(stdout);
    fprintf(stderr, "haptic-error: static solve %.4g N (%s, %d iterations)\n", force[2],
            report->converged ? "converged" : "NOT converged", report->iterations);
}

/* The reference: the full model solved statically with the tool pressed kErrorDepth below
 * touch; the tool's force into force. The tolerance is 1e-7: on liver2 the Newton iteration of
 * the contact potential stalls near 3e-8, and a solve that stops short of its tolerance leaves
 * the state as it was, so the force would read 0. Its line gives the residual reached. */
static void error_reference(const tissue* liver, const double touch[3], double force[3]) {
    scene s = scene_create(liver, SH_MATERIAL_COROTATIONAL, SH_INTEGRATOR_SYMPLECTIC_EULER, 0.0, touch);
    const double pressed[3] = {touch[0], touch[1], touch[2] - kErrorDepth};
    CHECK(sh_tool_set_pose(s.world, s.tool, pressed, kIdentity));
    sh_static_def def;
    sh_static_def_default(&def);
    def.tolerance = 1e-7;
    sh_static_report report;
    const double t0 = now_ns();
    const sh_status st = sh_world_solve_static(s.world, &def, &report);
    const double ms = (now_ns() - t0) * 1e-6;
    if (st != SH_OK && st != SH_ERR_NOT_CONVERGED) CHECK(st);
    double torque[3];
    CHECK(sh_tool_get_wrench(s.world, s.tool, force, torque));
    sh_contact_state contact;
    CHECK(sh_tool_get_contact(s.world, s.tool, &contact));
    print_reference(liver, pressed, force, &contact, &report, ms);
    scene_destroy(&s);
}

/* ------------------------------------------------------------------------------------------ */
/* One radius and mode                                                                          */

/* What a press and hold saw. */
typedef struct {
    tick_log log;     /* the timed hold: the last kErrorTimedTicks ticks */
    tick_log untimed; /* the ticks before it */
    double settle_force[3];   /* raw force kSettleTicks before the end */
    double sim_ns[kSimKept];  /* coupled: world step times */
    int sim_steps, sim_failed;
} error_run;

/* The press and hold of kErrorTime, one tick at a time; coupled: a world step of kSimDt after
 * the tick that reaches each multiple of kSimDt, on this thread, so the run is deterministic. */
static void press_and_hold(sh_haptic* haptic, sh_world* world, int coupled, const press_path* path, error_run* r) {
    const long ticks = (long)lround(kErrorTime / kHapticDt);
    const long timed_from = ticks - kErrorTimedTicks, settle_at = ticks - kSettleTicks;
    tick_log_alloc(&r->log, kErrorTimedTicks);
    memset(&r->untimed, 0, sizeof r->untimed);
    long next_sim = 1; /* world step k after tick ceil(k kSimDt / kHapticDt) */
    for (long i = 0; i < ticks; ++i) {
        tick_log* used = i >= timed_from ? &r->log : &r->untimed;
        run_ticks(haptic, error_pose, path, i, 1, kHapticDt, 0, used);
        if (i + 1 == settle_at)
            for (int k = 0; k < 3; ++k) r->settle_force[k] = used->last.raw_force[k];
        if (coupled && (i + 1) * kHapticDt >= next_sim * kSimDt - 1e-9) {
            const double t0 = now_ns();
            r->sim_failed += world_step(world);
            if (r->sim_steps < kSimKept) r->sim_ns[r->sim_steps] = now_ns() - t0;
            ++r->sim_steps;
            ++next_sim;
        }
    }
}

/* The coupled mode's extra fields: the full model's own tool force and its step time. */
static void print_world_fields(const scene* s, error_run* r, const double reference[3]) {
    double world_force[3], torque[3];
    CHECK(sh_tool_get_wrench(s->world, s->tool, world_force, torque));
    const stats w = summarize(r->sim_ns, r->sim_steps < kSimKept ? r->sim_steps : kSimKept);
    printf(",\"world_force\":[%.9g,%.9g,%.9g],\"world_rel_error\":%.6g,\"sim_steps\":%d,\"sim_failed\":%d,"
           "\"sim_step_median_ms\":%.3f",
           world_force[0], world_force[1], world_force[2], distance3(world_force, reference) / norm3(reference),
           r->sim_steps, r->sim_failed, w.median * 1e-6);
}

/* A case's JSON line (sorts the run's samples) and its summary on stderr. */
static void print_error_case(const char* name, const tissue* liver, double radius, int coupled, const scene* s,
                             const double reference[3], error_run* r) {
    const sh_haptic_output out = r->log.last;
    double diff[3], change[3];
    for (int k = 0; k < 3; ++k) {
        diff[k] = out.raw_force[k] - reference[k];
        change[k] = out.raw_force[k] - r->settle_force[k];
    }
    const double ref = norm3(reference);
    const stats t = summarize(r->log.ns, r->log.timed);
    const stats sub = summarize(r->log.substeps, r->log.timed);
    printf("{\"study\":\"haptic_error\",\"case\":\"%s\",\"mode\":\"%s\",\"mesh\":\"%s\",\"radius_m\":%g,"
           "\"buffer_tets\":%d,\"buffer_nodes\":%d,\"mesh_tets\":%d,\"depth_m\":%g,\"force\":[%.9g,%.9g,%.9g],"
           "\"reference\":[%.9g,%.9g,%.9g],\"rel_error\":%.6g,\"rel_error_normal\":%.6g,\"settle_change\":%.3g,",
           name, coupled ? "coupled" : "frozen", liver->name, radius, out.buffer_tets, out.buffer_nodes,
           liver->tet_count, kErrorDepth, out.raw_force[0], out.raw_force[1], out.raw_force[2], reference[0],
           reference[1], reference[2], norm3(diff) / ref, diff[2] / reference[2], norm3(change) / ref);
    print_times_us("", &t);
    printf(",\"substeps_median\":%g,\"substeps_max\":%g,\"steps\":%d,\"contact\":%d,\"faults\":%u", sub.median,
           sub.max, t.count, out.contact, r->log.faults | r->untimed.faults);
    if (coupled) print_world_fields(s, r, reference);
    printf("}\n");
    fflush(stdout);
    fprintf(stderr, "%s: %d tets, %.4g N against %.4g N (error %.3g), median %.2f us\n", name, out.buffer_tets,
            out.raw_force[2], reference[2], norm3(diff) / ref, t.median * 1e-3);
}

/* The case's name, which FILTER matches. */
static void error_case_name(char* name, size_t size, const char* mesh, int coupled, double radius) {
    snprintf(name, size, "haptic-error/%s/%s/r%.3f", mesh, coupled ? "coupled" : "frozen", radius);
}

/* One buffer radius in one mode: a fresh scene, the press and hold, the comparison. */
static void error_case(const tissue* liver, const double touch[3], const double reference[3], double radius,
                       int coupled, const haptic_options* options) {
    char name[128];
    error_case_name(name, sizeof name, liver->name, coupled, radius);
    if (!name_matches(name, options->filter)) return;
    press_path path;
    memcpy(path.touch, touch, sizeof path.touch);
    scene s = scene_create(liver, SH_MATERIAL_COROTATIONAL,
                           coupled ? SH_INTEGRATOR_IMPLICIT_EULER : SH_INTEGRATOR_SYMPLECTIC_EULER, kErrorDamping,
                           touch);
    const sh_haptic_def def = haptic_def_for(&s, radius, liver->tet_count, 1);
    sh_haptic* haptic = NULL;
    CHECK(sh_haptic_create(s.world, &def, &haptic));
    error_run r;
    memset(&r, 0, sizeof r);
    press_and_hold(haptic, s.world, coupled, &path, &r);
    print_error_case(name, liver, radius, coupled, &s, reference, &r);
    tick_log_free(&r.log);
    CHECK(sh_haptic_destroy(haptic));
    scene_destroy(&s);
}

/* ------------------------------------------------------------------------------------------ */

/* 1 if FILTER keeps any case on the mesh named name (so that an unwanted mesh is not loaded). */
static int any_case_wanted(const char* name, const haptic_options* options) {
    int wanted = 0;
    for (int coupled = 0; coupled < 2; ++coupled)
        for (int r = 0; r < kRadiusCount; ++r) {
            char case_name[128];
            error_case_name(case_name, sizeof case_name, name, coupled, kErrorRadii[r]);
            wanted |= name_matches(case_name, options->filter);
        }
    return wanted;
}

/* Per liver: the reference, then every radius frozen, then coupled. */
int haptic_run_error(const haptic_options* options) {
    for (size_t m = 0; m < sizeof kLivers / sizeof kLivers[0]; ++m) {
        if (!any_case_wanted(kLivers[m].name, options)) continue;
        tissue liver;
        if (!make_liver(&liver, options->mesh_dir, kLivers[m].file, kLivers[m].name)) return 1;
        double touch[3], reference[3];
        touch_point(&liver, touch);
        fprintf(stderr, "haptic-error: %s %d tets, %d fixed nodes; press at (%.4f, %.4f), touching height %.4f m\n",
                liver.name, liver.tet_count, liver.fixed_count, touch[0], touch[1], touch[2]);
        error_reference(&liver, touch, reference);
        for (int coupled = 0; coupled < 2; ++coupled)
            for (int r = 0; r < kRadiusCount; ++r)
                error_case(&liver, touch, reference, kErrorRadii[r], coupled, options);
        tissue_free(&liver);
    }
    return 0;
}
