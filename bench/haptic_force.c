/* softhap_bench haptic-force: the smoothness of the rendered force along a press and slide on
 * liver2, the VBM against a zero-order hold of the full model (haptic.c describes the study). */
#include "haptic_common.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* liver2, whose finer top keeps a sliding sphere in contact (on liver.msh's 2-3 cm facets it
 * loses its support where it straddles an edge between two facets). */
static const char* const kTraceFile = "liver2.msh";
static const char* const kTraceName = "liver2";
static const double kTraceDamping = 2.0; /* 1/s */
static const double kTraceRadius = 0.03; /* m */
static const double kTraceGap = 0.005, kTraceDepth = 0.008; /* m */
static const double kApproachEnd = 0.3, kPressEnd = 0.8, kSlideStart = 1.0, kSlideEnd = 2.5, kLiftStart = 2.7,
                    kLiftEnd = 3.2, kTraceEnd = 3.5; /* s */
enum { kSimKept = 512 }; /* world step times kept */

/* ------------------------------------------------------------------------------------------ */
/* The trajectory                                                                               */

typedef struct {
    double start[2], direction[2];
    double heights[kPathSamples]; /* touching height of the tool's centre along the slide */
} slide_path;

/* Smooth 0 -> 1 over [0, 1] with zero slope at both ends, so that the trajectory has no jump in
 * velocity for the force to show. */
static double ease(double s) {
    const double c = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
    return 0.5 - 0.5 * cos(kPi * c);
}

/* The slide from the liver's press point in its slide direction, with the touching height
 * sampled along it. */
static slide_path make_slide_path(const tissue* t) {
    slide_path p;
    for (int k = 0; k < 2; ++k) {
        p.start[k] = t->press[k];
        p.direction[k] = t->slide[k];
    }
    for (int s = 0; s < kPathSamples; ++s) {
        const double along = kTraceSlide * s / (kPathSamples - 1);
        p.heights[s] = touch_height(t, p.start[0] + along * p.direction[0], p.start[1] + along * p.direction[1]);
    }
    return p;
}

/* The trajectory at tick i (time (i + 1) kHapticDt), as haptic.c describes it: the depth below
 * the touching height and the distance slid follow their own schedules. */
static void trace_pose(const void* ctx, long tick, double out[3]) {
    const slide_path* p = (const slide_path*)ctx;
    const double t = (tick + 1) * kHapticDt;
    double below;
    if (t < kApproachEnd)
        below = -kTraceGap * (1.0 - ease(t / kApproachEnd));
    else if (t < kLiftStart)
        below = kTraceDepth * ease((t - kApproachEnd) / (kPressEnd - kApproachEnd));
    else
        below = kTraceDepth - (kTraceDepth + kTraceGap) * ease((t - kLiftStart) / (kLiftEnd - kLiftStart));
    const double slide = ease((t - kSlideStart) / (kSlideEnd - kSlideStart));
    const double s = slide * (kPathSamples - 1);
    int k = (int)s;
    if (k > kPathSamples - 2) k = kPathSamples - 2;
    const double h = p->heights[k] + (s - k) * (p->heights[k + 1] - p->heights[k]);
    out[0] = p->start[0] + slide * kTraceSlide * p->direction[0];
    out[1] = p->start[1] + slide * kTraceSlide * p->direction[1];
    out[2] = h - below;
}

/* ------------------------------------------------------------------------------------------ */
/* The run                                                                                      */

/* Per tick: the tool's pose, the three force signals (3 per tick) and the haptic output. */
typedef struct {
    long ticks;
    double *pos, *vbm, *raw, *zoh;
    int32_t *tets, *substeps, *contact;
    tick_log log;
    double sim_ns[kSimKept]; /* world step times */
    int sim_steps, sim_failed;
} trace;

/* A trace with room for ticks ticks. */
static void trace_alloc(trace* tr, long ticks) {
    tr->ticks = ticks;
    tr->pos = (double*)xmalloc(sizeof(double) * 3 * (size_t)ticks);
    tr->vbm = (double*)xmalloc(sizeof(double) * 3 * (size_t)ticks);
    tr->raw = (double*)xmalloc(sizeof(double) * 3 * (size_t)ticks);
    tr->zoh = (double*)xmalloc(sizeof(double) * 3 * (size_t)ticks);
    tr->tets = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)ticks);
    tr->substeps = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)ticks);
    tr->contact = (int32_t*)xmalloc(sizeof(int32_t) * (size_t)ticks);
    tr->sim_steps = tr->sim_failed = 0;
    tick_log_alloc(&tr->log, (int)ticks);
}

