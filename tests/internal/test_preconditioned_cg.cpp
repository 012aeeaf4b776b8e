// The sparse system's product and conjugate gradients preconditioned by a factorisation of a
// nearby matrix (linalg/preconditioned_cg.hpp), on a block of tets whose system is a graph
// Laplacian per tet plus a diagonal: the product against the dense matrix mirrored from the
// stored upper triangle, the CG solution against a direct solve of the same matrix, and the
// properties an inexact Newton update relies on (every iterate lowers the quadratic; one
// iteration with the exact factorisation is the exact solution).
#include "linalg/linear_solver.hpp"
#include "linalg/preconditioned_cg.hpp"
#include "linalg/sparse_system.hpp"

#include "kuhn_block.hpp"

#include <array>
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

constexpr int kCells = 5;  // cubes per side
const int32_t kNodes = kuhn::node_count(kCells);

// stiffness * (a graph Laplacian per tet, 4 I - ones per component, with an x-y coupling
// `shear` in its off-diagonal blocks) + diagonal(d) (d_i = 1 + (i % 5) / 4): symmetric
// positive definite for |shear| < 1. The pattern is built once: later calls only change the
// values (a solver analysed for it stays valid).
void assemble(sh::SparseSystem& a, double stiffness, double shear) {
    const std::vector<int32_t> tets = kuhn::block_tets(kCells);
    std::vector<int32_t> identity(kNodes);
    for (int32_t i = 0; i < kNodes; ++i) identity[static_cast<size_t>(i)] = i;
    if (a.dof_count() == 0) a.build_pattern(tets.data(), tets.size() / 4, 4, identity.data(), kNodes, kNodes);
    a.clear_values();
    const std::array<double, 144> ke = kuhn::laplacian_element(shear);
    for (size_t e = 0; e < tets.size() / 4; ++e) a.add_element(e, ke.data(), stiffness);
    std::vector<double> diagonal(3 * static_cast<size_t>(kNodes));
    for (size_t d = 0; d < diagonal.size(); ++d) diagonal[d] = 1.0 + static_cast<double>(d % 5) / 4.0;
    a.add_diagonal(diagonal.data(), 1.0);
}

// The full matrix mirrored from the stored upper triangle (row-major).
std::vector<double> dense(const sh::SparseSystem& a) {
    const size_t n = static_cast<size_t>(a.dof_count());
    std::vector<double> m(n * n, 0.0);
    for (size_t j = 0; j < n; ++j)
        for (int32_t k = a.column_starts()[j]; k < a.column_starts()[j + 1]; ++k) {
            const size_t i = static_cast<size_t>(a.row_indices()[static_cast<size_t>(k)]);
            m[i * n + j] = m[j * n + i] = a.values()[static_cast<size_t>(k)];
        }
    return m;
}

std::vector<double> right_hand_side(size_t n) {
    std::vector<double> b(n);
    for (size_t d = 0; d < n; ++d) b[d] = std::sin(0.7 * static_cast<double>(d)) + 0.1;
    return b;
}

sh::LinearSolverPtr direct_solver() {
#if SOFTHAP_WITH_CHOLMOD
    return sh::make_cholmod_solver();
#else
    return sh::make_ldlt_solver();
#endif
}

// A direct solver analysed for a and holding the factorisation of its current values.
sh::LinearSolverPtr factorised(const sh::SparseSystem& a) {
    sh::LinearSolverPtr solver = direct_solver();
    solver->analyze(a);
    solver->factorize(a);
    return solver;
}

// 1/2 x^T A x - b^T x.
double quadratic(const sh::SparseSystem& a, const std::vector<double>& b, const std::vector<double>& x) {
    std::vector<double> ax(x.size());
    a.multiply(x.data(), ax.data());
    double q = 0.0;
    for (size_t d = 0; d < x.size(); ++d) q += 0.5 * x[d] * ax[d] - b[d] * x[d];
    return q;
}

// solve_preconditioned_cg with a workspace left holding a previous solve's leftovers (NaN
// here): whatever it held must not leak into the result.
sh::PreconditionedCgResult cg(const sh::SparseSystem& a, sh::LinearSolver& preconditioner, const std::vector<double>& b,
                              std::vector<double>& x, double tolerance, int max_iterations) {
    sh::PreconditionedCgWork work;
    work.resize(b.size());
    for (sh::vec<double>* v : {&work.r, &work.z, &work.p, &work.q}) std::fill(v->begin(), v->end(), NAN);
    return sh::solve_preconditioned_cg(a, preconditioner, b.data(), x.data(), tolerance, max_iterations, work);
}

