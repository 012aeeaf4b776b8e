#include "solver/newton_matrix.hpp"

#include "core/vec3.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace sh {
namespace {

// The backend a settings name stands for.
LinearSolverKind solver_kind(sh_linear_solver kind) {
    switch (kind) {
        case SH_LINEAR_SOLVER_CHOLMOD: return LinearSolverKind::Cholmod;
        case SH_LINEAR_SOLVER_LDLT: return LinearSolverKind::Ldlt;
        case SH_LINEAR_SOLVER_CG: return LinearSolverKind::ConjugateGradient;
        default: return default_direct_solver();
    }
}

}  // namespace

void NewtonMatrix::reset(SparseSystem&& pattern, LinearSolverPtr new_solver) {
    const size_t dofs = static_cast<size_t>(pattern.dof_count());
    vec<double> r(dofs), d(dofs, 0.0), p(dofs);
    PreconditionedCgWork work;
    work.resize(dofs);
    // Commit only once everything is built.
    system = std::move(pattern);
    solver = std::move(new_solver);
    residual.swap(r);
    delta.swap(d);
    previous_v.swap(p);
    std::swap(cg, work);
    kept.valid = false;
    multigrid.clear();
    multigrid_failed = multigrid_mode = false;
    multigrid_pause = 0;
    multigrid_pause_length = 1;
}

LinearSolverPtr make_analysed_solver(const SparseSystem& system, const sh_implicit_settings& s,
                                     const EliminationOrder* suggested) {
    LinearSolverPtr solver = make_linear_solver(solver_kind(s.linear_solver), s.cg_tolerance, s.cg_max_iterations);
    solver->analyze(system, suggested);
    return solver;
}

double force_roundoff(const SparseSystem& system, const vec<double>& x, double scale) {
    const double largest = largest_magnitude(x.data(), x.size());
    double sum = 0.0;
    for (int32_t d = 0; d < system.dof_count(); ++d) {
        const double k = scale * system.values()[static_cast<size_t>(system.diagonal_slot(d))];
        sum += k * k;
    }
    return 64.0 * std::numeric_limits<double>::epsilon() * largest * std::sqrt(sum);
}

}  // namespace sh
