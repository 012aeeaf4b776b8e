// Conjugate gradients with a preconditioner: a direct solver's factorisation of a nearby matrix
// (one kept from an earlier Newton iterate or step serves the current tangent with a few
// iterations instead of a new factorisation) or a multigrid cycle.
#pragma once

#include "linalg/linear_solver.hpp"
#include "linalg/sparse_system.hpp"

#include <functional>

namespace sh {

/// z = M^-1 r for a symmetric positive definite M near the system's matrix.
class Preconditioner {
public:
    virtual ~Preconditioner() = default;
    /// z = M^-1 r (dof_count values each; they must not overlap).
    virtual void apply(const double* r, double* z) = 0;
    /// apply(), and az = A z where the preconditioner can form it for less than a product
    /// with A (the system's matrix); returns false, az untouched, where it cannot.
    virtual bool apply_with_product(const double* r, double* z, double* az) {
        (void)az;
        apply(r, z);
        return false;
    }
};

/// A direct solver's factorisation of a matrix with a's pattern as the preconditioner:
/// z = (factorised matrix)^-1 r.
class FactorisationPreconditioner final : public Preconditioner {
public:
    /// Keeps references to both: they must outlive it.
    FactorisationPreconditioner(const SparseSystem& a, LinearSolver& solver) : a_(a), solver_(solver) {}
    void apply(const double* r, double* z) override { solver_.solve(a_, r, z); }

private:
    const SparseSystem& a_;
    LinearSolver& solver_;
};

/// solve_preconditioned_cg's vectors, kept by its caller beside the matrix so that a solve
/// allocates nothing (sized for a.dof_count() by resize).
struct PreconditionedCgWork {
    vec<double> r, z, p, q;  ///< residual, preconditioned residual, direction, A direction
    vec<double> az;          ///< A z, where the preconditioner forms it
    /// Sizes the vectors for n DOFs; throws std::bad_alloc, changing nothing else.
    void resize(size_t n);
};

/// What solve_preconditioned_cg reached.
struct PreconditionedCgResult {
    int iterations = 0;              ///< matrix products (each with one preconditioner solve)
    bool converged = false;          ///< |b - A x| <= tolerance |b|
    double relative_residual = 1.0;  ///< |b - A x| / |b| at the end
    double seconds = 0.0;            ///< wall time, preconditioner solves included
};

/// Solves A x = b for the current values of a (symmetric positive definite expected) by
/// conjugate gradients from x = 0, each residual preconditioned by preconditioner.solve (a
/// direct solver whose factorisation, of a matrix with a's pattern, stays as it was). Stops when
/// |b - A x| <= tolerance |b| or after max_iterations; x then holds the last iterate. Each
/// iterate lowers the quadratic 1/2 x^T A x - b^T x further, so for b = -g (g a gradient) every
/// iterate is a descent direction. A curvature p^T A p that is not positive (A not positive
/// definite along p) stops it unconverged at the iterate before. Throws what the
/// preconditioner's solve throws. work must be sized for a.dof_count().
PreconditionedCgResult solve_preconditioned_cg(const SparseSystem& a, LinearSolver& preconditioner, const double* b,
                                               double* x, double tolerance, int max_iterations,
                                               PreconditionedCgWork& work);

/// The same with any preconditioner; multiply(x, y) computes y = A x. Where the
/// preconditioner returns A z beside z (apply_with_product), A p follows from the recurrence
/// A p = A z + beta A p_old, and multiply serves only where it does not. With warm, x holds on
/// entry a direction to start along (the solution of a nearby system, such as the last time
/// step's): CG starts from its multiple that minimises the quadratic, c = x^T b / x^T A x, for
/// one more product, or from 0 where c is not positive and finite. The quadratic is then below
/// its value at 0 from the start, so every iterate is still a descent direction.
PreconditionedCgResult solve_preconditioned_cg(int32_t dof_count, const std::function<void(const double*, double*)>& multiply,
                                               Preconditioner& preconditioner, const double* b, double* x, bool warm,
                                               double tolerance, int max_iterations, PreconditionedCgWork& work);

}  // namespace sh
