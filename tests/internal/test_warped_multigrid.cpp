// The warped two-level multigrid preconditioner (linalg/warped_multigrid.hpp) on blocks of tets
// whose system is a graph Laplacian per tet with an x-y coupling (anisotropic, so that a
// rotation changes it) plus a per-node mass: its node-block product against the sparse product; the
// cycle is a symmetric positive definite operator (CG needs both), and the product it forms
// beside itself is the matrix's; CG's iterations stay nearly
// flat as the mesh is refined (what a multigrid buys over the condition number's growth); and
// a matrix rotated rigidly as a whole is preconditioned exactly as well as the unrotated one
// when the cycle is given the rotation, and worse without it.
#include "core/error.hpp"
#include "linalg/preconditioned_cg.hpp"
#include "linalg/sparse_system.hpp"
#include "linalg/warped_multigrid.hpp"

#include "kuhn_block.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <cstdint>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

constexpr double kStiffness = 1e3, kShear = 0.6;

// The block's system: kStiffness * Q (per-tet Laplacian with shear) Q^T + m_i I per node,
// m_i = 1 + (i % 5) / 4, for the rotation Q of angle about axis (one for every node). Also
// the nodes' rest positions (unit cells). copies > 1: that many blocks along x, gap cells
// apart, sharing no element.
struct Block {
    sh::SparseSystem a;
    std::vector<double> rest;
};

