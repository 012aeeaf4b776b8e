// MonotoneCurve: a monotone cubic (Fritsch-Carlson) through tabulated points, linear beyond
// its ends, with its slope and integral (the tabulated spring law's curve).
#pragma once

#include "core/memory.hpp"

#include <cstdint>

namespace sh {

/// A C1 piecewise cubic through (x_k, y_k): monotone wherever the data are.
class MonotoneCurve {
public:
    /// Builds the curve through count >= 2 rows (x, y) of table, x strictly increasing and all
    /// finite (the caller checks them).
    void build(const double* table, int32_t count);

    /// y(x).
    double value(double x) const;

    /// dy/dx at x.
    double slope(double x) const;

    /// The integral of y from 0 to x.
    double integral(double x) const;

private:
    /// The integral of y from the first knot to x.
    double from_first_knot(double x) const;
    /// Index k of the segment [x_k, x_k+1] holding x, for x inside the knots.
    size_t segment(double x) const;

    vec<double> x_, y_, slope_;  ///< knots and Hermite slopes
    vec<double> knot_integral_;  ///< integral of the curve from x_[0] to each knot
};

}  // namespace sh