void product_matches_the_dense_matrix(void**) {
    sh::SparseSystem a;
    assemble(a, 2.0, 0.3);
    const size_t n = static_cast<size_t>(a.dof_count());
    const std::vector<double> m = dense(a), x = right_hand_side(n);
    std::vector<double> y(n, 123.0);  // multiply overwrites whatever y held
    a.multiply(x.data(), y.data());
    for (size_t i = 0; i < n; ++i) {
        double expected = 0.0;
        for (size_t j = 0; j < n; ++j) expected += m[i * n + j] * x[j];
        assert_true(std::fabs(y[i] - expected) <= 1e-12 * (1.0 + std::fabs(expected)));
    }
}

// Preconditioned by the factorisation of a stiffer, differently sheared matrix (the tangent
// of an earlier iterate), CG reaches the tolerance in a few iterations and its x solves the
// current matrix as the direct solver does, to the tolerance.
void nearby_factorisation_preconditions(void**) {
    sh::SparseSystem a;
    assemble(a, 40.0, 0.5);  // the kept factorisation's matrix
    sh::LinearSolverPtr solver = factorised(a);
    assemble(a, 50.0, 0.2);  // the current one, same pattern
    sh::LinearSolverPtr exact = factorised(a);
    const size_t n = static_cast<size_t>(a.dof_count());
    const std::vector<double> b = right_hand_side(n);
    std::vector<double> x(n, 7.0), reference(n, 0.0);  // CG starts from 0 whatever x held
    exact->solve(a, b.data(), reference.data());
    const sh::PreconditionedCgResult r = cg(a, *solver, b, x, 1e-10, 50);
    assert_true(r.converged);
    assert_true(r.iterations >= 2 && r.iterations <= 20);
    assert_true(r.relative_residual <= 1e-10);
    double worst = 0.0, largest = 0.0;
    for (size_t d = 0; d < n; ++d) {
        worst = std::fmax(worst, std::fabs(x[d] - reference[d]));
        largest = std::fmax(largest, std::fabs(reference[d]));
    }
    assert_true(worst <= 1e-8 * largest);
}

// Each extra iteration lowers the quadratic; an unconverged x at the cap is still a descent
// direction for the gradient -b (b^T x > 0).
void iterates_descend(void**) {
    sh::SparseSystem a;
    assemble(a, 10.0, 0.6);
    sh::LinearSolverPtr solver = factorised(a);
    assemble(a, 30.0, -0.4);
    const size_t n = static_cast<size_t>(a.dof_count());
    const std::vector<double> b = right_hand_side(n);
    double previous = 0.0;  // the quadratic at x = 0
    for (int cap = 1; cap <= 5; ++cap) {
        std::vector<double> x(n);
        const sh::PreconditionedCgResult r = cg(a, *solver, b, x, 1e-14, cap);
        assert_false(r.converged);
        assert_int_equal(r.iterations, cap);
        const double q = quadratic(a, b, x);
        assert_true(q < previous);
        double bx = 0.0;
        for (size_t d = 0; d < n; ++d) bx += b[d] * x[d];
        assert_true(bx > 0.0);
        previous = q;
    }
}

// With the current matrix's own factorisation, one iteration is the exact solution.
void exact_factorisation_takes_one_iteration(void**) {
    sh::SparseSystem a;
    assemble(a, 25.0, 0.1);
    sh::LinearSolverPtr solver = factorised(a);
    const size_t n = static_cast<size_t>(a.dof_count());
    const std::vector<double> b = right_hand_side(n);
    std::vector<double> x(n);
    const sh::PreconditionedCgResult r = cg(a, *solver, b, x, 1e-12, 10);
    assert_true(r.converged);
    assert_int_equal(r.iterations, 1);
}

// A matrix not positive definite along the first direction stops CG at x = 0, unconverged.
void negative_curvature_stops(void**) {
    sh::SparseSystem a;
    assemble(a, 25.0, 0.1);
    sh::LinearSolverPtr solver = factorised(a);
    for (double& v : a.values()) v = -v;
    const size_t n = static_cast<size_t>(a.dof_count());
    const std::vector<double> b = right_hand_side(n);
    std::vector<double> x(n, 1.0);
    const sh::PreconditionedCgResult r = cg(a, *solver, b, x, 1e-12, 10);
    assert_false(r.converged);
    for (const double v : x) assert_true(v == 0.0);
}

