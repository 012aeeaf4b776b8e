// A block of cubes split into six tets each (Kuhn), for the linear-algebra unit tests.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace kuhn {

/// Node (i, j, k) of a block of cells^3 cubes, numbered x fastest.
inline int32_t grid_node(int cells, int i, int j, int k) { return (k * (cells + 1) + j) * (cells + 1) + i; }

/// Nodes of the block.
inline int32_t node_count(int cells) { return (cells + 1) * (cells + 1) * (cells + 1); }

/// Its tets, 4 nodes each, six per cube around the cube's main diagonal.
inline std::vector<int32_t> block_tets(int cells) {
    static const int kKuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
    std::vector<int32_t> tets;
    for (int k = 0; k < cells; ++k)
        for (int j = 0; j < cells; ++j)
            for (int i = 0; i < cells; ++i)
                for (const auto& tet : kKuhn)
                    for (const int corner : tet)
                        tets.push_back(grid_node(cells, i + (corner & 1), j + ((corner >> 1) & 1), k + ((corner >> 2) & 1)));
    return tets;
}

/// The tets of `copies` blocks of cells^3 cubes, copy c's nodes numbered after copy c - 1's:
/// blocks that share no element.
inline std::vector<int32_t> copies_tets(int cells, int copies) {
    const std::vector<int32_t> one = block_tets(cells);
    std::vector<int32_t> tets;
    for (int copy = 0; copy < copies; ++copy)
        for (const int32_t node : one) tets.push_back(node + copy * node_count(cells));
    return tets;
}

/// Their nodes' positions (3 per node): unit cells, copy c shifted by c * pitch along x.
inline std::vector<double> copies_rest(int cells, int copies, double pitch) {
    std::vector<double> rest(3 * static_cast<size_t>(copies * node_count(cells)));
    for (int copy = 0; copy < copies; ++copy)
        for (int k = 0; k <= cells; ++k)
            for (int j = 0; j <= cells; ++j)
                for (int i = 0; i <= cells; ++i) {
                    const size_t n = static_cast<size_t>(grid_node(cells, i, j, k) + copy * node_count(cells));
                    rest[3 * n] = i + copy * pitch, rest[3 * n + 1] = j, rest[3 * n + 2] = k;
                }
    return rest;
}

/// A tet's graph Laplacian per component, 4 I - ones (row-major 12x12 over its 4 nodes' x y z),
/// with an x-y coupling `shear` in each block (symmetric positive semi-definite for |shear| < 1;
/// anisotropic, so that a rotation changes it).
inline std::array<double, 144> laplacian_element(double shear) {
    std::array<double, 144> ke{};
    for (int r = 0; r < 12; ++r)
        for (int c = 0; c < 12; ++c) {
            const double weight = r / 3 == c / 3 ? 3.0 : -1.0;
            const int rc = r % 3, cc = c % 3;
            ke[static_cast<size_t>(12 * r + c)] = rc == cc ? weight : (rc + cc == 1 ? weight * shear : 0.0);
        }
    return ke;
}

}  // namespace kuhn