/* Frees what trace_alloc allocated. */
static void trace_free(trace* tr) {
    free(tr->pos);
    free(tr->vbm);
    free(tr->raw);
    free(tr->zoh);
    free(tr->tets);
    free(tr->substeps);
    free(tr->contact);
    tick_log_free(&tr->log);
}

/* Keeps tick i's pose and haptic output in the trace. */
static void record_tick(trace* tr, const slide_path* path, long i) {
    const sh_haptic_output* out = &tr->log.last;
    trace_pose(path, i, &tr->pos[3 * i]);
    for (int k = 0; k < 3; ++k) {
        tr->vbm[3 * i + k] = out->force[k];
        tr->raw[3 * i + k] = out->raw_force[k];
    }
    tr->tets[i] = out->buffer_tets;
    tr->substeps[i] = out->substeps;
    tr->contact[i] = out->contact;
}

/* One thread, deterministic: a haptic tick every kHapticDt of haptic time and a world step after
 * the tick that reaches each multiple of kSimDt; the full model's force after each world step is
 * held until the next (the ZOH). */
static void run_trace(sh_haptic* haptic, const scene* s, const slide_path* path, trace* tr) {
    double held[3] = {0.0, 0.0, 0.0};
    long next_sim = 1;
    for (long i = 0; i < tr->ticks; ++i) {
        run_ticks(haptic, trace_pose, path, i, 1, kHapticDt, 0, &tr->log);
        record_tick(tr, path, i);
        if ((i + 1) * kHapticDt >= next_sim * kSimDt - 1e-9) {
            const double t0 = now_ns();
            tr->sim_failed += world_step(s->world);
            if (tr->sim_steps < kSimKept) tr->sim_ns[tr->sim_steps] = now_ns() - t0;
            ++tr->sim_steps;
            ++next_sim;
            double torque[3];
            CHECK(sh_tool_get_wrench(s->world, s->tool, held, torque));
        }
        for (int k = 0; k < 3; ++k) tr->zoh[3 * i + k] = held[k];
    }
}

/* ------------------------------------------------------------------------------------------ */
/* The output                                                                                   */

/* The per-tick trace as CSV at path (before the step times are sorted). 0 if it cannot be
 * written. */
static int write_trace_csv(const char* path, const trace* tr) {
    FILE* f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "softhap_bench: cannot write %s\n", path);
        return 0;
    }
    fprintf(f, "t,tool_x,tool_y,tool_z,vbm_x,vbm_y,vbm_z,raw_x,raw_y,raw_z,zoh_x,zoh_y,zoh_z,buffer_tets,"
               "substeps,contact,step_us\n");
    for (long i = 0; i < tr->ticks; ++i) {
        const double *p = &tr->pos[3 * i], *v = &tr->vbm[3 * i], *r = &tr->raw[3 * i], *z = &tr->zoh[3 * i];
        fprintf(f, "%.4f,%.6f,%.6f,%.6f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%d,%d,%.2f\n",
                (i + 1) * kHapticDt, p[0], p[1], p[2], v[0], v[1], v[2], r[0], r[1], r[2], z[0], z[1], z[2],
                tr->tets[i], tr->substeps[i], tr->contact[i], tr->log.ns[i] * 1e-3);
    }
    fclose(f);
    return 1;
}

/* Max and RMS of |F(i) - F(i-1)| over ticks [begin, end) of f (3 per tick). */
static void force_steps(const double* f, long begin, long end, double* max, double* rms) {
    double sum = 0.0;
    *max = 0.0;
    long n = 0;
    for (long i = begin > 0 ? begin : 1; i < end; ++i, ++n) {
        const double d = distance3(&f[3 * i], &f[3 * (i - 1)]);
        if (d > *max) *max = d;
        sum += d * d;
    }
    *rms = n > 0 ? sqrt(sum / n) : 0.0;
}

/* Per signal (VBM rendered, VBM raw, ZOH): its steps over the run and over the slide, and its
 * peak; a JSON line each and a summary on stderr. */
