#include "linalg/preconditioned_cg.hpp"

#include "core/clock.hpp"
#include "core/memory.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

double dot(const double* a, const double* b, size_t n) {
    double s = 0.0;
    for (size_t i = 0; i < n; ++i) s += a[i] * b[i];
    return s;
}

double dot(const vec<double>& a, const vec<double>& b) { return dot(a.data(), b.data(), a.size()); }

// x := c x with c = x^T b / x^T A x, the quadratic's minimiser along x (0 where c is not
// positive and finite: a guess pointing uphill, or none), and r := b - A x.
void start_along(const std::function<void(const double*, double*)>& multiply, const double* b, double* x,
                 vec<double>& r, vec<double>& ax) {
    const size_t n = r.size();
    multiply(x, ax.data());
    const double c = dot(x, b, n) / dot(x, ax.data(), n);
    const bool along = std::isfinite(c) && c > 0.0;
    for (size_t i = 0; i < n; ++i) {
        x[i] = along ? c * x[i] : 0.0;
        r[i] = along ? b[i] - c * ax[i] : b[i];
    }
}

}  // namespace

void PreconditionedCgWork::resize(size_t n) {
    vec<double> fresh[5] = {vec<double>(n), vec<double>(n), vec<double>(n), vec<double>(n), vec<double>(n)};
    r.swap(fresh[0]), z.swap(fresh[1]), p.swap(fresh[2]), q.swap(fresh[3]), az.swap(fresh[4]);
}

PreconditionedCgResult solve_preconditioned_cg(int32_t dof_count, const std::function<void(const double*, double*)>& multiply,
                                               Preconditioner& preconditioner, const double* b, double* x, bool warm,
                                               double tolerance, int max_iterations, PreconditionedCgWork& work) {
    const double t0 = now_seconds();
    PreconditionedCgResult out;
    const size_t n = static_cast<size_t>(dof_count);
    vec<double>&r = work.r, &z = work.z, &p = work.p, &q = work.q;
    const double b_norm = std::sqrt(dot(b, b, n));
    if (warm && b_norm > 0.0) start_along(multiply, b, x, r, q);
    else
        for (size_t i = 0; i < n; ++i) x[i] = 0.0, r[i] = b[i];
    out.relative_residual = b_norm > 0.0 ? std::sqrt(dot(r, r)) / b_norm : 0.0;
    out.converged = out.relative_residual <= tolerance;
    if (out.converged) {  // b = 0, or the start along x already meets the tolerance
        out.seconds = now_seconds() - t0;
        return out;
    }
    // q = A p: from the preconditioner's A z where it gives it (the same for every apply).
    const bool fused = preconditioner.apply_with_product(r.data(), z.data(), q.data());
    std::copy(z.begin(), z.end(), p.begin());
    double rz = dot(r, z);
    double carried = fused ? dot(p, q) : 0.0;  // p^T q, from the pass that made them where fused
    while (out.iterations < max_iterations) {
        if (!fused) multiply(p.data(), q.data());
        ++out.iterations;
        const double curvature = fused ? carried : dot(p, q);
        if (!(curvature > 0.0) || !(rz > 0.0)) break;
        const double alpha = rz / curvature;
        double rr = 0.0;  // |r|^2 in the same pass: one read of r where a dot of its own takes two
        for (size_t i = 0; i < n; ++i) {
            x[i] += alpha * p[i];
            r[i] -= alpha * q[i];
            rr += r[i] * r[i];
        }
        out.relative_residual = std::sqrt(rr) / b_norm;
        if (out.relative_residual <= tolerance) {
            out.converged = true;
            break;
        }
        // A z lands in az (work.z's partner) while q still holds A p_old.
        if (fused) preconditioner.apply_with_product(r.data(), z.data(), work.az.data());
        else preconditioner.apply(r.data(), z.data());
        const double rz_next = dot(r, z);
        const double beta = rz_next / rz;
        rz = rz_next;
        if (fused) {
            carried = 0.0;
            for (size_t i = 0; i < n; ++i) {
                p[i] = z[i] + beta * p[i];
                q[i] = work.az[i] + beta * q[i];
                carried += p[i] * q[i];  // the next curvature, in the same pass
            }
        } else {
            for (size_t i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
        }
    }
    out.seconds = now_seconds() - t0;
    return out;
}

PreconditionedCgResult solve_preconditioned_cg(const SparseSystem& a, LinearSolver& preconditioner, const double* b,
                                               double* x, double tolerance, int max_iterations,
                                               PreconditionedCgWork& work) {
    FactorisationPreconditioner factorisation(a, preconditioner);
    return solve_preconditioned_cg(
        a.dof_count(), [&](const double* in, double* out) { a.multiply(in, out); }, factorisation, b, x, false,
        tolerance, max_iterations, work);
}

}  // namespace sh
