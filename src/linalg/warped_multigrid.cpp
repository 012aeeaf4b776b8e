#include "linalg/warped_multigrid.hpp"

#include "core/error.hpp"
#include "core/union_find.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

// Free nodes per coarse node the grid aims at: about 4 fine cells per coarse cell along each
// axis on a structured mesh (4x4x4 coarse cells for a 15^3-cell cube: 5-7 CG iterations to a
// relative residual of 0.025 through large rotations). Finer grids cost more per cycle than
// they save in iterations.
constexpr double kCoarsening = 25.0;
// What one of the cycle's operations costs against one of a sparse solve's: the stored
// triangle (2.5 MB at 20 k tets) stays in cache across the cycle and is read in 4-double lanes,
// where a solve streams its factor (29 MB) from memory. Measured on the raptor's 17,793 DOF
// (AMD EPYC, AVX-512): 0.54 ms per iteration against 3.6 ms per CHOLMOD solve.
constexpr double kCachedOperationWeight = 0.22;
// The most coarse nodes: the coarse matrix is dense (1,200 DOF: 11.5 MB, a 0.2 ms solve).
constexpr int32_t kMaxCoarseNodes = 400;
// The grid search's bounds: cells along the longest side, and nodes of a grid (its index is
// one int32 per grid node).
constexpr int32_t kMaxCells = 256;
constexpr int64_t kMaxGridNodes = int64_t{1} << 21;
// Trilinear weights below this are left out of P, so that no coarse node hangs on weights of
// zero (a node on a grid plane) and makes the coarse matrix singular.
constexpr double kWeightFloor = 1e-9;
// The coarse matrix's diagonal is raised by this fraction of its mean: columns of P that
// happen to be dependent (a thin part with few nodes in a cell) then leave it positive
// definite, and their null direction is never restricted into (P^T annihilates it).
constexpr double kCoarseShift = 1e-10;

// A regular grid over a box: cells cubes of side h from lo, dims cells along each axis.
struct Grid {
    double lo[3] = {}, h = 0.0;
    int32_t dims[3] = {1, 1, 1};
    int64_t node(int32_t i, int32_t j, int32_t k) const {
        return (static_cast<int64_t>(k) * (dims[1] + 1) + j) * (dims[0] + 1) + i;
    }
    int64_t node_count() const { return static_cast<int64_t>(dims[0] + 1) * (dims[1] + 1) * (dims[2] + 1); }
    // The cell holding p and p's coordinates in it (each in [0, 1]).
    void locate(const double* p, int32_t cell[3], double t[3]) const {
        for (int a = 0; a < 3; ++a) {
            const double s = (p[a] - lo[a]) / h;
            cell[a] = std::clamp(static_cast<int32_t>(std::floor(s)), 0, dims[a] - 1);
            t[a] = std::clamp(s - cell[a], 0.0, 1.0);
        }
    }
    // Grid node and trilinear weight of p's cell corner c (bits: x, y, z).
    int64_t corner(const int32_t cell[3], const double t[3], int c, double& w) const {
        const int32_t d[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
        w = 1.0;
        for (int a = 0; a < 3; ++a) w *= d[a] ? t[a] : 1.0 - t[a];
        return node(cell[0] + d[0], cell[1] + d[1], cell[2] + d[2]);
    }
};

// The grid of `cells` cells along the longest side of the box [lo, hi].
Grid grid_over(const double lo[3], const double hi[3], int32_t cells) {
    Grid g;
    const double longest = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
    g.h = longest / cells;
    for (int a = 0; a < 3; ++a) {
        g.lo[a] = lo[a];
        g.dims[a] = std::max(1, static_cast<int32_t>(std::ceil((hi[a] - lo[a]) / g.h - 1e-9)));
    }
    return g;
}

// Grid nodes that some node's cell gives a weight above the floor, numbered in grid order
// into index (size node_count(), -1 elsewhere); returns their count.
int32_t number_corners(const Grid& g, const double* rest, int32_t nodes, vec<int32_t>& index) {
    index.assign(static_cast<size_t>(g.node_count()), -1);
    for (int32_t i = 0; i < nodes; ++i) {
        int32_t cell[3];
        double t[3], w;
        g.locate(rest + 3 * static_cast<size_t>(i), cell, t);
        for (int c = 0; c < 8; ++c) {
            const int64_t n = g.corner(cell, t, c, w);
            if (w > kWeightFloor) index[static_cast<size_t>(n)] = 0;
        }
    }
    int32_t count = 0;
    for (int32_t& n : index)
        if (n == 0) n = count++;
    return count;
}

}  // namespace

