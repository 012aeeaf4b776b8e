/* What the softhap_bench cut study (cut.c) cuts and how it times it: a mesh in metres with its
 * fixed base, a world holding one implicit FEM body of it, the cut surfaces laid over its
 * bounding box (a blade plane cut whole or in increments of one element), and a timed cut and
 * step (cut_scene.c). */
#ifndef SOFTHAP_BENCH_CUT_SCENE_H
#define SOFTHAP_BENCH_CUT_SCENE_H

#include <softhap/softhap.h>

#include <stdint.h>

/* A mesh to cut. */
typedef struct {
    const char* name;
    sh_mesh* mesh;          /* in metres */
    int32_t node_count, tet_count;
    int32_t* fixed;         /* the base: nodes less than kBaseFraction of the height above the lowest */
    int32_t fixed_count;
    double lo[3], hi[3];    /* bounding box (m) */
    double edge;            /* mean edge length (m): the blade's increment */
    int run, span, normal;  /* the box's axes from the longest to the shortest: the blade runs
                               along run, reaches across span, its plane's normal is normal */
} cut_mesh;

/* Loads dir/file into *m named name: scaled by scale if scale > 0 (liver2.msh: 0.1), else moved
 * to the origin and scaled so that its largest extent is size (m), as the step benches do. 0 with
 * a message on stderr if it does not load. */
int cut_mesh_load(const char* dir, const char* file, const char* name, double scale, double size, cut_mesh* m);

/* Frees what cut_mesh_load made. */
void cut_mesh_free(cut_mesh* m);

/* A world without gravity holding one FEM body of m (soft tissue, implicit Euler with the given
 * factor_reuse (sh_implicit_settings; 0: a fresh factorisation at every step), its base fixed),
 * at rest; the body's id in *body. */
sh_world* cut_world(const cut_mesh* m, double factor_reuse, sh_body_id* body);

/* Where along the run axis the blade has gone fraction of the way through the box (fraction 0:
 * one element before it; 1: one element past it). */
double blade_at(const cut_mesh* m, double fraction);

/* Increments of `elements` mean edge lengths each that take the blade from blade_at(m, 0) to
 * blade_at(m, 1) (the last may be shorter). */
int blade_increments(const cut_mesh* m, int elements);

/* The blade from s0 to s1 along the run axis as a quad (two triangles, 18 doubles, into tris): in
 * the plane at kBladePlane of the box's extent along the normal axis, reaching past the box along
 * the span axis by a fifth of the box's extent there. Successive quads share their edge at s1 /
 * s0. */
void blade_quad(const cut_mesh* m, double s0, double s1, double tris[18]);

/* A cut and what it cost: the library's report and the wall time around the call (s). */
typedef struct {
    sh_cut_report report;
    double wall;
} timed_cut;

/* Cuts body along the count triangles tris; exits on failure. */
timed_cut cut_timed(sh_world* world, sh_body_id body, const double* tris, int32_t count);

/* One sh_world_step of dt with report; its wall time (s). *failed counts steps not SH_OK. */
double step_timed(sh_world* world, double dt, sh_step_report* report, int* failed);

#endif
