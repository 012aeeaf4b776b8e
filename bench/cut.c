/*
 * softhap_bench cut: the time of one sh_body_cut against body size and cut length, and the time
 * of the first implicit step after a cut (the solver analyses the new sparsity pattern) against
 * a step without one. One JSON line per case on stdout, progress on stderr.
 *
 *   softhap_bench cut [FILTER] [--reps N] [--factor-reuse X] [--meshes DIR]
 *
 * FILTER keeps the cases whose name, cut/<mesh>/<kind>, contains it. --reps N: repetitions of
 * each single cut (default kReps, fewer once a case has run kCaseSeconds, at least kMinReps).
 * --factor-reuse X: the implicit settings' factor_reuse (default 0; the library's default, 0.25,
 * lets a body at rest skip factorising, so that a step without a cut costs almost nothing).
 *
 * Meshes: liver2.msh scaled by 0.1 (as palpation), Armadillo_Tetra_4406.vtu and
 * raptorTetra_19409.vtu scaled to a largest extent of 0.15 m (as the step benches). Each is one
 * FEM body (StVK, E = 30 kPa, nu = 0.45, rho = 1000 kg/m^3; implicit Euler, dt = 1/60 s, by
 * default a fresh factorisation at every step, so that a step after a cut differs from one
 * without only by what the cut costs the solver: the new pattern's analysis), gravity off (at rest: the step's cost is the
 * solver's, not a swing's), its lowest tenth fixed; kWarmSteps steps (the first builds the
 * solver), then kPlainSteps timed steps before the first cut. The cut surface is a blade
 * (cut_scene.c): a plane across the box's shortest axis at 0.47 of it, run along the longest,
 * reaching past the box along the third.
 * - single-<f>: one cut of the blade from one element before the box to fraction f of the way
 *   through it (0.25, 0.5, 1; 1 cuts the body in two), on a fresh body each repetition, then two
 *   steps;
 * - blade-<n>: the whole blade in increments of n mean edge lengths, each quad continuing the
 *   last, as a blade advances; the two steps after each of the first kBladeSteps cuts that change
 *   the topology.
 * Per case: the cut's time from sh_cut_report.seconds and the wall time around the call
 * (median, p99; s), tets and nodes added per cut (median, and in all), the lowest piece
 * quality; for the steps without a cut before ("plain"), the first after a cut that changed the
 * topology ("after_cut") and the second after it: their count, time and factorisation time
 * (median, p99; s), factorisations and Newton iterations per step and the most sub-steps; the
 * first after-cut step's median over the plain one's; steps that did not return SH_OK; the
 * 1-minute load average (other processes slow every time).
 *
 * Public API only; C99 plus POSIX clocks.
 */
#define _POSIX_C_SOURCE 200809L
#include "cut.h"

#include "bench_util.h"
#include "cut_scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double kDt = 1.0 / 60.0;    /* s: a host's sim thread at 60 Hz */
static const double kCaseSeconds = 4.0;  /* repetitions of a single cut stop past this */
static double g_factor_reuse = 0.0;      /* --factor-reuse */
enum { kReps = 10, kMinReps = 3, kWarmSteps = 1, kPlainSteps = 2, kBladeSteps = 4 };

/* A case: a single cut of the blade fraction of the way through the box (elements 0), or the
 * whole blade in increments of `elements` mean edge lengths. */
typedef struct {
    double fraction;
    int elements;
} cut_case;

static const cut_case kCases[] = {{0.25, 0}, {0.5, 0}, {1.0, 0}, {1.0, 1}, {1.0, 4}};

/* A mesh of the study: its file, name and scaling (cut_mesh_load). */
typedef struct {
    const char* file;
    const char* name;
    double scale, size;
} cut_mesh_file;

static const cut_mesh_file kMeshes[] = {{"liver2.msh", "liver2", 0.1, 0.0},
                                        {"Armadillo_Tetra_4406.vtu", "Armadillo_Tetra_4406", 0.0, 0.15},
                                        {"raptorTetra_19409.vtu", "raptorTetra_19409", 0.0, 0.15}};