void WarpedMultigrid::build_prolongation(const double* rest, int32_t nodes) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t i = 0; i < nodes; ++i)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], rest[3 * static_cast<size_t>(i) + a]);
            hi[a] = std::max(hi[a], rest[3 * static_cast<size_t>(i) + a]);
        }
    // The finest grid (cells along the longest side) within the coarse node budget, by
    // bisection (the count grows with the cells), and no grid of more than kMaxGridNodes nodes
    // (a body whose nodes fill little of their box: two organs far apart).
    const int32_t wanted = std::min(kMaxCoarseNodes, std::max(8, static_cast<int32_t>(nodes / kCoarsening)));
    const auto fits_budget = [&](int32_t cells) {
        const Grid g = grid_over(lo, hi, cells);
        return g.node_count() <= kMaxGridNodes && fill_prolongation(lo, hi, cells, rest, nodes) <= wanted;
    };
    int32_t fits = 1, too_many = 1;
    while (too_many < kMaxCells && fits_budget(2 * too_many)) fits = too_many *= 2;
    too_many = 2 * fits;
    while (too_many - fits > 1) {
        const int32_t middle = (fits + too_many) / 2;
        (fits_budget(middle) ? fits : too_many) = middle;
    }
    coarse_count_ = fill_prolongation(lo, hi, fits, rest, nodes);
}

int32_t WarpedMultigrid::fill_prolongation(const double lo[3], const double hi[3], int32_t cells, const double* rest,
                                           int32_t nodes) {
    const Grid g = grid_over(lo, hi, cells);
    vec<int32_t>& index = scratch_;
    number_corners(g, rest, nodes, index);
    corner_.assign(8 * static_cast<size_t>(nodes), -1);
    weight_.assign(8 * static_cast<size_t>(nodes), 0.0);
    for (int32_t i = 0; i < nodes; ++i) {
        int32_t cell[3];
        double t[3];
        g.locate(rest + 3 * static_cast<size_t>(i), cell, t);
        for (int c = 0; c < 8; ++c) {
            double w;
            const int64_t n = g.corner(cell, t, c, w);
            if (!(w > kWeightFloor)) continue;
            corner_[8 * static_cast<size_t>(i) + c] = index[static_cast<size_t>(n)];
            weight_[8 * static_cast<size_t>(i) + c] = w;
        }
    }
    return split_by_connection(nodes);
}

int32_t WarpedMultigrid::split_by_connection(int32_t nodes) {
    // Union-find over the attachments (node i, corner c) = 8 i + c: two attachments to the same
    // grid node are one coarse node if their fine nodes share an element (a block).
    vec<int32_t>& parent = scratch_;
    parent.resize(8 * static_cast<size_t>(nodes));
    for (size_t a = 0; a < parent.size(); ++a) parent[a] = static_cast<int32_t>(a);
    for (int32_t j = 0; j < nodes; ++j)
        for (int32_t b = blocks_.first_block()[j]; b < blocks_.first_block()[j + 1]; ++b) {
            const int32_t i = blocks_.row_node()[b];
            for (int p = 0; p < 8; ++p) {
                const int32_t grid_node = corner_[8 * static_cast<size_t>(i) + p];
                if (grid_node < 0) continue;
                for (int q = 0; q < 8; ++q)
                    if (corner_[8 * static_cast<size_t>(j) + q] == grid_node)
                        union_join(parent, 8 * i + p, 8 * j + q);
            }
        }
    // Each root is a coarse node; number them in order of their first attachment.
    vec<int32_t> number(parent.size(), -1);
    int32_t count = 0;
    for (int32_t a = 0; a < 8 * nodes; ++a) {
        if (corner_[static_cast<size_t>(a)] < 0) continue;
        int32_t& n = number[static_cast<size_t>(union_root(parent, a))];
        if (n < 0) n = count++;
        corner_[static_cast<size_t>(a)] = n;
    }
    return count;
}

