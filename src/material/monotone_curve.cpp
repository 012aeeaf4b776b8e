#include "material/monotone_curve.hpp"

#include <algorithm>
#include <cmath>

namespace sh {

void MonotoneCurve::build(const double* table, int32_t count) {
    const size_t n = static_cast<size_t>(count);
    x_.resize(n);
    y_.resize(n);
    for (size_t k = 0; k < n; ++k) {
        x_[k] = table[2 * k];
        y_[k] = table[2 * k + 1];
    }
    // Fritsch-Carlson slopes: a monotone data set gives a monotone curve.
    vec<double> secant(n - 1);
    for (size_t k = 0; k + 1 < n; ++k) secant[k] = (y_[k + 1] - y_[k]) / (x_[k + 1] - x_[k]);
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
        const double h = x_[k + 1] - x_[k], c = x_[k] + 0.5 * h, r = 0.5 * h / std::sqrt(3.0);
        knot_integral_[k + 1] = knot_integral_[k] + 0.5 * h * (value(c - r) + value(c + r));
    }
}

size_t MonotoneCurve::segment(double x) const {
    return static_cast<size_t>(std::upper_bound(x_.begin(), x_.end(), x) - x_.begin()) - 1;
}

double MonotoneCurve::value(double s) const {
    const size_t n = x_.size();
    if (s <= x_[0]) return y_[0] + slope_[0] * (s - x_[0]);
    if (s >= x_[n - 1]) return y_[n - 1] + slope_[n - 1] * (s - x_[n - 1]);
    const size_t k = segment(s);
    const double h = x_[k + 1] - x_[k], t = (s - x_[k]) / h, t2 = t * t, t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * y_[k] + (t3 - 2 * t2 + t) * h * slope_[k] + (-2 * t3 + 3 * t2) * y_[k + 1] +
           (t3 - t2) * h * slope_[k + 1];
}

double MonotoneCurve::slope(double s) const {
    const size_t n = x_.size();
    if (s <= x_[0]) return slope_[0];
    if (s >= x_[n - 1]) return slope_[n - 1];
    const size_t k = segment(s);
    const double h = x_[k + 1] - x_[k], t = (s - x_[k]) / h, t2 = t * t;
    return ((6 * t2 - 6 * t) * y_[k] + (-6 * t2 + 6 * t) * y_[k + 1]) / h + (3 * t2 - 4 * t + 1) * slope_[k] +
           (3 * t2 - 2 * t) * slope_[k + 1];
}

double MonotoneCurve::from_first_knot(double u) const {
    const size_t n = x_.size();
    if (u <= x_[0]) {
        const double d = u - x_[0];
        return d * (y_[0] + 0.5 * slope_[0] * d);
    }
    if (u >= x_[n - 1]) {
        const double d = u - x_[n - 1];
        return knot_integral_[n - 1] + d * (y_[n - 1] + 0.5 * slope_[n - 1] * d);
    }
    const size_t k = segment(u);
    const double h = u - x_[k], c = x_[k] + 0.5 * h, r = 0.5 * h / std::sqrt(3.0);
    return knot_integral_[k] + 0.5 * h * (value(c - r) + value(c + r));
}

double MonotoneCurve::integral(double s) const { return from_first_knot(s) - from_first_knot(0.0); }

}  // namespace sh
