// A suggested elimination order (linalg/linear_solver.hpp) on a system a cut changed: a block of
// tets whose nodes on half of a mid plane are duplicated, the tets above the plane taking the
// copies (as src/cut/ separates them). The order of the uncut block, with each copy placed after
// its original, must be kept (the analysis reports the uncut order's cost, not a fresh one), and
// the solution must equal that of a fresh analysis; a poor suggestion (the reverse of a good
// order) must be dropped for a fresh ordering, whose fill the test knows from a fresh analysis.
// A backend that does not order by nodes ignores the suggestion. Also the backend laid out for
// solves (make_solve_often_solver): simplicial where CHOLMOD's supernodes would be thin, and
// refusing an indefinite matrix as the others do.
#include "linalg/linear_solver.hpp"
#include "linalg/sparse_system.hpp"

#include "core/error.hpp"

#include "kuhn_block.hpp"

#include <array>
#include <cmath>
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

constexpr int kCells = 6;  // cubes per side
constexpr int kThinSupernodeCells = 4;  // a block whose factor does 64 flops per entry (40-100)

// The SPD system of a graph Laplacian per tet (4 I - ones, times I3) plus the identity on
// tets over nodes, every node free (free index = node index).
void assemble_laplacian(const std::vector<int32_t>& tets, int32_t nodes, sh::SparseSystem& a) {
    std::vector<int32_t> identity(static_cast<size_t>(nodes));
    for (int32_t i = 0; i < nodes; ++i) identity[static_cast<size_t>(i)] = i;
    a.build_pattern(tets.data(), tets.size() / 4, 4, identity.data(), nodes, nodes);
    const std::array<double, 144> ke = kuhn::laplacian_element(0.0);
    for (size_t e = 0; e < tets.size() / 4; ++e) a.add_element(e, ke.data(), 1.0);
    std::vector<double> ones(3 * static_cast<size_t>(nodes), 1.0);
    a.add_diagonal(ones.data(), 1.0);
}

// A block of kCells^3 cubes, six tets each (Kuhn split), and the nodes of a cut: the copies
// of the nodes at z = kCells / 2 with x < kCells / 2, taken by the tets above that plane.
struct Block {
    int32_t node_count = 0;
    std::vector<int32_t> tets;     // 4 per tet
    std::vector<int32_t> parent;   // per node: the node it copies, -1 for the block's own

    static int32_t grid_node(int i, int j, int k) { return kuhn::grid_node(kCells, i, j, k); }

    Block() : node_count(kuhn::node_count(kCells)), tets(kuhn::block_tets(kCells)) {
        parent.assign(static_cast<size_t>(node_count), -1);
    }

    // Duplicates the cut's nodes; the tets above the plane that use them take the copies.
    void cut() {
        std::vector<int32_t> copy(static_cast<size_t>(node_count), -1);
        const int plane = kCells / 2;
        for (int j = 0; j <= kCells; ++j)
            for (int i = 0; i < plane; ++i) {
                const int32_t original = grid_node(i, j, plane);
                copy[static_cast<size_t>(original)] = node_count++;
                parent.push_back(original);
            }
        for (size_t t = 0; t < tets.size(); t += 4) {
            int z_sum = 0;
            for (size_t c = 0; c < 4; ++c) z_sum += tets[t + c] / ((kCells + 1) * (kCells + 1));
            if (4 * plane >= z_sum) continue;  // at or below the plane
            for (size_t c = 0; c < 4; ++c)
                if (copy[static_cast<size_t>(tets[t + c])] >= 0) tets[t + c] = copy[static_cast<size_t>(tets[t + c])];
        }
    }

    void assemble(sh::SparseSystem& a) const { assemble_laplacian(tets, node_count, a); }
};

// x with A x = b for b_d = d % 7 - 3, through solver analysed (already) for a.
std::vector<double> solve(sh::LinearSolver& solver, const sh::SparseSystem& a) {
    std::vector<double> b(static_cast<size_t>(a.dof_count())), x(b.size(), 0.0);
    for (size_t d = 0; d < b.size(); ++d) b[d] = static_cast<double>(d % 7) - 3.0;
    solver.factorize(a);
    solver.solve(a, b.data(), x.data());
    return x;
}