// coarse += P_a^T block P_b: block (a, b) spread over the coarse nodes of a's and b's cells.
void WarpedMultigrid::add_coarse_block(int32_t a, int32_t b, const Eigen::Matrix3d& block, Eigen::MatrixXd& coarse) const {
    for (int p = 0; p < 8; ++p) {
        const int32_t I = corner_[8 * static_cast<size_t>(a) + p];
        if (I < 0) continue;
        const double wa = weight_[8 * static_cast<size_t>(a) + p];
        for (int q = 0; q < 8; ++q) {
            const int32_t J = corner_[8 * static_cast<size_t>(b) + q];
            if (J < 0) continue;
            coarse.block<3, 3>(3 * I, 3 * J) += wa * weight_[8 * static_cast<size_t>(b) + q] * block;
        }
    }
}

void WarpedMultigrid::build_coarse(const SparseSystem& a0) {
    const Eigen::Index n = 3 * static_cast<Eigen::Index>(coarse_count_);
    Eigen::MatrixXd coarse = Eigen::MatrixXd::Zero(n, n);
    for (int32_t j = 0; j < blocks_.node_count(); ++j) {
        double diagonal[3][3];
        blocks_.diagonal_block(a0, j, diagonal);
        Eigen::Matrix3d block = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&diagonal[0][0]);
        add_coarse_block(j, j, block, coarse);
        for (int32_t b = blocks_.first_block()[j]; b < blocks_.first_block()[j + 1]; ++b) {
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) block(r, c) = blocks_.entry(a0, j, b, r, c);
            const int32_t i = blocks_.row_node()[b];
            add_coarse_block(i, j, block, coarse);
            add_coarse_block(j, i, block.transpose(), coarse);
        }
    }
    coarse.diagonal().array() += kCoarseShift * coarse.diagonal().mean();
    coarse_.compute(coarse);
    SH_REQUIRE(coarse_.info() == Eigen::Success, SH_ERR_SOLVER,
               "multigrid: the coarse matrix of %d grid nodes is not positive definite", coarse_count_);
    coarse_rhs_.setZero(n);
}

void WarpedMultigrid::build(const SparseSystem& a0, const double* rest) {
    built_ = false;
    blocks_.build(a0);
    const int32_t nodes = blocks_.node_count();
    build_prolongation(rest, nodes);
    build_coarse(a0);
    inverse_diagonal_.assign(3 * static_cast<size_t>(nodes), Node4{});
    turn_.assign(6 * static_cast<size_t>(nodes), Node4{});
    coarse_lanes_.assign(static_cast<size_t>(coarse_count_), Node4{});
    z_.assign(static_cast<size_t>(nodes), Node4{});
    pushed_.assign(static_cast<size_t>(nodes), Node4{});
    residual_.assign(static_cast<size_t>(nodes), Node4{});
    change_.assign(static_cast<size_t>(nodes), Node4{});
    built_ = true;
}

void WarpedMultigrid::prepare(const SparseSystem& a, const double* rotations) {
    SH_REQUIRE(built_for(a), SH_ERR_INTERNAL, "multigrid: prepared with another pattern than it was built for");
    system_ = &a;
    for (int32_t i = 0; i < blocks_.node_count(); ++i) {
        const double* R = rotations + 9 * static_cast<size_t>(i);  // row-major
        Node4* turn = &turn_[6 * static_cast<size_t>(i)];
        for (int c = 0; c < 3; ++c) {
            turn[c] = Node4{R[c], R[3 + c], R[6 + c], 0.0};                  // R's columns
            turn[3 + c] = Node4{R[3 * c], R[3 * c + 1], R[3 * c + 2], 0.0};  // R^T's
        }
    }
    for (int32_t i = 0; i < blocks_.node_count(); ++i) {
        double diagonal[3][3];
        blocks_.diagonal_block(*system_, i, diagonal);
        const Eigen::Matrix3d d = Eigen::Map<const Eigen::Matrix3d>(&diagonal[0][0]);  // symmetric
        // Positive definite by its leading minors (Sylvester); the inverse in closed form,
        // where a 3x3 Cholesky factorisation and solve take several times as long.
        const bool definite = d(0, 0) > 0.0 && d(0, 0) * d(1, 1) - d(0, 1) * d(0, 1) > 0.0 && d.determinant() > 0.0;
        const Eigen::Matrix3d inverse = d.inverse();
        SH_REQUIRE(definite && inverse.allFinite(), SH_ERR_SOLVER,
                   "multigrid: the diagonal block of free node %d is not positive definite", i);
        for (int c = 0; c < 3; ++c)
            inverse_diagonal_[3 * static_cast<size_t>(i) + static_cast<size_t>(c)] =
                Node4{inverse(0, c), inverse(1, c), inverse(2, c), 0.0};
    }
}

