#include "solver/newton_body_state.hpp"

#include "model/external_field.hpp"
#include "solver/free_node_order.hpp"
#include "solver/node_links.hpp"

#include <utility>

namespace sh {
namespace {

// The elimination order the body's last analysis chose (as body nodes), carried over to the
// free nodes of index: a node keeps its place, a node added since (a cut's copy) follows its
// oldest ancestor in the order, and any other node goes last. false if there is no order.
bool carried_order(const Body& body, const EliminationOrder& last, const vec<int32_t>& index, int32_t free_count,
                   EliminationOrder& out) {
    const vec<int32_t>& elimination_nodes = last.nodes;
    if (elimination_nodes.empty()) return false;
    const int32_t n = body.node_count();
    vec<int32_t> rank(static_cast<size_t>(n), -1);
    for (size_t p = 0; p < elimination_nodes.size(); ++p)
        if (elimination_nodes[p] < n) rank[static_cast<size_t>(elimination_nodes[p])] = static_cast<int32_t>(p);
    int32_t ranks = static_cast<int32_t>(elimination_nodes.size());
    for (int32_t i = 0; i < n; ++i) {
        int32_t& r = rank[static_cast<size_t>(i)];
        const int32_t parent = body.parent_of(i);
        if (r < 0) r = parent >= 0 && parent < i ? rank[static_cast<size_t>(parent)] : ranks++;
    }
    // Counting sort of the free nodes by rank; equal ranks (a node and its copies) by index.
    vec<int32_t> start(static_cast<size_t>(ranks) + 1, 0);
    for (int32_t i = 0; i < n; ++i)
        if (index[static_cast<size_t>(i)] >= 0) ++start[static_cast<size_t>(rank[static_cast<size_t>(i)]) + 1];
    for (size_t r = 0; r < static_cast<size_t>(ranks); ++r) start[r + 1] += start[r];
    out.nodes.resize(static_cast<size_t>(free_count));
    for (int32_t i = 0; i < n; ++i)
        if (index[static_cast<size_t>(i)] >= 0)
            out.nodes[static_cast<size_t>(start[static_cast<size_t>(rank[static_cast<size_t>(i)])]++)] =
                index[static_cast<size_t>(i)];
    out.fill_per_node = last.fill_per_node;
    out.flops_per_node = last.flops_per_node;
    return true;
}

// solver's elimination order over pattern's free nodes, as body nodes, into out; false if the
// solver has none.
bool chosen_order(const LinearSolver* solver, const SparseSystem& pattern, EliminationOrder& out) {
    if (!solver || !solver->elimination_order(out)) return false;
    for (int32_t& f : out.nodes) f = pattern.dof_to_global()[3 * static_cast<size_t>(f)] / 3;
    return true;
}

}  // namespace

int32_t NewtonBodyState::prepare(const Body& body, const sh_implicit_settings& s, bool own_solver) {
    const int32_t n = body.node_count();
    bool changed = free_count < 0;
    int32_t count = 0;
    if (!changed)
        for (int32_t i = 0; i < n && !changed; ++i) changed = (free_index[static_cast<size_t>(i)] >= 0) != body.is_free(i);
    link_pairs.clear();
    if (body.field) body.field->add_tangent_links(link_pairs);
    collect_link_keys(link_pairs, needed_links);
    vec<uint64_t> grown;
    if (!links_to_build(links, needed_links, changed, grown)) {
        if (own_solver && !matrix.solver) matrix.solver = make_analysed_solver(matrix.system, s);
        return 3 * free_count;
    }

    vec<int32_t> index;
    count = number_free_nodes(body, index);
    link_key_pairs(grown, link_pairs);
    SparseSystem pattern;
    pattern.build_pattern(body.element_nodes(), static_cast<size_t>(body.element_count()), body.nodes_per_element(),
                          index.data(), n, count, link_pairs.data(), link_pairs.size() / 2, body.tangent_order());
    EliminationOrder suggested;
    const bool suggest = own_solver && carried_order(body, elimination, index, count, suggested);
    LinearSolverPtr solver = own_solver ? make_analysed_solver(pattern, s, suggest ? &suggested : nullptr) : nullptr;
    EliminationOrder chosen;
    const bool ordered = chosen_order(solver.get(), pattern, chosen);
    vec<double> diag(3 * static_cast<size_t>(count));
    // Commit only once everything is built (reset changes nothing if it throws).
    matrix.reset(std::move(pattern), std::move(solver));
    free_index.swap(index);
    diagonal.swap(diag);
    links.swap(grown);
    if (ordered) std::swap(elimination, chosen);  // else the last order stays for the next analysis
    free_count = count;
    return 3 * count;
}

double NewtonBodyState::assemble_tangent(const Body& body, const double* x, double stiffness_scale, double damping_scale,
                                         const double* v, const double* add_diagonal, double roundoff_scale) {
    SparseSystem& system = matrix.system;
    system.clear_values();
    body.add_tangent(x, stiffness_scale, damping_scale, system);
    if (body.field) body.field->add_tangent(x, v, stiffness_scale, damping_scale, free_index.data(), system);
    const double roundoff = force_roundoff(system, body.x, roundoff_scale);
    if (add_diagonal) system.add_diagonal(add_diagonal, 1.0);
    return roundoff;
}

}  // namespace sh
