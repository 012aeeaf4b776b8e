// The multigrid's coarse space: the aggregates of linalg/node_aggregates.hpp (every node in
// exactly one, each connected by elements, founders' whole neighbourhoods, none across parts
// that share no element) and the rigid prolongation P of linalg/rigid_prolongation.hpp: its
// columns orthonormal (P^T P = I), rigid motions of the whole body in its range (P P^T v = v),
// degenerate aggregates' rotations inert, and its Galerkin matrix equal to P^T A P formed
// densely from P's columns and A's products.
#include "linalg/block_rows.hpp"
#include "linalg/linear_solver.hpp"
#include "linalg/node_aggregates.hpp"
#include "linalg/rigid_prolongation.hpp"
#include "linalg/sparse_system.hpp"
#include "linalg/upper_blocks.hpp"

#include "kuhn_block.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <cstdint>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

// `copies` Kuhn blocks of cells^3 cubes along x, sharing no element, with their system: a
// Laplacian per tet with shear plus a mass, and the nodes' rest positions (unit cells, the
// copies one cell apart). rows and blocks read it.
struct Scene {
    sh::SparseSystem a;
    sh::UpperBlocks blocks;
    sh::BlockRows rows;
    std::vector<double> rest;
};

void build_scene(int cells, int copies, Scene& out) {
    const std::vector<int32_t> tets = kuhn::copies_tets(cells, copies);
    const int32_t nodes = copies * kuhn::node_count(cells);
    std::vector<int32_t> identity(static_cast<size_t>(nodes));
    for (int32_t i = 0; i < nodes; ++i) identity[static_cast<size_t>(i)] = i;
    out.a.build_pattern(tets.data(), tets.size() / 4, 4, identity.data(), nodes, nodes);
    const std::array<double, 144> ke = kuhn::laplacian_element(0.6);
    for (size_t e = 0; e < tets.size() / 4; ++e) out.a.add_element(e, ke.data(), 1e3);
    const std::vector<double> mass(3 * static_cast<size_t>(nodes), 2.0);
    out.a.add_diagonal(mass.data(), 1.0);
    out.blocks.build(out.a);
    out.rows.build(out.a, out.blocks);
    out.rest = kuhn::copies_rest(cells, copies, cells + 1.0);
}

// True if nodes i and j share a block of rows (an element).
bool neighbours(const sh::BlockRows& rows, int32_t i, int32_t j) {
    for (int32_t e = rows.first[static_cast<size_t>(i)]; e < rows.first[static_cast<size_t>(i) + 1]; ++e)
        if (rows.column[static_cast<size_t>(e)] == j) return true;
    return false;
}

// The number of connected parts of aggregate a's nodes in rows' graph (flood fill).
int parts_of(const sh::BlockRows& rows, const sh::vec<int32_t>& aggregate, int32_t a) {
    const int32_t n = rows.node_count();
    std::vector<char> seen(static_cast<size_t>(n), 0);
    int parts = 0;
    for (int32_t start = 0; start < n; ++start) {
        if (aggregate[static_cast<size_t>(start)] != a || seen[static_cast<size_t>(start)]) continue;
        ++parts;
        std::vector<int32_t> stack{start};
        seen[static_cast<size_t>(start)] = 1;
        while (!stack.empty()) {
            const int32_t i = stack.back();
            stack.pop_back();
            for (int32_t e = rows.first[static_cast<size_t>(i)]; e < rows.first[static_cast<size_t>(i) + 1]; ++e) {
                const int32_t j = rows.column[static_cast<size_t>(e)];
                if (aggregate[static_cast<size_t>(j)] == a && !seen[static_cast<size_t>(j)]) seen[static_cast<size_t>(j)] = 1, stack.push_back(j);
            }
        }
    }
    return parts;
}