/* Samples of one kind of step: wall time and factorisation time (s) per step, and totals. */
typedef struct {
    double *wall, *factor;
    int count, substeps_max;
    long factorizations, newton;
} step_samples;

/* Samples of one case; every array has room for as many values as samples_make was given. */
typedef struct {
    int cuts;
    double *cut, *wall, *tets, *nodes; /* per cut: report.seconds, wall (s), tets and nodes added */
    step_samples plain;                /* steps without a cut just before */
    step_samples after, second;        /* the first and second step after a cut that changed the topology */
    long tets_total, nodes_total;
    double min_quality;
    int failed;
} cut_samples;

/* Empty samples with room for capacity values per array. */
static cut_samples samples_make(int capacity) {
    cut_samples s;
    memset(&s, 0, sizeof s);
    double** arrays[] = {&s.cut,         &s.wall,         &s.tets,      &s.nodes,       &s.plain.wall,
                         &s.plain.factor, &s.after.wall, &s.after.factor, &s.second.wall, &s.second.factor};
    for (size_t k = 0; k < sizeof arrays / sizeof arrays[0]; ++k) *arrays[k] = (double*)xmalloc(sizeof(double) * (size_t)capacity);
    s.min_quality = 1.0;
    return s;
}

/* Frees the arrays of s. */
static void samples_free(cut_samples* s) {
    double* arrays[] = {s->cut,         s->wall,         s->tets,      s->nodes,       s->plain.wall,
                        s->plain.factor, s->after.wall, s->after.factor, s->second.wall, s->second.factor};
    for (size_t k = 0; k < sizeof arrays / sizeof arrays[0]; ++k) free(arrays[k]);
}

/* Adds cut t to s; returns 1 if it changed the topology. */
static int add_cut(cut_samples* s, const timed_cut* t) {
    s->cut[s->cuts] = t->report.seconds;
    s->wall[s->cuts] = t->wall;
    s->tets[s->cuts] = t->report.tets_added;
    s->nodes[s->cuts] = t->report.nodes_added;
    ++s->cuts;
    s->tets_total += t->report.tets_added;
    s->nodes_total += t->report.nodes_added;
    if (t->report.min_quality < s->min_quality) s->min_quality = t->report.min_quality;
    return t->report.tets_added != 0 || t->report.nodes_added != 0;
}

/* One step of world, timed into into (failures counted in *failed). */
static void timed_step(sh_world* world, step_samples* into, int* failed) {
    sh_step_report r;
    into->wall[into->count] = step_timed(world, kDt, &r, failed);
    into->factor[into->count++] = r.factorize_seconds;
    into->factorizations += r.factorizations;
    into->newton += r.newton_iterations;
    if (r.substeps > into->substeps_max) into->substeps_max = r.substeps;
}

/* The two steps after a cut that changed the topology, timed into s. */
static void steps_after_cut(sh_world* world, cut_samples* s) {
    timed_step(world, &s->after, &s->failed);
    timed_step(world, &s->second, &s->failed);
}

/* A fresh world holding m's body, past its warm-up and plain steps (timed into s). */
static sh_world* warm_world(const cut_mesh* m, sh_body_id* body, cut_samples* s) {
    sh_world* world = cut_world(m, g_factor_reuse, body);
    sh_step_report r;
    for (int i = 0; i < kWarmSteps; ++i) step_timed(world, kDt, &r, &s->failed);
    for (int i = 0; i < kPlainSteps; ++i) timed_step(world, &s->plain, &s->failed);
    return world;
}

/* One repetition of single-<fraction>: a fresh body, the cut, the steps after it. */
static void single_rep(const cut_mesh* m, double fraction, cut_samples* s) {
    sh_body_id body;
    sh_world* world = warm_world(m, &body, s);
    double tris[18];
    blade_quad(m, blade_at(m, 0.0), blade_at(m, fraction), tris);
    const timed_cut t = cut_timed(world, body, tris, 2);
    if (add_cut(s, &t))
        steps_after_cut(world, s);
    else
        fprintf(stderr, "softhap_bench cut: %s: the single cut missed the body\n", m->name);
    CHECK(sh_world_destroy(world));
}

