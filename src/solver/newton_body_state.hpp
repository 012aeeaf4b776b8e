// NewtonBodyState: what one body keeps from one Newton solve to the next (implicit steps, static
// solves): which of its nodes are free and in what order (its free-node index map), and its own
// matrix over their DOFs, assembled from its elements, its field and its mass. A body solved
// alone factorises that matrix; a body solved together with others (NewtonProblem::prepare) has
// it assembled and then added into their joint matrix. Its solver's elimination order outlives a
// topology change, so that the analysis after a cut extends it instead of ordering afresh.
#pragma once

#include "core/memory.hpp"
#include "model/body.hpp"
#include "solver/newton_matrix.hpp"

#include <softhap/softhap.h>

#include <cstdint>

namespace sh {

/// Per-body data of the Newton solves, built on first use and kept across steps while the
/// body's free nodes stay the same.
struct NewtonBodyState {
    vec<int32_t> free_index;  ///< per node: its index among the body's free nodes, or -1
    int32_t free_count = -1;  ///< free nodes of the body; -1: not prepared yet
    NewtonMatrix matrix;      ///< the body's own matrix over its free DOFs (3 per free node)
    vec<double> diagonal;     ///< per free DOF: the diagonal added to the tangent (scratch)
    EliminationOrder elimination;  ///< its solver's elimination order, as the body's node indices (empty: none)
    vec<uint64_t> links;           ///< node links the pattern holds beyond the elements (node_links.hpp)
    vec<uint64_t> needed_links;    ///< scratch: the links the body's field asks for now
    vec<int32_t> link_pairs;       ///< scratch: node pairs as the field reports them

    /// Rebuilds free_index and the matrix's pattern (and, with own_solver, its solver and
    /// symbolic analysis) if body's free nodes changed since the last call, or if its field
    /// asks for a link (ExternalField::add_tangent_links) the pattern lacks; makes the solver
    /// if own_solver and there is none yet. Returns the number of free DOFs.
    int32_t prepare(const Body& body, const sh_implicit_settings& settings, bool own_solver = true);

    /// The body's topology changed: the next prepare rebuilds the pattern and the analysis,
    /// suggesting the last elimination order with each added node placed after its parent.
    void forget_pattern() noexcept {
        free_count = -1;
        matrix.kept.valid = false;
    }

    /// Clears the matrix and adds stiffness_scale K + damping_scale D of body at positions x
    /// (3 per node; body.x, or e.g. its rest shape) and velocities v (null: at rest) from its
    /// elements and its field, then add_diagonal (per free DOF) if not null. Returns the
    /// round-off of the body's forces at body.x: force_roundoff of the matrix before the
    /// diagonal, with roundoff_scale.
    double assemble_tangent(const Body& body, const double* x, double stiffness_scale, double damping_scale,
                            const double* v, const double* add_diagonal, double roundoff_scale);
};

}  // namespace sh