void every_aggregate_is_one_connected_part_of_one_block(void**) {
    Scene scene;
    build_scene(6, 2, scene);
    sh::vec<int32_t> aggregate;
    const int32_t count = sh::aggregate_nodes(scene.rows, aggregate);
    const int32_t nodes = scene.rows.node_count(), per_copy = nodes / 2;
    // A founder's aggregate holds it and its neighbours: 14 in a Kuhn mesh's interior, 3 to 13
    // on its surface (218 of a 7^3-node block's 343 nodes), so aggregates average 4 to 15.
    assert_true(count >= nodes / 15 && count <= nodes / 4);
    std::vector<int> size(static_cast<size_t>(count), 0);
    std::vector<int> copy_of(static_cast<size_t>(count), -1);
    for (int32_t i = 0; i < nodes; ++i) {
        const int32_t a = aggregate[static_cast<size_t>(i)];
        assert_true(a >= 0 && a < count);
        ++size[static_cast<size_t>(a)];
        int& copy = copy_of[static_cast<size_t>(a)];
        if (copy < 0) copy = i / per_copy;
        assert_int_equal(copy, i / per_copy);  // never across the copies
    }
    for (int32_t a = 0; a < count; ++a) {
        assert_true(size[static_cast<size_t>(a)] >= 1);
        assert_int_equal(parts_of(scene.rows, aggregate, a), 1);
    }
}

void founders_aggregates_hold_their_whole_neighbourhood(void**) {
    // Node 0 is visited first, with every neighbour free: its aggregate is it and them, and
    // nodes left over that joined it from next to one of them.
    Scene scene;
    build_scene(4, 1, scene);
    sh::vec<int32_t> aggregate;
    sh::aggregate_nodes(scene.rows, aggregate);
    int held = 0;
    for (int32_t j = 0; j < scene.rows.node_count(); ++j) {
        const bool near = j == 0 || neighbours(scene.rows, 0, j);
        const bool joined = aggregate[static_cast<size_t>(j)] == aggregate[0];
        if (near) assert_true(joined);
        if (joined && !near) {
            bool beside = false;
            for (int32_t k = 1; k < scene.rows.node_count(); ++k) beside = beside || (neighbours(scene.rows, 0, k) && neighbours(scene.rows, k, j));
            assert_true(beside);
        }
        held += near;
    }
    assert_int_equal(held, 8);  // the block's corner node and the 7 other corners of its cube (every Kuhn tet holds it)
}

// P as a dense matrix: its columns are the prolongations of the coarse unit vectors.
Eigen::MatrixXd dense_prolongation(sh::RigidProlongation& p, int32_t nodes) {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(3 * nodes, p.coarse_dofs());
    std::vector<double> unit(static_cast<size_t>(p.coarse_dofs()), 0.0);
    std::vector<sh::Node4> column(static_cast<size_t>(nodes));
    for (int32_t c = 0; c < p.coarse_dofs(); ++c) {
        unit.assign(unit.size(), 0.0);
        unit[static_cast<size_t>(c)] = 1.0;
        column.assign(column.size(), sh::Node4{});
        p.prolong_add(unit.data(), column.data());
        for (int32_t i = 0; i < nodes; ++i)
            for (int r = 0; r < 3; ++r) out(3 * i + r, c) = column[static_cast<size_t>(i)][r];
    }
    return out;
}

// A scene's aggregates, their prolongation and P as a dense matrix.
struct Coarse {
    Scene scene;
    sh::vec<int32_t> aggregate;
    int32_t count = 0;
    sh::RigidProlongation p;
    Eigen::MatrixXd dense;
};

void build_coarse(int cells, Coarse& out) {
    build_scene(cells, 1, out.scene);
    out.count = sh::aggregate_nodes(out.scene.rows, out.aggregate);
    out.p.build(out.aggregate, out.count, out.scene.rest.data());
    out.dense = dense_prolongation(out.p, out.scene.rows.node_count());
}

// a as a dense matrix, from its products with the unit vectors.
Eigen::MatrixXd dense_matrix(const sh::SparseSystem& a) {
    const int32_t n = a.dof_count();
    Eigen::MatrixXd out(n, n);
    std::vector<double> unit(static_cast<size_t>(n)), column(unit.size());
    for (int32_t c = 0; c < n; ++c) {
        unit.assign(unit.size(), 0.0);
        unit[static_cast<size_t>(c)] = 1.0;
        a.multiply(unit.data(), column.data());
        for (int32_t r = 0; r < n; ++r) out(r, c) = column[static_cast<size_t>(r)];
    }
    return out;
}

