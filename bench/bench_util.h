/* Helpers shared by the softhap_bench subcommands: a fatal status check, a monotonic clock,
 * order statistics of timing samples, case filters and names, the mesh folder and meshes, the
 * defs of the bodies and tools the benches build, and CPU pinning. */
#ifndef SOFTHAP_BENCH_UTIL_H
#define SOFTHAP_BENCH_UTIL_H

#include <softhap/softhap.h>

#include <stddef.h>
#include <stdint.h>

/* Runs expr (an sh_status); on failure prints it with the library's last error and exits 1. */
#define CHECK(expr) bench_check((expr), #expr)
void bench_check(sh_status status, const char* expr);

/* CLOCK_MONOTONIC in ns. */
double now_ns(void);

/* malloc that exits on failure (size 0 allocates 1 byte). */
void* xmalloc(size_t size);

/* qsort comparator of doubles, ascending. */
int cmp_double(const void* a, const void* b);

/* Value at quantile q of sorted[0..n): the smallest value with at least q*n values at or below. */
double quantile(const double* sorted, int n, double q);

/* Median of sorted[0..n). */
double median(const double* sorted, int n);

/* Order statistics and mean of a sample (count 0: all zero). */
typedef struct {
    int count;
    double median, p99, p999, max, mean;
} stats;

/* Sorts v[0..n) and summarises it. */
stats summarize(double* v, int n);

/* Euclidean length of a 3-vector. */
double norm3(const double* a);

/* Distance between the points a and b. */
double distance3(const double* a, const double* b);

/* (b - a) x (c - a): the normal of triangle abc (its length twice the area), not normalised. */
void triangle_cross(const double* a, const double* b, const double* c, double n[3]);

/* 1 if a case named name is wanted: no filter, or name contains filter. */
int name_matches(const char* name, const char* filter);

/* An argument none of a subcommand's own options took: the first word not starting with '-' is
 * its FILTER (stored in *filter; returns -1: go on); --help or -h prints usage and returns 0;
 * anything else prints usage and returns 2. A return >= 0 is the subcommand's exit code. */
int bench_filter_arg(const char* arg, const char** filter, void (*usage)(void));

/* The lower-case name of a material model ("stvk"), as the cases and JSON lines spell it. */
const char* material_name(sh_material_model model);

/* The mesh folder: given if not NULL, else the first of $SOFTHAP_MESHES, the build's default,
 * ../shared/meshes and ../../shared/meshes that holds probe (a file name). NULL, with a message
 * on stderr, if none does. */
const char* bench_find_mesh_dir(const char* given, const char* probe);

/* Loads dir/file as it is; NULL with a message on stderr if it does not load. */
sh_mesh* bench_load_mesh(const char* dir, const char* file);

/* Loads dir/file, turns its nodes by turn (a row-major 3x3 rotation; NULL: as they are), moves
 * the lowest corner of their bounding box (of the turned nodes; of sh_mesh_info's bounds when
 * not turned) to the origin and scales them so that the largest extent is size (m). Returns
 * the new mesh in *out_mesh and its node array (3 per node, caller frees) in *out_nodes; 0 with
 * a message on stderr if the file does not load. */
int bench_load_scaled_mesh(const char* dir, const char* file, const double* turn, double size, sh_mesh** out_mesh,
                           double** out_nodes);

/* The mesh's surface triangles (3 node indices each, outward; caller frees), their count in
 * *out_count. */
int32_t* bench_surface_triangles(const sh_mesh* mesh, int32_t* out_count);

/* A world with gravity off (so that a tool's force is the contact alone) if !gravity, else the
 * default world (gravity -9.81 m/s^2 along z). */
sh_world* bench_world_create(int gravity);

/* The default FEM body def for mesh with an isotropic material of the given model, Young's
 * modulus (Pa), Poisson ratio and density (kg/m^3); the caller sets the rest. */
sh_fem_body_def bench_fem_body_def(const sh_mesh* mesh, sh_material_model model, double young, double poisson,
                                   double density);

/* The default collider def of a sphere of radius (m) centred at position. */
sh_collider_def bench_sphere_def(double radius, const double position[3]);

/* The CPU the calling thread runs on; -1 where unknown (or not Linux). */
int bench_current_cpu(void);

/* Pins the calling thread to cpu (Linux; nothing if cpu < 0 or elsewhere), so that its cache and
 * timings stay put. */
void bench_pin_thread(int cpu);

/* The 1-minute load average from /proc/loadavg; unknown if it cannot be read. */
double bench_load_average(double unknown);

#endif
