#include "solver/newton_body_state.hpp"

#include "model/external_field.hpp"

#include <utility>

namespace sh {

int32_t NewtonBodyState::prepare(const Body& body, const sh_implicit_settings& s, bool own_solver) {
    const int32_t n = body.node_count();
    bool changed = free_count < 0;
    int32_t count = 0;
    if (!changed)
        for (int32_t i = 0; i < n && !changed; ++i) changed = (free_index[static_cast<size_t>(i)] >= 0) != body.is_free(i);
    if (!changed) {
        if (own_solver && !matrix.solver) matrix.solver = make_analysed_solver(matrix.system, s);
        return 3 * free_count;
    }

    vec<int32_t> index(static_cast<size_t>(n), -1);
    for (int32_t i = 0; i < n; ++i)
        if (body.is_free(i)) index[static_cast<size_t>(i)] = count++;
    SparseSystem pattern;
    pattern.build_pattern(body.element_nodes(), static_cast<size_t>(body.element_count()), body.nodes_per_element(),
                          index.data(), n, count);
    LinearSolverPtr solver = own_solver ? make_analysed_solver(pattern, s) : nullptr;
    vec<double> diag(3 * static_cast<size_t>(count));
    // Commit only once everything is built (reset changes nothing if it throws).
    matrix.reset(std::move(pattern), std::move(solver));
    free_index.swap(index);
    diagonal.swap(diag);
    free_count = count;
    return 3 * count;
}

double NewtonBodyState::assemble_tangent(const Body& body, double stiffness_scale, double damping_scale, const double* v,
                                         const double* add_diagonal, double roundoff_scale) {
    SparseSystem& system = matrix.system;
    system.clear_values();
    body.add_tangent(body.x.data(), stiffness_scale, damping_scale, system);
    if (body.field)
        body.field->add_tangent(body.x.data(), v, stiffness_scale, damping_scale, free_index.data(), system);
    const double roundoff = force_roundoff(system, body.x, roundoff_scale);
    if (add_diagonal) system.add_diagonal(add_diagonal, 1.0);
    return roundoff;
}

}  // namespace sh