/* The blade in increments of `elements` mean edges on one fresh body; after each of the first
 * kBladeSteps cuts that change the topology, the two steps after it (a cut per frame; the rest
 * of the blade is only cut, to keep the case short). */
static void blade_run(const cut_mesh* m, int elements, cut_samples* s) {
    sh_body_id body;
    sh_world* world = warm_world(m, &body, s);
    const double start = blade_at(m, 0.0), end = blade_at(m, 1.0), increment = elements * m->edge;
    for (int k = 0; k < blade_increments(m, elements); ++k) {
        double tris[18];
        blade_quad(m, start + k * increment, fmin(start + (k + 1) * increment, end), tris);
        const timed_cut t = cut_timed(world, body, tris, 2);
        if (add_cut(s, &t) && s->after.count < kBladeSteps) steps_after_cut(world, s);
    }
    CHECK(sh_world_destroy(world));
}

/* Median and p99 of v[0..n) (sorted here) as JSON fields key_median_s and key_p99_s. */
static void print_quantiles(const char* key, double* v, int n) {
    const stats st = summarize(v, n);
    printf(",\"%s_median_s\":%.6g,\"%s_p99_s\":%.6g", key, st.median, key, st.p99);
}

/* The JSON fields of one kind of step, named after key: wall and factorisation time, and per step
 * factorisations and Newton iterations, the most sub-steps. */
static void print_steps(const char* key, step_samples* s) {
    char name[64];
    printf(",\"%s_steps\":%d", key, s->count);
    snprintf(name, sizeof name, "%s_step", key);
    print_quantiles(name, s->wall, s->count);
    snprintf(name, sizeof name, "%s_factorize", key);
    print_quantiles(name, s->factor, s->count);
    const double n = s->count > 0 ? s->count : 1;
    printf(",\"%s_factorizations_per_step\":%.3g,\"%s_newton_per_step\":%.3g,\"%s_substeps_max\":%d", key,
           s->factorizations / n, key, s->newton / n, key, s->substeps_max);
}

/* Case c's JSON line. */
static void print_case(const char* name, const cut_mesh* m, const cut_case* c, cut_samples* s) {
    printf("{\"case\":\"%s\",\"mesh\":\"%s\",\"tets\":%d,\"nodes\":%d,\"cut\":\"%s\",\"length_m\":%.4g,"
           "\"increment_m\":%.4g,\"factor_reuse\":%g,\"cuts\":%d",
           name, m->name, m->tet_count, m->node_count, c->elements ? "blade" : "single",
           blade_at(m, c->fraction) - blade_at(m, 0.0), c->elements * m->edge, g_factor_reuse, s->cuts);
    print_quantiles("cut", s->cut, s->cuts);
    print_quantiles("wall", s->wall, s->cuts);
    const stats tets = summarize(s->tets, s->cuts), nodes = summarize(s->nodes, s->cuts);
    printf(",\"tets_added\":%g,\"nodes_added\":%g,\"tets_added_total\":%ld,\"nodes_added_total\":%ld,\"min_quality\":%.4g",
           tets.median, nodes.median, s->tets_total, s->nodes_total, s->min_quality);
    print_steps("plain", &s->plain); /* sorts the step samples */
    print_steps("after_cut", &s->after);
    print_steps("second_after_cut", &s->second);
    const double ratio = s->after.count && s->plain.count
                             ? median(s->after.wall, s->after.count) / median(s->plain.wall, s->plain.count)
                             : 0.0;
    printf(",\"after_cut_over_plain\":%.3g,\"failed_steps\":%d,\"load_average\":%.2f}\n", ratio, s->failed,
           bench_load_average(-1.0));
    fflush(stdout);
}

/* The name of case c of mesh into name (room for size bytes): cut/<mesh>/single-<fraction> or
 * cut/<mesh>/blade-<elements>. */
