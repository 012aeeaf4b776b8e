// The integrator table: what the solvers know of each sh_integrator, in one row per kind.
// Explicit Runge-Kutta methods are their Butcher tableaux, stepped by one routine
// (explicit_integrator.cpp); adding one is adding its row.
#pragma once

#include "model/body.hpp"
#include "solver/stepped_body.hpp"

#include <softhap/softhap.h>

namespace sh {

/// How a kind of integrator advances a body.
enum class StepScheme {
    RungeKutta,       ///< explicit, the Butcher tableau of the row
    SymplecticEuler,  ///< v += h a(x, v), then x += h v
    ImplicitEuler,    ///< backward Euler (implicit_integrator.cpp)
};

/// An explicit Runge-Kutta method for y' = F(y), y = (x, v) (autonomous: no c column).
struct ButcherTableau {
    int stages = 0;
    double a[kMaxStages][kMaxStages] = {};  ///< a[i][j], used for j < i
    double b[kMaxStages] = {};
};

/// One row of the integrator table.
struct IntegratorKind {
    const char* name;          ///< as the Python bindings spell it
    StepScheme scheme;
    ButcherTableau tableau;    ///< RungeKutta only
    /// Its critical step over leapfrog's 2 / omega_max on an undamped body (INFINITY: none).
    double stability_factor;
};

/// The row of integrator (a valid sh_integrator).
const IntegratorKind& integrator_kind(sh_integrator integrator);

/// True if integrator is a valid sh_integrator.
bool is_integrator(int integrator);

/// Critical step of body under integrator at its current state, the body's contact field
/// included (s); INFINITY for an implicit integrator.
double critical_step(const Body& body, sh_integrator integrator);

}  // namespace sh