// The uncut block's order with each copy placed right after its original.
sh::EliminationOrder carried(const sh::EliminationOrder& uncut, const Block& block) {
    sh::EliminationOrder out = uncut;
    out.nodes.clear();
    for (const int32_t node : uncut.nodes) {
        out.nodes.push_back(node);
        for (int32_t i = 0; i < block.node_count; ++i)
            if (block.parent[static_cast<size_t>(i)] == node) out.nodes.push_back(i);
    }
    return out;
}

void assert_same_solution(const std::vector<double>& x, const std::vector<double>& reference) {
    double worst = 0.0, largest = 0.0;
    for (size_t d = 0; d < x.size(); ++d) {
        worst = std::fmax(worst, std::fabs(x[d] - reference[d]));
        largest = std::fmax(largest, std::fabs(reference[d]));
    }
    assert_true(largest > 0.1);
    assert_true(worst <= 1e-12 * largest);
}

#if SOFTHAP_WITH_CHOLMOD
// A CHOLMOD solver analysed for a (from suggested, if given); the order it chose into order.
sh::LinearSolverPtr analysed(const sh::SparseSystem& a, sh::EliminationOrder& order,
                             const sh::EliminationOrder* suggested = nullptr) {
    sh::LinearSolverPtr solver = sh::make_cholmod_solver();
    solver->analyze(a, suggested);
    assert_true(solver->elimination_order(order));
    return solver;
}

void test_carried_order_is_kept_and_solves_the_same(void**) {
    Block block;
    sh::SparseSystem uncut_system;
    block.assemble(uncut_system);
    sh::EliminationOrder uncut;
    analysed(uncut_system, uncut);
    assert_int_equal(uncut.nodes.size(), block.node_count);
    assert_true(uncut.fill_per_node > 1.0 && uncut.flops_per_node > 1.0);

    block.cut();
    sh::SparseSystem cut_system;
    block.assemble(cut_system);
    sh::EliminationOrder fresh_order, kept;
    sh::LinearSolverPtr fresh = analysed(cut_system, fresh_order);
    assert_true(fresh_order.fill_per_node != uncut.fill_per_node);  // else keeping proves nothing

    const sh::EliminationOrder suggestion = carried(uncut, block);
    sh::LinearSolverPtr given = analysed(cut_system, kept, &suggestion);
    assert_true(kept.fill_per_node == uncut.fill_per_node);  // the suggestion's baseline: it was kept
    assert_true(kept.flops_per_node == uncut.flops_per_node);
    std::vector<bool> seen(static_cast<size_t>(block.node_count), false);
    for (const int32_t node : kept.nodes) seen[static_cast<size_t>(node)] = true;
    for (int32_t i = 0; i < block.node_count; ++i) assert_true(seen[static_cast<size_t>(i)]);
    assert_same_solution(solve(*given, cut_system), solve(*fresh, cut_system));
}

void test_poor_suggestion_is_dropped_for_a_fresh_order(void**) {
    Block block;
    sh::SparseSystem system;
    block.assemble(system);
    sh::EliminationOrder good, chosen;
    sh::LinearSolverPtr fresh = analysed(system, good);
    // The reverse of a minimum-degree order eliminates the separators first: much more fill.
    sh::EliminationOrder reversed = good;
    for (size_t k = 0; k < good.nodes.size(); ++k) reversed.nodes[k] = good.nodes[good.nodes.size() - 1 - k];
    sh::LinearSolverPtr given = analysed(system, chosen, &reversed);
    assert_true(chosen.fill_per_node == good.fill_per_node);
    assert_true(chosen.nodes == good.nodes);
    assert_same_solution(solve(*given, system), solve(*fresh, system));
}

// The SPD system of assemble_laplacian on a block of cells^3 cubes.
sh::SparseSystem laplacian_block(int cells) {
    sh::SparseSystem a;
    assemble_laplacian(kuhn::block_tets(cells), kuhn::node_count(cells), a);
    return a;
}

