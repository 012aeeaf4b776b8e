// The assembly order of a sparse system (SparseSystem::build_pattern's element_order): the
// scatter map is laid out in it, and the matrix must not depend on it. A Kuhn block of 48 tets,
// with two nodes fixed and the free nodes numbered out of the file's order, each tet adding a
// different element matrix: assembled in the elements' order and in a shuffled one, the
// system's product is the dense sum of the element matrices written out by hand, also when
// each is added from its node blocks told a wrong place in the order. An order that is not a
// permutation is refused, naming its entry, and leaves the system empty.
#include "linalg/sparse_system.hpp"

#include "core/error.hpp"
#include "kuhn_block.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
}

namespace {

constexpr int kCells = 2;
const int32_t kFixed[2] = {0, 13};

// Free index per node: the fixed nodes -1, the others numbered from the last node down.
std::vector<int32_t> free_index(int32_t& count) {
    const int32_t n = kuhn::node_count(kCells);
    std::vector<int32_t> index(static_cast<size_t>(n), 0);
    for (const int32_t f : kFixed) index[static_cast<size_t>(f)] = -1;
    count = 0;
    for (int32_t i = n - 1; i >= 0; --i)
        if (index[static_cast<size_t>(i)] == 0) index[static_cast<size_t>(i)] = count++;
    return index;
}

// Tet e's element matrix: its Laplacian with its own shear, times e + 1.
std::array<double, 144> element_matrix(size_t e) {
    std::array<double, 144> ke = kuhn::laplacian_element(0.1 * static_cast<double>(e % 7) - 0.3);
    for (double& v : ke) v *= static_cast<double>(e + 1);
    return ke;
}

// The sum of the element matrices over the free DOFs, written out densely.
Eigen::MatrixXd dense_reference(const std::vector<int32_t>& tets, const std::vector<int32_t>& index, int32_t count) {
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(3 * count, 3 * count);
    for (size_t e = 0; e < tets.size() / 4; ++e) {
        const std::array<double, 144> ke = element_matrix(e);
        for (int p = 0; p < 12; ++p)
            for (int q = 0; q < 12; ++q) {
                const int32_t fi = index[static_cast<size_t>(tets[4 * e + static_cast<size_t>(p / 3)])];
                const int32_t fj = index[static_cast<size_t>(tets[4 * e + static_cast<size_t>(q / 3)])];
                if (fi >= 0 && fj >= 0) m(3 * fi + p % 3, 3 * fj + q % 3) += ke[static_cast<size_t>(12 * p + q)];
            }
    }
    return m;
}

// The system's matrix, column by column from its products with the unit vectors.
Eigen::MatrixXd product_columns(const sh::SparseSystem& a) {
    const int32_t n = a.dof_count();
    Eigen::MatrixXd m(n, n);
    std::vector<double> unit(static_cast<size_t>(n), 0.0), column(static_cast<size_t>(n));
    for (int32_t d = 0; d < n; ++d) {
        unit[static_cast<size_t>(d)] = 1.0;
        a.multiply(unit.data(), column.data());
        unit[static_cast<size_t>(d)] = 0.0;
        for (int32_t r = 0; r < n; ++r) m(r, d) = column[static_cast<size_t>(r)];
    }
    return m;
}

// Builds the pattern with order (null: the elements' own) and adds every element in it.
void assemble(sh::SparseSystem& a, const std::vector<int32_t>& tets, const std::vector<int32_t>& index,
              int32_t count, const std::vector<int32_t>* order) {
    const size_t elements = tets.size() / 4;
    a.build_pattern(tets.data(), elements, 4, index.data(), kuhn::node_count(kCells), count, nullptr, 0,
                    order ? order->data() : nullptr);
    for (size_t p = 0; p < elements; ++p) {
        const size_t e = order ? static_cast<size_t>((*order)[p]) : p;
        a.add_element(e, element_matrix(e).data(), 1.0);
    }
}

// The block, its free numbering, the dense reference and the elements in a shuffled order.
struct Scene {
    std::vector<int32_t> tets = kuhn::block_tets(kCells);
    int32_t count = 0;
    std::vector<int32_t> index = free_index(count);
    Eigen::MatrixXd reference = dense_reference(tets, index, count);
    std::vector<int32_t> shuffled;
    explicit Scene(unsigned seed) : shuffled(tets.size() / 4) {
        std::iota(shuffled.begin(), shuffled.end(), 0);
        std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(seed));
        assert_true(shuffled[0] != 0 || shuffled[1] != 1);
    }
    // a's matrix is the reference to round-off.
    void check(const sh::SparseSystem& a) const {
        assert_int_equal(a.dof_count(), 3 * count);
        const double worst = (product_columns(a) - reference).cwiseAbs().maxCoeff();
        assert_true(reference.cwiseAbs().maxCoeff() > 10.0);
        assert_true(worst <= 1e-12 * reference.cwiseAbs().maxCoeff());
    }
};

