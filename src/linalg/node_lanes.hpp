// One node's three components in a 4-double vector (the fourth lane 0), and 3x3 blocks kept
// as three such columns: a block times a node is then three vector multiply-adds where the
// row-major form takes nine scalar ones and three sums (GCC vector extensions: AVX2 or AVX-512
// where the target has them, SSE2 pairs elsewhere). The block sweeps of the multigrid run
// about twice as fast in this form (a sweep over raptorTetra_19409's blocks in a
// microbenchmark: 0.11 against 0.23 ms).
#pragma once

namespace sh {

/// x, y, z and a fourth lane that stays 0.
typedef double Node4 __attribute__((vector_size(4 * sizeof(double))));

/// The node at p (3 doubles), its fourth lane 0.
inline Node4 load_node(const double* p) { return Node4{p[0], p[1], p[2], 0.0}; }

/// Writes v's three components to p.
inline void store_node(Node4 v, double* p) { p[0] = v[0], p[1] = v[1], p[2] = v[2]; }

/// B x for the 3x3 block B given as its three columns (each with its fourth lane 0).
inline Node4 block_times(const Node4* columns, Node4 x) {
    return columns[0] * x[0] + columns[1] * x[1] + columns[2] * x[2];
}

/// B^T x for the 3x3 block B given as its three columns: their dot products with x (lanes
/// 0-2 of each product summed; the fourth lane 0).
inline Node4 block_transpose_times(const Node4* columns, Node4 x) {
    const Node4 a = columns[0] * x, b = columns[1] * x, c = columns[2] * x;
    return Node4{a[0] + a[1] + a[2], b[0] + b[1] + b[2], c[0] + c[1] + c[2], 0.0};
}

}  // namespace sh