void build_block(int cells, double angle, Block& out, int copies = 1, double gap = 0.0) {
    const std::vector<int32_t> tets = kuhn::copies_tets(cells, copies);
    const int32_t nodes = copies * kuhn::node_count(cells);
    std::vector<int32_t> identity(static_cast<size_t>(nodes));
    for (int32_t i = 0; i < nodes; ++i) identity[static_cast<size_t>(i)] = i;
    out.a.build_pattern(tets.data(), tets.size() / 4, 4, identity.data(), nodes, nodes);
    const Eigen::Matrix3d q = Eigen::AngleAxisd(angle, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
    Eigen::Matrix<double, 12, 12, Eigen::RowMajor> ke(kuhn::laplacian_element(kShear).data());
    Eigen::Matrix<double, 12, 12, Eigen::RowMajor> rotation = Eigen::Matrix<double, 12, 12, Eigen::RowMajor>::Zero();
    for (int b = 0; b < 4; ++b) rotation.block<3, 3>(3 * b, 3 * b) = q;
    ke = rotation * ke * rotation.transpose();
    for (size_t e = 0; e < tets.size() / 4; ++e) out.a.add_element(e, ke.data(), kStiffness);
    std::vector<double> mass(3 * static_cast<size_t>(nodes));
    for (size_t d = 0; d < mass.size(); ++d) mass[d] = 1.0 + static_cast<double>((d / 3) % 5) / 4.0;
    out.a.add_diagonal(mass.data(), 1.0);
    out.rest = kuhn::copies_rest(cells, copies, cells + gap);
}

std::vector<double> rotations_of(size_t nodes, double angle) {
    const Eigen::Matrix3d q = Eigen::AngleAxisd(angle, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
    std::vector<double> out(9 * nodes);
    for (size_t i = 0; i < nodes; ++i)
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) out[9 * i + 3 * static_cast<size_t>(r) + static_cast<size_t>(c)] = q(r, c);
    return out;
}

std::vector<double> wave(size_t n, double phase) {
    std::vector<double> b(n);
    for (size_t d = 0; d < n; ++d) b[d] = std::sin(0.7 * static_cast<double>(d) + phase) + 0.1;
    return b;
}

double dot(const std::vector<double>& a, const std::vector<double>& b) {
    double s = 0.0;
    for (size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
    return s;
}

// CG iterations to a relative residual of 1e-8 on a's system for the right-hand side b.
int cg_iterations(const sh::SparseSystem& a, sh::WarpedMultigrid& multigrid, const std::vector<double>& b) {
    const size_t n = b.size();
    sh::PreconditionedCgWork work;
    work.resize(n);
    std::vector<double> x(n);
    const sh::PreconditionedCgResult result = sh::solve_preconditioned_cg(
        a.dof_count(), [&](const double* in, double* out) { a.multiply(in, out); }, multigrid, b.data(), x.data(), false,
        1e-8, 500, work);
    assert_true(result.converged);
    return result.iterations;
}

// CG iterations to a relative residual of 1e-8 on the block's system rotated by solved_angle,
// the right-hand side rotated with it, the multigrid built at angle 0 and given the rotations
// of given_angle.
int iterations(int cells, double solved_angle, double given_angle) {
    Block rest, solved;
    build_block(cells, 0.0, rest);
    build_block(cells, solved_angle, solved);
    sh::WarpedMultigrid multigrid;
    multigrid.build(rest.a, rest.rest.data());
    const size_t n = static_cast<size_t>(rest.a.dof_count());
    sh::SparseSystem& a = rest.a;
    a.values() = solved.a.values();  // the same tets in the same order: the same pattern
    multigrid.prepare(a, rotations_of(n / 3, given_angle).data());
    const std::vector<double> q = rotations_of(1, solved_angle), plain = wave(n, 0.0);
    std::vector<double> b(n);
    for (size_t i = 0; i < n / 3; ++i)
        for (int r = 0; r < 3; ++r)
            b[3 * i + static_cast<size_t>(r)] = q[3 * static_cast<size_t>(r)] * plain[3 * i] +
                                                q[3 * static_cast<size_t>(r) + 1] * plain[3 * i + 1] +
                                                q[3 * static_cast<size_t>(r) + 2] * plain[3 * i + 2];
    return cg_iterations(a, multigrid, b);
}

// A multigrid built for the block (cells, turned by angle) at its rest shape and prepared
// with its matrix and every node's rotation of turn.
void prepare_block(int cells, double angle, double turn, Block& block, sh::WarpedMultigrid& multigrid) {
    build_block(cells, angle, block);
    multigrid.build(block.a, block.rest.data());
    multigrid.prepare(block.a, rotations_of(static_cast<size_t>(block.a.dof_count()) / 3, turn).data());
}

void cycle_is_symmetric_positive_definite(void**) {
    Block block;
    sh::WarpedMultigrid multigrid;
    prepare_block(6, 0.0, 0.5, block, multigrid);  // any rotations: still SPD
    const size_t n = static_cast<size_t>(block.a.dof_count());
    const std::vector<double> r1 = wave(n, 0.0), r2 = wave(n, 1.3);
    std::vector<double> z1(n), z2(n);
    multigrid.apply(r1.data(), z1.data());
    multigrid.apply(r2.data(), z2.data());
    const double scale = std::sqrt(dot(r1, z1) * dot(r2, z2));
    assert_true(std::fabs(dot(r2, z1) - dot(r1, z2)) <= 1e-10 * scale);
    assert_true(dot(r1, z1) > 0.0 && dot(r2, z2) > 0.0);
    assert_true(multigrid.coarse_nodes() >= 8 && multigrid.coarse_nodes() < kuhn::node_count(6) / 4);
}

void products_are_the_matrix_times_the_cycles_output(void**) {
    // apply_with_product's A z comes from the sweep's changes, not from a product: it must
    // equal the sparse system's own product of the same z, and z must be apply()'s. multiply's
    // A z, from the node blocks as the sweeps read them (each node's diagonal block, the blocks
    // it pulls from the nodes before it, the ones it pushes to them), must equal it too.
    Block block;
    sh::WarpedMultigrid multigrid;
    prepare_block(6, 0.7, 0.7, block, multigrid);
    const size_t n = static_cast<size_t>(block.a.dof_count());
    const std::vector<double> r = wave(n, 0.2);
    std::vector<double> z(n), az(n), plain(n), product(n);
    multigrid.apply(r.data(), plain.data());
    assert_true(multigrid.apply_with_product(r.data(), z.data(), az.data()));
    block.a.multiply(z.data(), product.data());
    double largest = 0.0;
    for (size_t d = 0; d < n; ++d) largest = std::fmax(largest, std::fabs(product[d]));
    std::vector<double> by_blocks(n);
    multigrid.multiply(z.data(), by_blocks.data());
    for (size_t d = 0; d < n; ++d) {
        assert_true(z[d] == plain[d]);
        // Round-off: the rows sum stiffness terms 1e3 times the largest result (measured 1.2e-12).
        assert_true(std::fabs(az[d] - product[d]) <= 1e-10 * largest);
        assert_true(std::fabs(by_blocks[d] - product[d]) <= 1e-10 * largest);
    }
}

void iterations_stay_flat_as_the_mesh_is_refined(void**) {
    // The condition number grows 4x per halving of h (kStiffness / mass dominates): plain CG's
    // iterations would double per refinement. Measured: 16, 14 and 16 at 8, 16 and 24 cells (a
    // trilinear grid took 11 each: this Laplacian's low modes are translations only, where the
    // aggregates' rotation modes that serve elasticity add nothing).
    const int coarse = iterations(8, 0.0, 0.0), middle = iterations(16, 0.0, 0.0), fine = iterations(24, 0.0, 0.0);
    assert_true(coarse <= 18 && middle <= 18 && fine <= 18);
    assert_true(fine <= coarse + 3);
}

void rotation_given_restores_the_unrotated_convergence(void**) {
    const int plain = iterations(12, 0.0, 0.0);
    const int warped = iterations(12, 2.0, 2.0);
    const int unwarped = iterations(12, 2.0, 0.0);
    assert_int_equal(warped, plain);  // the cycle for Q A0 Q^T given Q is Q (the cycle for A0) Q^T
    assert_true(unwarped > plain + 5);  // measured: 13 and 23
}

void parts_that_share_no_element_get_coarse_nodes_of_their_own(void**) {
    // Two blocks 0.3 cells apart share no element (a cut, legs side by side): a coarse node
    // tying both would pull one by the other (a grid's nodes did: 38 iterations against 11
    // alone). Each keeps the convergence it has alone.
    Block alone, apart;
    build_block(8, 0.0, alone);
    build_block(8, 0.0, apart, 2, 0.3);
    sh::WarpedMultigrid one, two;
    one.build(alone.a, alone.rest.data());
    two.build(apart.a, apart.rest.data());
    one.prepare(alone.a, rotations_of(alone.rest.size() / 3, 0.0).data());
    two.prepare(apart.a, rotations_of(apart.rest.size() / 3, 0.0).data());
    const int single = cg_iterations(alone.a, one, wave(alone.rest.size(), 0.0));
    const int pair = cg_iterations(apart.a, two, wave(apart.rest.size(), 0.0));
    assert_true(pair <= single + 2);
}

// prepare must refuse a with SH_ERR_SOLVER, naming free node `node`.
void expect_refused(const sh::SparseSystem& a, sh::WarpedMultigrid& multigrid, int32_t node) {
    bool refused = false;
    char expected[64];
    std::snprintf(expected, sizeof expected, "free node %d is not positive definite", node);
    try {
        multigrid.prepare(a, rotations_of(static_cast<size_t>(a.dof_count() / 3), 0.0).data());
    } catch (const sh::Error& e) {
        refused = e.status() == SH_ERR_SOLVER && std::strstr(e.message().c_str(), expected);
    }
    assert_true(refused);
}

void diagonal_block_not_positive_definite_is_refused_by_node(void**) {
    // Positive diagonal entries, but a coupling that makes the block indefinite: in its
    // leading 2x2 minor (node 5: x-y) or only in its determinant (node 7: y-z).
    for (const int32_t node : {5, 7}) {
        Block block;
        build_block(3, 0.0, block);
        sh::WarpedMultigrid multigrid;
        multigrid.build(block.a, block.rest.data());
        double coupling[9] = {};
        const int r = node == 5 ? 0 : 1;
        coupling[3 * r + r + 1] = coupling[3 * (r + 1) + r] = 1e6;  // the diagonal entries are about 1e4
        block.a.add_block(node, node, coupling, 1.0);
        expect_refused(block.a, multigrid, node);
    }
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(diagonal_block_not_positive_definite_is_refused_by_node),
        cmocka_unit_test(cycle_is_symmetric_positive_definite),
        cmocka_unit_test(products_are_the_matrix_times_the_cycles_output),
        cmocka_unit_test(iterations_stay_flat_as_the_mesh_is_refined),
        cmocka_unit_test(rotation_given_restores_the_unrotated_convergence),
        cmocka_unit_test(parts_that_share_no_element_get_coarse_nodes_of_their_own),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
