/* The box meshes of the tests and the accuracy benchmark: plain C, no cmocka, so softhap_bench
 * builds it too. */
#ifndef SOFTHAP_BOX_MESH_H
#define SOFTHAP_BOX_MESH_H

#include <stdint.h>

/** The node and tet arrays of the structured grid whose node planes are x = xs[0..nx],
 *  y = ys[0..ny], z = zs[0..nz] (each strictly increasing, so a graded mesh is a grid with
 *  uneven spacing): nx*ny*nz boxes of 6 tets each (Kuhn split along each box's 0-6 diagonal, so
 *  neighbouring boxes conform; every tet is right-handed). Node (i, j, k) of the grid is node
 *  (k (ny + 1) + j) (nx + 1) + i, at (xs[i], ys[j], zs[k]). The caller frees both arrays (either
 *  may be NULL if allocation failed; the counts are set regardless). */
void sh_test_grid_arrays(const double* xs, int nx, const double* ys, int ny, const double* zs, int nz,
                         double** out_nodes, int32_t* out_node_count, int32_t** out_tets,
                         int32_t* out_tet_count);

/** sh_test_grid_arrays of the axis-aligned box [0,lx]x[0,ly]x[0,lz] split into nx*ny*nz equal
 *  boxes (node planes at lx i / nx, ly j / ny, lz k / nz). */
void sh_test_box_arrays(double lx, double ly, double lz, int nx, int ny, int nz, double** out_nodes,
                        int32_t* out_node_count, int32_t** out_tets, int32_t* out_tet_count);

#endif
