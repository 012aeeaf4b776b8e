/* Helpers shared by the softhap_bench subcommands: a fatal status check, a monotonic clock,
 * order statistics of timing samples, the mesh folder and scaled meshes. */
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

/* The mesh folder: given if not NULL, else the first of $SOFTHAP_MESHES, the build's default,
 * ../shared/meshes and ../../shared/meshes that holds probe (a file name). NULL if none. */
const char* bench_find_mesh_dir(const char* given, const char* probe);

/* Loads dir/file, turns its nodes by turn (a row-major 3x3 rotation; NULL: as they are), moves
 * the lowest corner of their bounding box (of the turned nodes; of sh_mesh_info's bounds when
 * not turned) to the origin and scales them so that the largest extent is size (m). Returns
 * the new mesh in *out_mesh and its node array (3 per node, caller frees) in *out_nodes; 0 with
 * a message on stderr if the file does not load. */
int bench_load_scaled_mesh(const char* dir, const char* file, const double* turn, double size, sh_mesh** out_mesh,
                           double** out_nodes);

#endif