static void case_name(const char* mesh, const cut_case* c, char* name, size_t size) {
    if (c->elements)
        snprintf(name, size, "cut/%s/blade-%d", mesh, c->elements);
    else
        snprintf(name, size, "cut/%s/single-%g", mesh, c->fraction);
}

/* 1 if filter keeps a case of mesh. */
static int mesh_wanted(const char* mesh, const char* filter) {
    char name[256];
    for (size_t k = 0; k < sizeof kCases / sizeof kCases[0]; ++k) {
        case_name(mesh, &kCases[k], name, sizeof name);
        if (name_matches(name, filter)) return 1;
    }
    return 0;
}

/* Case c on mesh m: reps repetitions of a single cut (0: kReps, fewer past kCaseSeconds), or
 * one blade; its JSON line. */
static void run_case(const cut_mesh* m, const cut_case* c, const char* name, int reps) {
    const int count = reps > 0 ? reps : kReps;
    cut_samples s = samples_make(c->elements ? blade_increments(m, c->elements) + kPlainSteps : kPlainSteps * count);
    if (c->elements) {
        blade_run(m, c->elements, &s);
    } else {
        const double start = now_ns();
        for (int r = 0; r < count; ++r) {
            single_rep(m, c->fraction, &s);
            if (reps <= 0 && r + 1 >= kMinReps && (now_ns() - start) * 1e-9 > kCaseSeconds) break;
        }
    }
    print_case(name, m, c, &s);
    samples_free(&s);
}

/* The subcommand's usage on stderr. */
static void usage(void) {
    fprintf(stderr, "usage: softhap_bench cut [FILTER] [--reps N] [--factor-reuse X] [--meshes DIR]\n"
                    "  FILTER  keep the cases whose name contains it (cut/<mesh>/single-<f>, cut/<mesh>/blade-<n>)\n"
                    "  --reps N  repetitions of each single cut (default %d, fewer past %g s a case)\n"
                    "  --factor-reuse X  the implicit body's factor_reuse, in [0, 1) (default 0: factorise every step)\n"
                    "  --meshes DIR  mesh folder holding liver2.msh and the .vtu meshes\n",
                    kReps, kCaseSeconds);
}

/* The command line, then every mesh's cases. */
int run_cut(int argc, char** argv) {
    const char* filter = NULL;
    const char* given_dir = NULL;
    int reps = 0;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--meshes") == 0 && i + 1 < argc) {
            given_dir = argv[++i];
        } else if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc && (reps = atoi(argv[i + 1])) >= 1) {
            ++i;
        } else if (strcmp(argv[i], "--factor-reuse") == 0 && i + 1 < argc) {
            g_factor_reuse = atof(argv[++i]);
        } else {
            const int code = bench_filter_arg(argv[i], &filter, usage);
            if (code >= 0) return code;
        }
    }
    const char* dir = bench_find_mesh_dir(given_dir, kMeshes[0].file);
    if (!dir) return 1;
    bench_pin_thread(bench_current_cpu());
    for (size_t k = 0; k < sizeof kMeshes / sizeof kMeshes[0]; ++k) {
        if (!mesh_wanted(kMeshes[k].name, filter)) continue;
        cut_mesh m;
        if (!cut_mesh_load(dir, kMeshes[k].file, kMeshes[k].name, kMeshes[k].scale, kMeshes[k].size, &m)) return 1;
        fprintf(stderr, "cut: %s: %d nodes, %d tets, %d fixed, mean edge %.4g m, blade %.4g m along axis %d\n", m.name,
                m.node_count, m.tet_count, m.fixed_count, m.edge, blade_at(&m, 1.0) - blade_at(&m, 0.0), m.run);
        for (size_t c = 0; c < sizeof kCases / sizeof kCases[0]; ++c) {
            char name[256];
            case_name(m.name, &kCases[c], name, sizeof name);
            if (name_matches(name, filter)) run_case(&m, &kCases[c], name, reps);
        }
        cut_mesh_free(&m);
    }
    return 0;
}
