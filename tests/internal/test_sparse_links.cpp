// Links in a sparse system's pattern (SparseSystem::build_pattern's links): blocks between nodes
// that share no element, as a contact spanning several faces couples them. Two tets with no
// node in common, linked across: the pattern holds exactly the linked blocks beside the
// elements' (its stored count follows the header's formula), add_block reaches them and no
// other block between the tets, every solver solves the linked system as a dense solve of the
// same matrix written out by hand does, and a link naming a node out of range is refused with a
// message that says it is a link.
#include "linalg/linear_solver.hpp"
#include "linalg/sparse_system.hpp"

#include "core/error.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

constexpr int32_t kNodes = 8;
const int32_t kTets[8] = {0, 1, 2, 3, 4, 5, 6, 7};  // two tets, no node in common
const int32_t kLinks[6] = {1, 6, 5, 2, 3, 3};        // (3, 3): a node linked to itself adds nothing
constexpr size_t kLinkCount = 3;
constexpr double kCoupling = -0.75;  // the linked blocks: kCoupling times the identity

std::vector<int32_t> identity() {
    std::vector<int32_t> index(kNodes);
    for (int32_t i = 0; i < kNodes; ++i) index[static_cast<size_t>(i)] = i;
    return index;
}

// Per tet, the graph Laplacian (4 I - ones, times I3): the element matrix, and the dense one.
void element_matrix(double ke[144]) {
    for (int r = 0; r < 12; ++r)
        for (int c = 0; c < 12; ++c) ke[12 * r + c] = r % 3 == c % 3 ? (r / 3 == c / 3 ? 3.0 : -1.0) : 0.0;
}

// The system: both tets' Laplacians, the links' coupling blocks, 4 on the diagonal.
void assemble(sh::SparseSystem& a) {
    const std::vector<int32_t> index = identity();
    a.build_pattern(kTets, 2, 4, index.data(), kNodes, kNodes, kLinks, kLinkCount);
    double ke[144];
    element_matrix(ke);
    a.add_element(0, ke, 1.0);
    a.add_element(1, ke, 1.0);
    const double block[9] = {kCoupling, 0.0, 0.0, 0.0, kCoupling, 0.0, 0.0, 0.0, kCoupling};
    a.add_block(1, 6, block, 1.0);
    a.add_block(5, 2, block, 1.0);
    std::vector<double> diagonal(3 * kNodes, 4.0);
    a.add_diagonal(diagonal.data(), 1.0);
}

// The same matrix written out densely from its definition.
Eigen::MatrixXd dense_reference() {
    Eigen::MatrixXd m = Eigen::MatrixXd::Identity(3 * kNodes, 3 * kNodes) * 4.0;
    for (int t = 0; t < 2; ++t)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                for (int c = 0; c < 3; ++c) m(3 * (4 * t + a) + c, 3 * (4 * t + b) + c) += a == b ? 3.0 : -1.0;
    for (size_t l = 0; l < 2; ++l) {
        const int i = kLinks[2 * l], j = kLinks[2 * l + 1];
        for (int c = 0; c < 3; ++c) {
            m(3 * i + c, 3 * j + c) += kCoupling;
            m(3 * j + c, 3 * i + c) += kCoupling;
        }
    }
    return m;
}

void test_pattern_holds_the_linked_blocks(void**) {
    sh::SparseSystem a;
    assemble(a);
    assert_true(a.has_block(1, 6) && a.has_block(6, 1) && a.has_block(2, 5));
    assert_false(a.has_block(0, 7));
    assert_false(a.has_block(1, 5));
    // 6 per node, 9 per pair: 6 pairs in each tet and the 2 links across.
    assert_int_equal(a.nonzero_count(), 6 * kNodes + 9 * (6 + 6 + 2));
    const double block[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    bool refused = false;
    try {
        a.add_block(0, 7, block, 1.0);
    } catch (const sh::Error& e) {
        refused = e.status() == SH_ERR_INTERNAL;
    }
    assert_true(refused);
}

void test_every_solver_solves_the_linked_system(void**) {
    sh::SparseSystem a;
    assemble(a);
    Eigen::VectorXd b(3 * kNodes);
    for (int d = 0; d < 3 * kNodes; ++d) b(d) = static_cast<double>(d % 5) - 2.0;
    const Eigen::VectorXd reference = dense_reference().ldlt().solve(b);
    std::vector<sh::LinearSolverPtr> solvers;
    solvers.push_back(sh::make_ldlt_solver());
    solvers.push_back(sh::make_cg_solver(1e-14, 500));
#if SOFTHAP_WITH_CHOLMOD
    solvers.push_back(sh::make_cholmod_solver());
    solvers.push_back(sh::make_cholmod_solver(sh::CholmodLayout::ForSolves));
#endif
    solvers.push_back(sh::make_solve_often_solver());
    for (sh::LinearSolverPtr& solver : solvers) {
        std::vector<double> x(3 * kNodes, 0.0);
        solver->analyze(a);
        solver->factorize(a);
        solver->solve(a, b.data(), x.data());
        double worst = 0.0;
        for (int d = 0; d < 3 * kNodes; ++d) worst = std::fmax(worst, std::fabs(x[static_cast<size_t>(d)] - reference(d)));
        assert_true(reference.cwiseAbs().maxCoeff() > 0.1);
        assert_true(worst <= 1e-10 * reference.cwiseAbs().maxCoeff());
    }
}

void test_a_link_out_of_range_is_refused_by_name(void**) {
    const std::vector<int32_t> index = identity();
    const int32_t bad[2] = {2, kNodes};
    sh::SparseSystem a;
    bool refused = false;
    try {
        a.build_pattern(kTets, 2, 4, index.data(), kNodes, kNodes, bad, 1);
    } catch (const sh::Error& e) {
        refused = e.status() == SH_ERR_INVALID_ARGUMENT && std::strstr(e.message().c_str(), "link 0 node 1 is 8");
    }
    assert_true(refused);
    assert_int_equal(a.dof_count(), 0);  // left empty
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pattern_holds_the_linked_blocks),
        cmocka_unit_test(test_every_solver_solves_the_linked_system),
        cmocka_unit_test(test_a_link_out_of_range_is_refused_by_name),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