void WarpedMultigrid::backward_sweep(const double* r, double* z) {
    // Row J sums its right part from the pushes of the nodes after it (already new) and its
    // left part from the blocks it holds (the nodes before it, not yet changed).
    std::fill(pushed_.begin(), pushed_.end(), Node4{});
    for (int32_t j = blocks_.node_count() - 1; j >= 0; --j) {
        const size_t n = static_cast<size_t>(j);
        const Node4 s = load_node(r + 3 * n) - pushed_[n] - blocks_.pull(*system_, j, z_.data());
        const Node4 updated = block_times(&inverse_diagonal_[3 * n], s);
        blocks_.push(*system_, j, updated, pushed_.data());
        change_[n] = updated - z_[n];
        z_[n] = updated;
        store_node(updated, z + 3 * n);
    }
}

void WarpedMultigrid::first_sweep(const double* r) {
    // residual_ gathers -U z_ from each node's push once its value is final.
    std::fill(residual_.begin(), residual_.end(), Node4{});
    for (int32_t j = 0; j < blocks_.node_count(); ++j) {
        const size_t n = static_cast<size_t>(j);
        z_[n] = block_times(&inverse_diagonal_[3 * n], load_node(r + 3 * n) - blocks_.pull(*system_, j, z_.data()));
        blocks_.push(*system_, j, -z_[n], residual_.data());
    }
}

void WarpedMultigrid::coarse_correction() {
    const int32_t n = blocks_.node_count();
    std::fill(coarse_lanes_.begin(), coarse_lanes_.end(), Node4{});
    for (int32_t i = 0; i < n; ++i) {
        const size_t node = static_cast<size_t>(i);
        const Node4 local = block_times(&turn_[6 * node + 3], residual_[node]);  // R^T e
        for (int p = 0; p < 8; ++p) {
            const int32_t I = corner_[8 * node + static_cast<size_t>(p)];
            if (I >= 0) coarse_lanes_[static_cast<size_t>(I)] += weight_[8 * node + static_cast<size_t>(p)] * local;
        }
    }
    for (int32_t I = 0; I < coarse_count_; ++I)
        for (int c = 0; c < 3; ++c) coarse_rhs_[3 * I + c] = coarse_lanes_[static_cast<size_t>(I)][c];
    coarse_.solveInPlace(coarse_rhs_);
    for (int32_t I = 0; I < coarse_count_; ++I) coarse_lanes_[static_cast<size_t>(I)] = load_node(&coarse_rhs_[3 * I]);
    for (int32_t i = 0; i < n; ++i) {
        const size_t node = static_cast<size_t>(i);
        Node4 local{};
        for (int p = 0; p < 8; ++p) {
            const int32_t I = corner_[8 * node + static_cast<size_t>(p)];
            if (I >= 0) local += weight_[8 * node + static_cast<size_t>(p)] * coarse_lanes_[static_cast<size_t>(I)];
        }
        z_[node] += block_times(&turn_[6 * node], local);  // R P u
    }
}

void WarpedMultigrid::apply(const double* r, double* z) {
    first_sweep(r);
    coarse_correction();
    backward_sweep(r, z);
}

bool WarpedMultigrid::apply_with_product(const double* r, double* z, double* az) {
    apply(r, z);
    // Node j's sweep solved its row for r with the nodes before it (i < j) not yet changed:
    // (A z)_j = r_j + sum over i < j of A_ji change_i.
    for (int32_t j = 0; j < blocks_.node_count(); ++j) {
        const size_t n = static_cast<size_t>(j);
        store_node(load_node(r + 3 * n) + blocks_.pull(*system_, j, change_.data()), az + 3 * n);
    }
    return true;
}

double WarpedMultigrid::iteration_work() const {
    // Per stored block, 36 operations for each sweep (its pull and its push: the first sweep
    // with its residual, the backward sweep) and 18 for the half product CG's A p takes from
    // the cycle; the transfers; the dense coarse solve. They count kCachedOperationWeight of a
    // sparse solve's operation each.
    const double stored = static_cast<double>(blocks_.block_count()) + blocks_.node_count();
    const double coarse = 3.0 * coarse_count_;
    return kCachedOperationWeight * ((2.0 * 36.0 + 18.0) * stored + 120.0 * blocks_.node_count() + 2.0 * coarse * coarse);
}

}  // namespace sh