// Laid out for solves, CHOLMOD keeps a factor simplicial where its own choice is supernodal:
// a block whose factorisation does between 40 (CHOLMOD's switch) and kSolvesSupernodalSwitch
// flops per factor entry. The layouts show in the factorisation's work estimate (a supernodal
// one runs kSupernodalSpeed times a solve's speed, a simplicial one at it, both never under 12
// solves), and both solve as the LDL^T backend does.
void test_solve_often_layout_keeps_thin_supernodes_simplicial(void**) {
    const sh::SparseSystem system = laplacian_block(kThinSupernodeCells);
    sh::LinearSolverPtr chosen = sh::make_cholmod_solver(), for_solves = sh::make_solve_often_solver();
    chosen->analyze(system);
    for_solves->analyze(system);
    const double entries = chosen->work().solve / 4.0;  // a solve's 4 operations per factor entry
    const double per_entry = for_solves->work().factorize / entries;  // fl / lnz, at a solve's speed
    assert_true(per_entry > 48.0 && per_entry < sh::kSolvesSupernodalSwitch);  // past the 12-solve floor
    assert_true(chosen->work().factorize < 0.9 * for_solves->work().factorize);
    sh::LinearSolverPtr ldlt = sh::make_ldlt_solver();
    ldlt->analyze(system);
    const std::vector<double> reference = solve(*ldlt, system);
    assert_same_solution(solve(*chosen, system), reference);
    assert_same_solution(solve(*for_solves, system), reference);
}
#endif

// The solve-often backend (a simplicial factor, with or without CHOLMOD) refuses an indefinite
// matrix by name, as the others do.
void test_solve_often_solver_refuses_an_indefinite_matrix(void**) {
    Block block;
    sh::SparseSystem system;
    block.assemble(system);
    system.values()[static_cast<size_t>(system.diagonal_slot(100))] = -50.0;
    sh::LinearSolverPtr solver = sh::make_solve_often_solver();
    solver->analyze(system);
    bool refused = false;
    try {
        solver->factorize(system);
    } catch (const sh::Error& e) {
        refused = e.status() == SH_ERR_SOLVER && std::strstr(e.message().c_str(), "not positive definite");
    }
    assert_true(refused);
}

void test_ldlt_ignores_the_suggestion(void**) {
    Block block;
    sh::SparseSystem system;
    block.assemble(system);
    sh::EliminationOrder order;
    for (int32_t i = block.node_count - 1; i >= 0; --i) order.nodes.push_back(i);
    sh::LinearSolverPtr ldlt = sh::make_ldlt_solver();
    ldlt->analyze(system, &order);
    sh::EliminationOrder none;
    assert_false(ldlt->elimination_order(none));
    assert_true(none.nodes.empty());
    sh::LinearSolverPtr plain = sh::make_ldlt_solver();
    plain->analyze(system);
    assert_same_solution(solve(*ldlt, system), solve(*plain, system));
}

void test_suggestion_of_the_wrong_size_is_refused(void**) {
    Block block;
    sh::SparseSystem system;
    block.assemble(system);
    sh::EliminationOrder short_order;
    short_order.nodes.assign(3, 0);
    sh::LinearSolverPtr solver = sh::make_ldlt_solver();
    bool refused = false;
    try {
        solver->analyze(system, &short_order);
    } catch (const sh::Error& e) {
        refused = e.status() == SH_ERR_INTERNAL;
    }
    assert_true(refused);
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
#if SOFTHAP_WITH_CHOLMOD
        cmocka_unit_test(test_carried_order_is_kept_and_solves_the_same),
        cmocka_unit_test(test_poor_suggestion_is_dropped_for_a_fresh_order),
        cmocka_unit_test(test_solve_often_layout_keeps_thin_supernodes_simplicial),
#endif
        cmocka_unit_test(test_solve_often_solver_refuses_an_indefinite_matrix),
        cmocka_unit_test(test_ldlt_ignores_the_suggestion),
        cmocka_unit_test(test_suggestion_of_the_wrong_size_is_refused),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