void test_the_matrix_does_not_depend_on_the_assembly_order(void**) {
    const Scene scene(7);
    const std::vector<int32_t>* orders[2] = {nullptr, &scene.shuffled};
    for (const std::vector<int32_t>* order : orders) {
        sh::SparseSystem a;
        assemble(a, scene.tets, scene.index, scene.count, order);
        scene.check(a);
    }
}

// Ke in node blocks, as add_element_lane reads a lane (stride 1): entry (3a + r, 3b + s) at
// ((4a + b) 9 + 3r + s).
std::array<double, 144> node_blocks(const std::array<double, 144>& ke) {
    std::array<double, 144> blocks{};
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
            for (int r = 0; r < 3; ++r)
                for (int s = 0; s < 3; ++s)
                    blocks[static_cast<size_t>((4 * a + b) * 9 + 3 * r + s)] =
                        ke[static_cast<size_t>(12 * (3 * a + r) + 3 * b + s)];
    return blocks;
}

void test_lanes_added_at_any_expected_place_give_the_same_matrix(void**) {
    // Each element added from its node blocks, told its true place in the order, or a wrong
    // one (always 0, or past the end): the matrix is the same.
    const Scene scene(11);
    const std::vector<int32_t>& order = scene.shuffled;
    for (int told = 0; told < 3; ++told) {
        sh::SparseSystem a;
        a.build_pattern(scene.tets.data(), order.size(), 4, scene.index.data(), kuhn::node_count(kCells), scene.count,
                        nullptr, 0, order.data());
        for (size_t p = 0; p < order.size(); ++p) {
            const size_t e = static_cast<size_t>(order[p]);
            const size_t place = told == 0 ? p : told == 1 ? 0 : order.size() + p;
            a.add_element_lane(e, place, node_blocks(element_matrix(e)).data(), 1, 1.0);
        }
        scene.check(a);
    }
}

// build_pattern with order must refuse it with a message holding `names`, leaving a empty.
void expect_refused(const std::vector<int32_t>& order, const char* names) {
    const std::vector<int32_t> tets = kuhn::block_tets(kCells);
    int32_t count = 0;
    const std::vector<int32_t> index = free_index(count);
    sh::SparseSystem a;
    assemble(a, tets, index, count, nullptr);
    bool refused = false;
    try {
        a.build_pattern(tets.data(), tets.size() / 4, 4, index.data(), kuhn::node_count(kCells), count, nullptr, 0,
                        order.data());
    } catch (const sh::Error& e) {
        refused = e.status() == SH_ERR_INVALID_ARGUMENT && std::strstr(e.message().c_str(), names);
    }
    assert_true(refused);
    assert_int_equal(a.dof_count(), 0);
    assert_int_equal(a.nonzero_count(), 0);
}

void test_an_order_that_is_not_a_permutation_is_refused_by_entry(void**) {
    std::vector<int32_t> order(kuhn::block_tets(kCells).size() / 4);
    std::iota(order.begin(), order.end(), 0);
    std::vector<int32_t> repeated = order;
    repeated[5] = 2;
    expect_refused(repeated, "element_order[5] = 2");
    std::vector<int32_t> outside = order;
    outside[3] = static_cast<int32_t>(order.size());
    expect_refused(outside, "element_order[3] = 48");
    std::vector<int32_t> negative = order;
    negative[0] = -1;
    expect_refused(negative, "element_order[0] = -1");
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_matrix_does_not_depend_on_the_assembly_order),
        cmocka_unit_test(test_lanes_added_at_any_expected_place_give_the_same_matrix),
        cmocka_unit_test(test_an_order_that_is_not_a_permutation_is_refused_by_entry),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