void prolongation_is_orthonormal_and_holds_the_rigid_motions(void**) {
    Coarse coarse;
    build_coarse(5, coarse);
    const Eigen::MatrixXd& dense = coarse.dense;
    const int32_t nodes = coarse.scene.rows.node_count(), dofs = coarse.p.coarse_dofs();
    // P^T P = I: restricting the prolongation of any u gives u back.
    assert_true((dense.transpose() * dense - Eigen::MatrixXd::Identity(dofs, dofs)).cwiseAbs().maxCoeff() < 1e-12);
    // restrict_to is P^T.
    std::vector<sh::Node4> s(static_cast<size_t>(nodes));
    Eigen::VectorXd sv(3 * nodes);
    for (int32_t d = 0; d < 3 * nodes; ++d) sv[d] = std::sin(0.3 * d) + 0.2, s[static_cast<size_t>(d / 3)][d % 3] = sv[d];
    std::vector<double> restricted(static_cast<size_t>(dofs));
    coarse.p.restrict_to(s.data(), restricted.data());
    const Eigen::VectorXd expected = dense.transpose() * sv;
    for (int32_t c = 0; c < dofs; ++c) assert_true(std::fabs(restricted[static_cast<size_t>(c)] - expected[c]) < 1e-12);
    // A rigid motion of the whole block, v_i = t + w x x_i, is in P's range: P P^T v = v.
    const Eigen::Vector3d t(0.3, -1.1, 0.7), w(0.4, 0.9, -0.5);
    Eigen::VectorXd v(3 * nodes);
    for (int32_t i = 0; i < nodes; ++i)
        v.segment<3>(3 * i) = t + w.cross(Eigen::Vector3d(&coarse.scene.rest[3 * static_cast<size_t>(i)]));
    assert_true((dense * (dense.transpose() * v) - v).cwiseAbs().maxCoeff() < 1e-10 * v.cwiseAbs().maxCoeff());
}

void galerkin_matrix_is_the_dense_triple_product(void**) {
    Coarse coarse;
    build_coarse(4, coarse);
    const Eigen::MatrixXd expected = coarse.dense.transpose() * dense_matrix(coarse.scene.a) * coarse.dense;
    sh::SparseSystem galerkin;
    coarse.p.galerkin(coarse.scene.rows, galerkin);
    assert_int_equal(galerkin.dof_count(), 6 * coarse.count);
    const double largest = expected.cwiseAbs().maxCoeff();
    assert_true((dense_matrix(galerkin) - expected).cwiseAbs().maxCoeff() <= 1e-9 * largest);
}

void flat_aggregates_have_inert_rotations_and_a_definite_coarse_matrix(void**) {
    // Aggregates chosen by hand: node 0 alone (no rotation moves it), nodes 1 and 2 on a line
    // (the rotation about it moves neither), the rest together. Their columns are zero and the
    // coarse matrix still factorises.
    Scene scene;
    build_scene(2, 1, scene);
    const int32_t nodes = scene.rows.node_count();
    sh::vec<int32_t> aggregate(static_cast<size_t>(nodes), 2);
    aggregate[0] = 0, aggregate[1] = aggregate[2] = 1;  // nodes 1, 2: (1, 0, 0), (2, 0, 0)
    sh::RigidProlongation p;
    p.build(aggregate, 3, scene.rest.data());
    const Eigen::MatrixXd dense = dense_prolongation(p, nodes);
    const Eigen::VectorXd norms = dense.colwise().norm();
    for (int c = 0; c < 18; ++c) {
        const bool inert = (c >= 3 && c < 6) || c == 6 + 3;  // node 0's rotations; the pair's about x (its line)
        assert_true(inert ? norms[c] == 0.0 : std::fabs(norms[c] - 1.0) < 1e-12);
    }
    // The coarse matrix is P^T A P with 1 on the inert DOFs' diagonal (their rows are zero).
    sh::SparseSystem coarse;
    p.galerkin(scene.rows, coarse);
    Eigen::MatrixXd expected = dense.transpose() * dense_matrix(scene.a) * dense;
    for (int c = 0; c < 18; ++c)
        if (norms[c] == 0.0) expected(c, c) += 1.0;
    assert_true((dense_matrix(coarse) - expected).cwiseAbs().maxCoeff() <= 1e-9 * expected.cwiseAbs().maxCoeff());
    sh::LinearSolverPtr solver = sh::make_linear_solver(sh::default_direct_solver(), 0.0, 1);
    solver->analyze(coarse);
    solver->factorize(coarse);  // throws if not positive definite
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_aggregate_is_one_connected_part_of_one_block),
        cmocka_unit_test(founders_aggregates_hold_their_whole_neighbourhood),
        cmocka_unit_test(prolongation_is_orthonormal_and_holds_the_rigid_motions),
        cmocka_unit_test(galerkin_matrix_is_the_dense_triple_product),
        cmocka_unit_test(flat_aggregates_have_inert_rotations_and_a_definite_coarse_matrix),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
