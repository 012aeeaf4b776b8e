#include "box_mesh.h"

#include <stdlib.h>

void sh_test_grid_arrays(const double* xs, int nx, const double* ys, int ny, const double* zs, int nz,
                         double** out_nodes, int32_t* out_node_count, int32_t** out_tets,
                         int32_t* out_tet_count) {
    const int px = nx + 1, py = ny + 1, pz = nz + 1;
    const int node_count = px * py * pz, tet_count = 6 * nx * ny * nz;
    double* nodes = malloc(sizeof(double) * 3 * (size_t)node_count);
    int32_t* tets = malloc(sizeof(int32_t) * 4 * (size_t)tet_count);
    *out_nodes = nodes;
    *out_node_count = node_count;
    *out_tets = tets;
    *out_tet_count = tet_count;
    if (nodes == NULL || tets == NULL) return;
    for (int k = 0; k < pz; ++k)
        for (int j = 0; j < py; ++j)
            for (int i = 0; i < px; ++i) {
                double* p = &nodes[3 * (size_t)((k * py + j) * px + i)];
                p[0] = xs[i];
                p[1] = ys[j];
                p[2] = zs[k];
            }
    static const int kuhn[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
    int t = 0;
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                const int c[8] = {
                    (k * py + j) * px + i, (k * py + j) * px + i + 1,
                    (k * py + j + 1) * px + i + 1, (k * py + j + 1) * px + i,
                    ((k + 1) * py + j) * px + i, ((k + 1) * py + j) * px + i + 1,
                    ((k + 1) * py + j + 1) * px + i + 1, ((k + 1) * py + j + 1) * px + i};
                for (int s = 0; s < 6; ++s, ++t)
                    for (int a = 0; a < 4; ++a) tets[4 * t + a] = c[kuhn[s][a]];
            }
}

void sh_test_box_arrays(double lx, double ly, double lz, int nx, int ny, int nz, double** out_nodes,
                        int32_t* out_node_count, int32_t** out_tets, int32_t* out_tet_count) {
    const int px = nx + 1, py = ny + 1, pz = nz + 1;
    /* One allocation holds the three plane arrays. */
    double* planes = malloc(sizeof(double) * (size_t)(px + py + pz));
    if (planes == NULL) {
        *out_nodes = NULL;
        *out_tets = NULL;
        *out_node_count = px * py * pz;
        *out_tet_count = 6 * nx * ny * nz;
        return;
    }
    double *xs = planes, *ys = planes + px, *zs = planes + px + py;
    for (int i = 0; i < px; ++i) xs[i] = lx * i / nx;
    for (int j = 0; j < py; ++j) ys[j] = ly * j / ny;
    for (int k = 0; k < pz; ++k) zs[k] = lz * k / nz;
    sh_test_grid_arrays(xs, nx, ys, ny, zs, nz, out_nodes, out_node_count, out_tets, out_tet_count);
    free(planes);
}