static void print_smoothness(const trace* tr) {
    const long slide_begin = (long)lround(kSlideStart / kHapticDt), slide_end = (long)lround(kSlideEnd / kHapticDt);
    static const char* const kSignals[] = {"vbm", "vbm_raw", "zoh"};
    const double* signals[] = {tr->vbm, tr->raw, tr->zoh};
    for (int k = 0; k < 3; ++k) {
        double max_all, rms_all, max_slide, rms_slide, peak = 0.0;
        force_steps(signals[k], 0, tr->ticks, &max_all, &rms_all);
        force_steps(signals[k], slide_begin, slide_end, &max_slide, &rms_slide);
        for (long i = 0; i < tr->ticks; ++i)
            if (norm3(&signals[k][3 * i]) > peak) peak = norm3(&signals[k][3 * i]);
        printf("{\"study\":\"haptic_force\",\"signal\":\"%s\",\"max_dF_N\":%.6g,\"rms_dF_N\":%.6g,"
               "\"max_dF_slide_N\":%.6g,\"rms_dF_slide_N\":%.6g,\"peak_N\":%.6g,\"ticks\":%ld}\n",
               kSignals[k], max_all, rms_all, max_slide, rms_slide, peak, tr->ticks);
        fprintf(stderr, "haptic-force %s: max |dF| %.4g N, RMS |dF| %.4g N per tick (slide: %.4g, %.4g), peak %.4g N\n",
                kSignals[k], max_all, rms_all, max_slide, rms_slide, peak);
    }
}

/* The run's JSON line: the set-up, the buffer, contact and the step times (sorts them, so it
 * comes after the CSV). */
static void print_force_run(const tissue* liver, const slide_path* path, trace* tr, const char* csv) {
    const stats t = summarize(tr->log.ns, tr->log.timed);
    const stats w = summarize(tr->sim_ns, tr->sim_steps < kSimKept ? tr->sim_steps : kSimKept);
    long tet_sum = 0, in_contact = 0;
    for (long i = 0; i < tr->ticks; ++i) {
        tet_sum += tr->tets[i];
        in_contact += tr->contact[i];
    }
    printf("{\"study\":\"haptic_force_run\",\"mesh\":\"%s\",\"radius_m\":%g,\"ticks\":%ld,\"sim_steps\":%d,"
           "\"slide\":[%.4f,%.4f],\"press\":[%.5f,%.5f],\"mean_buffer_tets\":%.1f,\"contact_ticks\":%ld,",
           liver->name, kTraceRadius, tr->ticks, tr->sim_steps, path->direction[0], path->direction[1],
           path->start[0], path->start[1], (double)tet_sum / tr->ticks, in_contact);
    print_times_us("", &t);
    printf(",\"sim_step_median_ms\":%.3f,\"sim_step_max_ms\":%.3f,\"sim_failed\":%d,\"allocations\":%ld,\"faults\":%u,"
           "\"csv\":\"%s\"}\n",
           w.median * 1e-6, w.max * 1e-6, tr->sim_failed, tr->log.allocations, tr->log.faults, csv ? csv : "");
    fflush(stdout);
}

/* ------------------------------------------------------------------------------------------ */

/* The press and slide on liver2 with the default force limits (10 N, 2000 N/s, 50 ms ramp). */
int haptic_run_force(const haptic_options* options) {
    tissue liver;
    if (!make_liver(&liver, options->mesh_dir, kTraceFile, kTraceName)) return 1;
    const slide_path path = make_slide_path(&liver);
    double start[3];
    trace_pose(&path, -1, start);
    scene s = scene_create(&liver, SH_MATERIAL_COROTATIONAL, SH_INTEGRATOR_IMPLICIT_EULER, kTraceDamping, start);
    sh_haptic_def def = haptic_def_for(&s, kTraceRadius, 2000, 0);
    def.stale_after = 0.1; /* the default: the world steps every 1/60 s here */
    sh_haptic* haptic = NULL;
    CHECK(sh_haptic_create(s.world, &def, &haptic));
    trace tr;
    trace_alloc(&tr, lround(kTraceEnd / kHapticDt));
    run_trace(haptic, &s, &path, &tr);
    if (options->csv && !write_trace_csv(options->csv, &tr)) return 1;
    print_smoothness(&tr);
    print_force_run(&liver, &path, &tr, options->csv);
    trace_free(&tr);
    CHECK(sh_haptic_destroy(haptic));
    scene_destroy(&s);
    tissue_free(&liver);
    return 0;
}