// solve_preconditioned_cg started along x's entry values (warm), preconditioned by solver.
sh::PreconditionedCgResult warm_cg(const sh::SparseSystem& a, sh::LinearSolver& solver, const std::vector<double>& b,
                                   std::vector<double>& x, double tolerance, int max_iterations) {
    sh::FactorisationPreconditioner factorisation(a, solver);
    sh::PreconditionedCgWork work;
    work.resize(b.size());
    return sh::solve_preconditioned_cg(
        a.dof_count(), [&](const double* in, double* out) { a.multiply(in, out); }, factorisation, b.data(), x.data(),
        true, tolerance, max_iterations, work);
}

// Started along the solution of a nearby system (the last time step's), CG needs fewer
// iterations to the same solution, and every capped iterate is still a descent direction.
void warm_start_along_a_nearby_solution(void**) {
    sh::SparseSystem a;
    assemble(a, 10.0, -0.4);  // a poor preconditioner, as the multigrid is on a hard system
    sh::LinearSolverPtr preconditioner = factorised(a);
    const size_t n = static_cast<size_t>(a.dof_count());
    const std::vector<double> b = right_hand_side(n);
    assemble(a, 49.0, 0.22);  // the nearby system
    std::vector<double> nearby(n), reference(n);
    factorised(a)->solve(a, b.data(), nearby.data());
    assemble(a, 50.0, 0.2);  // the current one
    factorised(a)->solve(a, b.data(), reference.data());
    // To an inexact Newton update's tolerance (cold: 7 iterations, warm: 3) and to 1e-10.
    std::vector<double> cold(n), warm = nearby;
    const int cold_iterations = cg(a, *preconditioner, b, cold, 1e-3, 50).iterations;
    assert_true(warm_cg(a, *preconditioner, b, warm, 1e-3, 50).iterations < cold_iterations - 2);
    warm = nearby;
    assert_true(warm_cg(a, *preconditioner, b, warm, 1e-10, 50).converged);
    for (size_t d = 0; d < n; ++d) assert_true(std::fabs(warm[d] - reference[d]) <= 1e-8 * std::fabs(reference[d]) + 1e-12);
    for (int cap = 1; cap <= 3; ++cap) {
        std::vector<double> x = nearby;
        warm_cg(a, *preconditioner, b, x, 1e-14, cap);
        double bx = 0.0;
        for (size_t d = 0; d < n; ++d) bx += b[d] * x[d];
        assert_true(bx > 0.0);
        assert_true(quadratic(a, b, x) < 0.0);
    }
}

// Started along the exact solution, CG is done without an iteration; along a direction
// that points uphill, or one that is not finite, it starts from 0 as a cold solve does.
void warm_start_takes_only_a_downhill_direction(void**) {
    sh::SparseSystem a;
    assemble(a, 30.0, 0.3);
    sh::LinearSolverPtr solver = factorised(a);
    sh::LinearSolverPtr preconditioner = factorised(a);
    const size_t n = static_cast<size_t>(a.dof_count());
    const std::vector<double> b = right_hand_side(n);
    std::vector<double> exact(n);
    solver->solve(a, b.data(), exact.data());
    std::vector<double> x = exact;
    const sh::PreconditionedCgResult at_solution = warm_cg(a, *preconditioner, b, x, 1e-10, 10);
    assert_true(at_solution.converged);
    assert_int_equal(at_solution.iterations, 0);
    for (size_t d = 0; d < n; ++d) assert_true(std::fabs(x[d] - exact[d]) <= 1e-10 * std::fabs(exact[d]) + 1e-14);
    std::vector<double> cold(n);
    const int cold_iterations = cg(a, *preconditioner, b, cold, 1e-12, 10).iterations;
    for (const double sign : {-1.0, std::nan("")}) {
        for (size_t d = 0; d < n; ++d) x[d] = sign * exact[d];
        assert_int_equal(warm_cg(a, *preconditioner, b, x, 1e-12, 10).iterations, cold_iterations);
        for (size_t d = 0; d < n; ++d) assert_true(x[d] == cold[d]);
    }
}

}  // namespace

int main() {
    const CMUnitTest tests[] = {
        cmocka_unit_test(product_matches_the_dense_matrix),  cmocka_unit_test(nearby_factorisation_preconditions),
        cmocka_unit_test(iterates_descend),                  cmocka_unit_test(exact_factorisation_takes_one_iteration),
        cmocka_unit_test(negative_curvature_stops),         cmocka_unit_test(warm_start_along_a_nearby_solution),
        cmocka_unit_test(warm_start_takes_only_a_downhill_direction),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
