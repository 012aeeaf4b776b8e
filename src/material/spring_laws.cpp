#include "material/spring_laws.hpp"

#include "core/enum_value.hpp"
#include "core/error.hpp"

#include <algorithm>
#include <cmath>

namespace sh {
namespace {

void require_finite_at_least(double value, double minimum, bool strict, const char* name) {
    const bool ok = std::isfinite(value) && (strict ? value > minimum : value >= minimum);
    SH_REQUIRE(ok, SH_ERR_INVALID_ARGUMENT, "params.%s = %g, must be finite and %s %g", name, value, strict ? ">" : ">=", minimum);
}

}  // namespace

SpringLaw::SpringLaw(const sh_spring_params& p) : params_(p) {
    params_.table = nullptr;
    require_finite_at_least(p.damping, 0.0, false, "damping");
    const int law = enum_value(p.law);
    SH_REQUIRE(law >= SH_SPRING_LINEAR && law <= SH_SPRING_TABLE, SH_ERR_INVALID_ARGUMENT, "params.law = %d is not a sh_spring_law", law);
    switch (p.law) {
        case SH_SPRING_LINEAR:
            require_finite_at_least(p.stiffness, 0.0, true, "stiffness");
            break;
        case SH_SPRING_CUBIC:
            require_finite_at_least(p.lambda1, 0.0, false, "lambda1");
            require_finite_at_least(p.lambda2, 0.0, true, "lambda2");
            break;
        case SH_SPRING_HYPERBOLIC:
            require_finite_at_least(p.a, 0.0, false, "a");
            require_finite_at_least(p.b, 0.0, true, "b");
            break;
        case SH_SPRING_TABLE: {
            require(p.table != nullptr, SH_ERR_INVALID_ARGUMENT, "params.table is NULL");
            SH_REQUIRE(p.table_rows >= 2, SH_ERR_INVALID_ARGUMENT, "params.table_rows = %d, a curve needs at least 2 rows", p.table_rows);
            const size_t n = static_cast<size_t>(p.table_rows);
            strain_.resize(n);
            force_.resize(n);
            for (size_t k = 0; k < n; ++k) {
                strain_[k] = p.table[2 * k];
                force_[k] = p.table[2 * k + 1];
                SH_REQUIRE(std::isfinite(strain_[k]) && std::isfinite(force_[k]), SH_ERR_INVALID_ARGUMENT, "params.table row %zu is not finite", k);
                SH_REQUIRE(k == 0 || strain_[k] > strain_[k - 1], SH_ERR_INVALID_ARGUMENT, "params.table row %zu: strain %g does not increase", k, strain_[k]);
            }
            // Fritsch-Carlson slopes: a monotone data set gives a monotone curve.
            vec<double> secant(n - 1);
            for (size_t k = 0; k + 1 < n; ++k) secant[k] = (force_[k + 1] - force_[k]) / (strain_[k + 1] - strain_[k]);
            slope_.resize(n);
            slope_[0] = secant[0];
            slope_[n - 1] = secant[n - 2];
            for (size_t k = 1; k + 1 < n; ++k)
                slope_[k] = secant[k - 1] * secant[k] <= 0.0 ? 0.0 : 0.5 * (secant[k - 1] + secant[k]);
            for (size_t k = 0; k + 1 < n; ++k) {
                if (secant[k] == 0.0) {
                    slope_[k] = slope_[k + 1] = 0.0;
                    continue;
                }
                const double alpha = slope_[k] / secant[k], beta = slope_[k + 1] / secant[k];
                const double r = alpha * alpha + beta * beta;
                if (r > 9.0) {
                    const double tau = 3.0 / std::sqrt(r);
                    slope_[k] = tau * alpha * secant[k];
                    slope_[k + 1] = tau * beta * secant[k];
                }
            }
            knot_integral_.assign(n, 0.0);
            for (size_t k = 0; k + 1 < n; ++k) {
                // Two-point Gauss-Legendre is exact for the cubic segment.
                const double h = strain_[k + 1] - strain_[k], c = strain_[k] + 0.5 * h, r = 0.5 * h / std::sqrt(3.0);
                knot_integral_[k + 1] = knot_integral_[k] + 0.5 * h * (curve(c - r) + curve(c + r));
            }
            break;
        }
    }
}

double SpringLaw::curve(double s) const {
    const size_t n = strain_.size();
    if (s <= strain_[0]) return force_[0] + slope_[0] * (s - strain_[0]);
    if (s >= strain_[n - 1]) return force_[n - 1] + slope_[n - 1] * (s - strain_[n - 1]);
    const size_t k = static_cast<size_t>(std::upper_bound(strain_.begin(), strain_.end(), s) - strain_.begin()) - 1;
    const double h = strain_[k + 1] - strain_[k], t = (s - strain_[k]) / h, t2 = t * t, t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * force_[k] + (t3 - 2 * t2 + t) * h * slope_[k] + (-2 * t3 + 3 * t2) * force_[k + 1] +
           (t3 - t2) * h * slope_[k + 1];
}

double SpringLaw::curve_slope(double s) const {
    const size_t n = strain_.size();
    if (s <= strain_[0]) return slope_[0];
    if (s >= strain_[n - 1]) return slope_[n - 1];
    const size_t k = static_cast<size_t>(std::upper_bound(strain_.begin(), strain_.end(), s) - strain_.begin()) - 1;
    const double h = strain_[k + 1] - strain_[k], t = (s - strain_[k]) / h, t2 = t * t;
    return ((6 * t2 - 6 * t) * force_[k] + (-6 * t2 + 6 * t) * force_[k + 1]) / h + (3 * t2 - 4 * t + 1) * slope_[k] +
           (3 * t2 - 2 * t) * slope_[k + 1];
}

double SpringLaw::curve_integral(double s) const {
    auto from_first_knot = [&](double u) {
        const size_t n = strain_.size();
        if (u <= strain_[0]) {
            const double d = u - strain_[0];
            return d * (force_[0] + 0.5 * slope_[0] * d);
        }
        if (u >= strain_[n - 1]) {
            const double d = u - strain_[n - 1];
            return knot_integral_[n - 1] + d * (force_[n - 1] + 0.5 * slope_[n - 1] * d);
        }
        const size_t k = static_cast<size_t>(std::upper_bound(strain_.begin(), strain_.end(), u) - strain_.begin()) - 1;
        const double h = u - strain_[k], c = strain_[k] + 0.5 * h, r = 0.5 * h / std::sqrt(3.0);
        return knot_integral_[k] + 0.5 * h * (curve(c - r) + curve(c + r));
    };
    return from_first_knot(s) - from_first_knot(0.0);
}

double SpringLaw::tension(double l, double l0) const {
    const double dx = l - l0, d = dx / l0;
    switch (params_.law) {
        case SH_SPRING_LINEAR: return params_.stiffness * dx;
        case SH_SPRING_CUBIC: return params_.lambda1 * d * d * d + params_.lambda2 * d;
        case SH_SPRING_HYPERBOLIC: return dx / (params_.a * std::fabs(dx) + params_.b);
        case SH_SPRING_TABLE: return curve(d);
    }
    return 0.0;
}

double SpringLaw::stiffness(double l, double l0) const {
    const double dx = l - l0, d = dx / l0;
    switch (params_.law) {
        case SH_SPRING_LINEAR: return params_.stiffness;
        case SH_SPRING_CUBIC: return (3.0 * params_.lambda1 * d * d + params_.lambda2) / l0;
        case SH_SPRING_HYPERBOLIC: {
            const double denominator = params_.a * std::fabs(dx) + params_.b;
            return params_.b / (denominator * denominator);
        }
        case SH_SPRING_TABLE: return curve_slope(d) / l0;
    }
    return 0.0;
}

double SpringLaw::energy(double l, double l0) const {
    const double dx = l - l0, d = dx / l0;
    switch (params_.law) {
        case SH_SPRING_LINEAR: return 0.5 * params_.stiffness * dx * dx;
        case SH_SPRING_CUBIC: return l0 * (0.25 * params_.lambda1 * d * d * d * d + 0.5 * params_.lambda2 * d * d);
        case SH_SPRING_HYPERBOLIC: {
            const double a = params_.a, b = params_.b, u = a * std::fabs(dx) / b;
            if (u < 1e-4) return dx * dx / (2.0 * b) - a * std::fabs(dx) * dx * dx / (3.0 * b * b);
            return std::fabs(dx) / a - b / (a * a) * std::log1p(u);
        }
        case SH_SPRING_TABLE: return l0 * curve_integral(d);
    }
    return 0.0;
}

}  // namespace sh
