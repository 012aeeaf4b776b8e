// The material table: the constitutive laws of tetrahedral elements, one row per
// sh_material_model in the enum's order, and the one place that lists them. The FEM body's
// force, energy and tangent loops and the haptic buffer's blocks run over it; adding a law is
// its header plus its row here.
//
// A row is a law type providing, per lane (kLanes elements at once):
//   kModel                                  its sh_material_model (checked against the row)
//   kProjectTangent                         true if dP/dF can be indefinite, so that the
//                                           tangent stiffness projects it to positive
//                                           semi-definite per element (in F's singular
//                                           frame: such a law must be isotropic, and
//                                           provide principal_stiffness(s, lambda, mu),
//                                           its dP/dF's eigensystem in the singular values
//                                           s: see PrincipalStiffnessLanes)
//   kRotates                                true if State holds the element's rotation R
//                                           (state.R), and the law has
//                                           stress_at(F, R, lambda, mu, state) and
//                                           energy_at(F, R, lambda, mu), P and psi with R,
//                                           F's polar rotation, given: a caller that keeps
//                                           each element's R between passes finds the next
//                                           from it (fem_kernel.hpp's kept_rotation)
//   kTangentWork                            an estimate of one element's tangent (its
//                                           dP/dF, projection and scatter) in the
//                                           floating-point operations of a sparse solve
//                                           (FactorWork): the implicit step weighs it
//                                           against factorisations and solves
//   State                                   what stress() computes that differential() reuses
//   jacobian(F, state)                      det F, for the inverted-element count
//   stress(F, lambda, mu, state)            the first Piola-Kirchhoff stress P(F)
//   differential(F, state, dF, lambda, mu)  its differential dP(F)[dF], which the
//                                           stiffness-proportional damping force takes and
//                                           a law that does not project its tangent forms
//                                           it from (the corotational law's holds R fixed,
//                                           for a dissipating damping)
//   energy(F, lambda, mu)                   the energy density psi(F)
// lambda and mu are the Lame parameters of the material's small-strain limit: every law
// reduces to linear elasticity for small strains. Every law is homogeneous of degree one in
// (lambda, mu): P, dP and psi scale with them. The element kernels use this to pass lambda and
// mu already multiplied by -V0 (see TetBlock), which yields the nodal-force matrix -V0 P and
// the element energy -V0 psi without extra products.
#pragma once

#include "core/error.hpp"
#include "material/corotational_material.hpp"
#include "material/linear_material.hpp"
#include "material/neohookean_material.hpp"
#include "material/stvk_material.hpp"

#include <softhap/softhap.h>

namespace sh {

/// A list of law types (the rows of a table).
template <class... Laws>
struct LawList {
    static constexpr int size = sizeof...(Laws);  ///< rows
};

/// The material table, indexed by sh_material_model.
using MaterialTable = LawList<LinearMaterial, StvkMaterial, CorotationalMaterial, NeoHookeanMaterial>;

/// True if row i of the list is the law of model i, for every row.
template <class... Laws>
constexpr bool rows_in_model_order(LawList<Laws...>) {
    int row = 0;
    return ((static_cast<int>(Laws::kModel) == row++) && ...);
}

static_assert(MaterialTable::size == SH_MATERIAL_COUNT, "one row per sh_material_model");
static_assert(rows_in_model_order(MaterialTable{}), "rows in the order of sh_material_model");

/// Calls visit(Law{}, model) for each row of the list, in order.
template <class... Laws, class Visit>
void for_each_law(LawList<Laws...>, Visit&& visit) {
    (visit(Laws{}, static_cast<int>(Laws::kModel)), ...);
}

/// Calls visit(Law{}, model) for each law of the material table: loops over every law's
/// elements, with the law's code inlined.
template <class Visit>
void for_each_material(Visit&& visit) {
    for_each_law(MaterialTable{}, visit);
}

/// Calls visit(Law{}) for the law of model. A model outside the table is SH_ERR_INTERNAL:
/// the API rejects it before any element has it.
template <class Visit>
void visit_material(int model, Visit&& visit) {
    bool found = false;
    for_each_material([&](auto law, int row) {
        if (row != model) return;
        found = true;
        visit(law);
    });
    SH_REQUIRE(found, SH_ERR_INTERNAL, "material model %d is not in the material table", model);
}

}  // namespace sh
