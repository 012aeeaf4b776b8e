/* The box mesh of the tests and the accuracy benchmark: plain C, no cmocka, so softhap_bench
 * builds it too. */
#ifndef SOFTHAP_BOX_MESH_H
#define SOFTHAP_BOX_MESH_H

#include <stdint.h>

/** The node and tet arrays of the axis-aligned box [0,lx]x[0,ly]x[0,lz] split into nx*ny*nz
 *  cubes of 6 tets each (Kuhn split along each cube's 0-6 diagonal, so neighbouring cubes
 *  conform); node (i, j, k) of the grid is node (k (ny + 1) + j) (nx + 1) + i. The caller frees
 *  both arrays (either may be NULL if allocation failed; the counts are set regardless). */
void sh_test_box_arrays(double lx, double ly, double lz, int nx, int ny, int nz, double** out_nodes,
                        int32_t* out_node_count, int32_t** out_tets, int32_t* out_tet_count);

#endif
